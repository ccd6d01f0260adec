"""Our sockets' receive queues: a generous buffer, and the kernel's drops counted (Linux
SO_RXQ_OVFL) or said to be unknown, never a pretended 0."""

from __future__ import annotations

import socket
import struct
import sys
from pathlib import Path

import pytest

from mavconform.reference_impl.net import SimNetwork, UdpDriver
from mavconform.reference_impl.net import receive_queue as rq

from .nodes import EchoNode, RecorderNode, SenderNode

pytestmark = pytest.mark.udp
linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="SO_RXQ_OVFL is Linux's")
FLOOD = 300


def _rmem_max() -> int | None:
    try:
        return int(Path("/proc/sys/net/core/rmem_max").read_text())
    except (OSError, ValueError):
        return None


@linux_only
def test_a_socket_asks_for_a_generous_buffer_and_says_what_it_got():
    with UdpDriver() as drv:
        node = RecorderNode()
        drv.add_node(node)
        queue = drv.receive_queue(node)
        cap = _rmem_max()
        if cap is not None:   # Linux grants twice what it is asked, up to twice rmem_max
            assert queue.granted == 2 * min(rq.RECEIVE_BUFFER, cap)
        assert queue.granted > 0 and queue.drops == 0


@linux_only
def test_a_flood_past_a_tiny_buffer_is_counted_datagram_for_datagram():
    with UdpDriver() as drv:
        receiver = RecorderNode()
        where = drv.add_node(receiver)
        assert drv.resize_receive_buffer(receiver, 1) < 8192   # the kernel's minimum: a few datagrams
        flood = SenderNode(where, count=FLOOD, interval=0.0)   # all in one flush, before any read
        drv.add_node(flood)
        queue = drv.receive_queue(receiver)
        assert drv.run_until(lambda: flood.sent == FLOOD and receiver.received, timeout=5.0)
        drv.run_until(lambda: False, timeout=0.0)   # read what the queue kept
        kept = len(receiver.received)
        assert kept < FLOOD
        # the count comes with the next datagram queued after the drops
        later = RecorderNode()
        drv.add_node(later)
        later.send(b"after the flood", where)
        assert drv.run_until(lambda: queue.drops + len(receiver.received) == FLOOD + 1, timeout=5.0), \
            (queue.drops, len(receiver.received))
        assert queue.drops == FLOOD - kept > 0   # loopback loses nothing else


def test_drops_are_unknown_where_the_platform_cannot_count_them(monkeypatch):
    monkeypatch.setattr(rq, "SO_RXQ_OVFL", None)   # as on macOS or Windows
    with UdpDriver() as drv:
        echo = EchoNode()
        echo_at = drv.add_node(echo)
        sender = SenderNode(echo_at, count=3, interval=0.0)
        drv.add_node(sender)
        assert drv.run_until(lambda: len(sender.received) == 3, timeout=5.0)   # read without it
        assert drv.receive_queue(echo).drops is None
        assert drv.receive_queue(sender).drops is None
        assert not drv.receive_queue(echo).counted


class _Refusing:
    """A socket whose kernel refuses every option (and cannot say its buffer)."""

    def setsockopt(self, *args):
        raise OSError(92, "Protocol not available")

    def getsockopt(self, *args):
        raise OSError(92, "Protocol not available")


def test_a_refused_option_leaves_the_drops_unknown_not_zero():
    queue = rq.open_queue(_Refusing())   # type: ignore[arg-type]
    assert queue.drops is None and queue.granted is None
    assert rq.total_drops([rq.ReceiveQueue(100, True), queue]) is None


@pytest.mark.skipif(rq.SO_RXQ_OVFL is None, reason="no SO_RXQ_OVFL here")
def test_the_counter_is_cumulative_and_wraps_at_32_bits():
    queue = rq.ReceiveQueue(4096, counted=True)
    counter = (socket.SOL_SOCKET, rq.SO_RXQ_OVFL)
    queue.note([(*counter, struct.pack("=I", 5))])
    queue.note([(*counter, struct.pack("=I", 5))])   # no new drops: the same total
    assert queue.drops == 5
    queue.note([(*counter, struct.pack("=I", 2**32 - 1))])
    queue.note([(*counter, struct.pack("=I", 3))])   # wrapped: 4 more
    assert queue.drops == 2**32 - 1 + 4
    queue.note([(socket.SOL_SOCKET, rq.SO_RXQ_OVFL + 1, struct.pack("=I", 999))])   # another option
    assert queue.drops == 2**32 + 3
    assert rq.total_drops([queue, rq.ReceiveQueue(None, True)]) == 2**32 + 3


def test_virtual_time_has_no_queue_to_overflow():
    net = SimNetwork()
    node = RecorderNode()
    net.add_node("a", node)
    assert net.receive_queue(node).drops == 0
