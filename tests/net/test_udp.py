import socket

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import CaptureRecord, FaultModel, MonotonicClock, UdpDriver

from .nodes import EchoNode, RecorderNode, SenderNode, TimerNode

pytestmark = pytest.mark.udp
LOCAL = "127.0.0.1"


def test_echo_over_loopback():
    with UdpDriver() as drv:
        echo = EchoNode()
        echo_addr = drv.add_node(echo)
        assert echo_addr[0] == LOCAL and echo_addr[1] > 0
        sender = SenderNode(echo_addr, count=5, interval=0.0)
        sender_addr = drv.add_node(sender)
        log: list[CaptureRecord] = []
        drv.add_capture(log.append)
        assert drv.run_until(lambda: len(sender.received) == 5, timeout=5.0)
        assert sorted(sender.payloads) == [b"%d" % i for i in range(5)]
        assert {src for _, src, _ in echo.received} == {sender_addr}
        assert {src for _, src, _ in sender.received} == {echo_addr}
        assert {r.kind for r in log} == {"tx", "rx"}
        assert drv.stats[(sender_addr, echo_addr)].delivered == 5


def test_outgoing_loss_drops_everything():
    with UdpDriver() as drv:
        echo = EchoNode()
        echo_addr = drv.add_node(echo)
        sender = SenderNode(echo_addr, count=5, interval=0.0)
        sender_addr = drv.add_node(sender, outgoing=FaultModel(loss=1.0))
        assert drv.run_until(lambda: bool(echo.received), timeout=0.2) is False
        assert echo.received == []
        assert drv.stats[(sender_addr, echo_addr)].dropped == 5


def test_incoming_delay_uses_timers():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as drv:
        rec = RecorderNode()
        rec_addr = drv.add_node(rec, incoming=FaultModel(delay=0.05))
        sender = RecorderNode()
        drv.add_node(sender)
        start = clock.now()
        sender.send(b"late", rec_addr)
        assert drv.run_until(lambda: bool(rec.received), timeout=2.0)
        assert rec.received[0][2] - start >= 0.05


def test_silent_peer_times_out():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as drv:
        rec = RecorderNode()
        drv.add_node(rec)
        start = clock.now()
        assert drv.run_until(lambda: bool(rec.received), timeout=0.2) is False
        elapsed = clock.now() - start
        assert 0.2 <= elapsed < 1.0


def test_a_scaled_clock_waits_its_own_seconds_in_less_real_time():
    """A faster clock's timeout is in its seconds: the driver sleeps 1/speed of it for real."""
    from mavconform.reference_impl.net.clock import ScaledClock
    clock = ScaledClock(8.0)
    with UdpDriver(clock=clock) as drv:
        rec = RecorderNode()
        drv.add_node(rec)
        waits: list[float] = []
        select = drv._selector.select
        drv._selector.select = lambda timeout=None: (waits.append(timeout), select(timeout))[1]
        start = clock.now()
        assert drv.run_until(lambda: bool(rec.received), timeout=0.8) is False
        assert clock.now() - start >= 0.8
        assert waits and max(waits) <= 0.1 + 1e-9


def test_wakes_for_node_deadline():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as drv:
        due = clock.now() + 0.05
        timer = TimerNode([due])
        drv.add_node(timer)
        assert drv.run_until(lambda: bool(timer.polls), timeout=5.0)
        assert due <= timer.polls[0] < due + 1.0


def test_send_to_closed_port_does_not_raise():
    probe = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    probe.bind((LOCAL, 0))
    closed = probe.getsockname()
    probe.close()
    with UdpDriver() as drv:
        node = RecorderNode()
        drv.add_node(node)
        for i in range(3):
            node.send(b"anyone?", closed)
            drv.run_for(0.05)
        assert node.received == []


def test_bind_failure_is_usage_error():
    with UdpDriver() as drv:
        addr = drv.add_node(RecorderNode())
        with pytest.raises(UsageError, match=f"{addr[0]}:{addr[1]}"):
            drv.add_node(RecorderNode(), bind=addr)


def test_closed_driver_refuses_to_run():
    drv = UdpDriver()
    drv.add_node(RecorderNode())
    drv.close()
    drv.close()
    with pytest.raises(ValueError):
        drv.run_for(0.01)
