import pymavlink.dialects.v20.common as common
import pytest

from mavconform.reference_impl.net import CaptureRecord, DropMessage, FaultModel, SimClock, SimNetwork
from mavconform.reference_impl.wire import FrameEncoder

from .nodes import EchoNode, PingNode, RecorderNode, SenderNode, TimerNode


def pair(a_node, b_node, seed=0, **faults):
    net = SimNetwork(seed=seed)
    net.add_node("a", a_node)
    net.add_node("b", b_node)
    net.connect("a", "b", **faults)
    return net


def test_clean_link_delivers_at_send_time():
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b)
    net.clock.advance_to(3.0)
    a.send(b"hi", "b")
    assert net.run_until_quiet(timeout=1.0)
    assert b.received == [(b"hi", "a", 3.0)]
    assert net.clock.now() == 3.0
    s = net.stats[("a", "b")]
    assert (s.sent, s.delivered, s.dropped) == (1, 1, 0)


def test_delay_keeps_order_and_timing():
    sender, b = SenderNode("b", count=10, interval=0.1), RecorderNode()
    net = pair(sender, b, a_to_b=FaultModel(delay=0.5))
    net.run_for(5.0)
    assert b.payloads == [b"%d" % i for i in range(10)]
    assert [t for _, _, t in b.received] == pytest.approx([0.5 + 0.1 * i for i in range(10)])


def test_jitter_bounds():
    sender, b = SenderNode("b", count=200, interval=0.1), RecorderNode()
    net = pair(sender, b, a_to_b=FaultModel(delay=0.2, jitter=0.05))
    net.run_for(30.0)
    assert len(b.received) == 200
    for data, _, t in b.received:
        sent_at = 0.1 * int(data)
        assert sent_at + 0.2 - 1e-9 <= t <= sent_at + 0.25 + 1e-9


def test_reorder_really_reorders():
    sender, b = SenderNode("b", count=300, interval=0.01), RecorderNode()
    net = pair(sender, b, a_to_b=FaultModel(reorder=0.2, reorder_delay=0.05))
    net.run_for(10.0)
    order = [int(d) for d in b.payloads]
    assert sorted(order) == list(range(300))      # nothing lost
    assert order != list(range(300))              # but overtaken
    assert net.stats[("a", "b")].reordered > 0
    times = [t for _, _, t in b.received]
    assert times == sorted(times)                 # delivered in time order


def lossy_run(seed: int) -> list[CaptureRecord]:
    fault = FaultModel(loss=0.1, duplicate=0.05, reorder=0.1, delay=0.01, jitter=0.02, corrupt=0.02)
    ping, echo = PingNode("b", rounds=50), EchoNode()
    net = pair(ping, echo, seed=seed, a_to_b=fault, b_to_a=fault)
    log: list[CaptureRecord] = []
    net.add_capture(log.append)
    assert net.run_until(lambda: ping.done == 50, timeout=60.0)
    return log


def test_same_seed_identical_capture_different_seed_differs():
    a, b, c = lossy_run(3), lossy_run(3), lossy_run(4)
    assert a == b
    assert a != c
    assert {r.kind for r in a} == {"tx", "rx", "drop"}


def test_run_until_timeout_returns_false_and_clock_at_end():
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b)
    assert net.run_until(lambda: bool(b.received), timeout=2.5) is False
    assert net.clock.now() == 2.5


def test_run_until_returns_when_condition_holds():
    sender, b = SenderNode("b", count=100, interval=1.0), RecorderNode()
    net = pair(sender, b)
    assert net.run_until(lambda: len(b.received) == 3, timeout=1000.0)
    assert net.clock.now() == 2.0
    assert net.run_until(lambda: True, timeout=0.0)


class BusyNode(RecorderNode):
    """A buggy node whose deadline never moves forward."""

    def next_deadline(self):
        return 0.0


def test_run_until_respects_max_steps():
    net = SimNetwork()
    busy = BusyNode()
    net.add_node("busy", busy)
    assert net.run_until(lambda: False, timeout=10.0, max_steps=100) is False
    assert net.steps == 100
    assert net.clock.now() == 0.0


def test_in_flight_and_run_until_quiet():
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b, a_to_b=FaultModel(delay=1.0))
    a.send(b"x", "b")
    a.send(b"y", "b")
    net.run_for(0.5)
    assert net.in_flight() == 2
    assert net.run_until_quiet(timeout=0.2) is False
    assert net.clock.now() == pytest.approx(0.7)
    assert net.run_until_quiet(timeout=10.0)
    assert net.in_flight() == 0
    assert net.clock.now() == 1.0
    assert b.payloads == [b"x", b"y"]


def test_node_deadlines_are_honoured():
    net = SimNetwork()
    timer = TimerNode([0.5, 1.25, 3.0])
    net.add_node("t", timer)
    net.run_for(2.0)
    assert timer.polls == [0.5, 1.25]
    assert net.clock.now() == 2.0
    net.run_for(2.0)
    assert timer.polls == [0.5, 1.25, 3.0]


def test_past_deadline_polled_at_current_time():
    net = SimNetwork(clock=SimClock(start=5.0))
    timer = TimerNode([1.0])
    net.add_node("t", timer)
    net.run_for(1.0)
    assert timer.polls == [5.0]


def test_no_route_is_dropped_and_captured():
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b)
    log: list[CaptureRecord] = []
    net.add_capture(log.append)
    a.send(b"lost", "nowhere")
    net.run_for(1.0)
    assert [(r.kind, r.src, r.dst, r.data) for r in log] == [
        ("tx", "a", "nowhere", b"lost"), ("drop", "a", "nowhere", b"lost")]
    assert net.stats[("a", "nowhere")].dropped == 1


def test_fault_drop_and_duplicate_are_captured():
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b, a_to_b=FaultModel(duplicate=1.0), b_to_a=FaultModel(loss=1.0))
    log: list[CaptureRecord] = []
    net.add_capture(log.append)
    a.send(b"twice", "b")
    b.send(b"never", "a")
    net.run_until_quiet(timeout=1.0)
    kinds = [(r.kind, r.data) for r in log]
    assert kinds.count(("rx", b"twice")) == 2
    assert ("drop", b"never") in kinds
    assert b.payloads == [b"twice", b"twice"] and a.received == []
    assert net.stats[("a", "b")].duplicated == 1
    assert net.stats[("b", "a")].dropped == 1


def test_ping_pong_completes_under_loss():
    ping, echo = PingNode("b", rounds=100), EchoNode()
    net = pair(ping, echo, a_to_b=FaultModel(loss=0.1), b_to_a=FaultModel(loss=0.1))
    assert net.run_until(lambda: ping.done == 100, timeout=1000.0)
    assert ping.sends > 100


def test_shared_fault_model_gets_separate_rule_counters():
    enc = FrameEncoder(1, 1, dialect=common)
    ack = enc.encode(common.MAVLink_mission_ack_message(1, 1, 0, 0))
    fault = FaultModel(rules=(DropMessage("MISSION_ACK", nth=1),), dialect=common)
    a, b = RecorderNode(), RecorderNode()
    net = pair(a, b, a_to_b=fault, b_to_a=fault)
    a.send(ack, "b")
    b.send(ack, "a")
    net.run_until_quiet(timeout=1.0)
    assert a.received == [] and b.received == []   # each direction dropped its own 1st ACK


def test_wiring_errors():
    net = SimNetwork()
    net.add_node("a", RecorderNode())
    with pytest.raises(ValueError):
        net.add_node("a", RecorderNode())
    with pytest.raises(ValueError):
        net.connect("a", "missing")
    with pytest.raises(ValueError):
        net.connect("a", "a")
    with pytest.raises(ValueError):
        net.run_until(lambda: False, timeout=-1.0)
