"""GuardedNode: a node that raises falls silent and keeps the exception; the driver goes on."""

from __future__ import annotations

from mavconform.reference_impl.net.guard import GuardedNode
from mavconform.reference_impl.net.sim import SimNetwork


class _Bomb:
    def __init__(self) -> None:
        self.polls = 0
        self.out: list = []

    def datagram_received(self, data, source, now):
        if data == b"boom":
            raise ZeroDivisionError("boom")
        self.out.append((b"echo:" + data, source))

    def poll(self, now):
        self.polls += 1

    def next_deadline(self):
        return None

    def take_outgoing(self):
        out, self.out = self.out, []
        return out


class _Sink:
    def __init__(self) -> None:
        self.got: list[bytes] = []
        self.out: list = []

    def datagram_received(self, data, source, now):
        self.got.append(data)

    def poll(self, now):
        pass

    def next_deadline(self):
        return None

    def take_outgoing(self):
        out, self.out = self.out, []
        return out


def test_a_raising_node_stops_and_the_network_runs_on() -> None:
    net = SimNetwork(seed=1)
    guard, sink = GuardedNode(_Bomb()), _Sink()
    net.add_node("bomb", guard)
    net.add_node("sink", sink)
    net.connect("bomb", "sink")
    sink.out.append((b"hello", "bomb"))
    net.run_for(1.0)
    assert sink.got == [b"echo:hello"] and guard.crash is None
    sink.out += [(b"boom", "bomb"), (b"again", "bomb")]
    net.run_for(1.0)
    assert guard.crash is not None and guard.crash.startswith("ZeroDivisionError: boom (")
    assert sink.got == [b"echo:hello"]          # silent after the crash
    assert guard.next_deadline() is None
