"""Small DatagramNodes for driver tests: they record what they see and send on cue; and a
clock that jumps, for a host that stalls."""

from __future__ import annotations

from typing import Hashable

from mavconform.reference_impl.net.clock import ScaledClock

Address = Hashable


class RecorderNode:
    """Records every datagram; sends what `send()` queued. No timers."""

    def __init__(self) -> None:
        self.received: list[tuple[bytes, Address, float]] = []
        self._out: list[tuple[bytes, Address]] = []

    def send(self, data: bytes, dst: Address) -> None:
        self._out.append((data, dst))

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        self.received.append((data, source, now))

    def poll(self, now: float) -> None:
        pass

    def next_deadline(self) -> float | None:
        return None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out, self._out = self._out, []
        return out

    @property
    def payloads(self) -> list[bytes]:
        return [d for d, _, _ in self.received]


class EchoNode(RecorderNode):
    """Sends every datagram straight back to where it came from."""

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        super().datagram_received(data, source, now)
        self._out.append((data, source))


class SenderNode(RecorderNode):
    """Sends `count` numbered datagrams to `peer`, one every `interval` seconds from `start`."""

    def __init__(self, peer: Address, count: int, interval: float, start: float = 0.0) -> None:
        super().__init__()
        self.peer, self.count, self.interval = peer, count, interval
        self.sent = 0
        self._next: float | None = start if count else None
        self.polls: list[float] = []

    def poll(self, now: float) -> None:
        self.polls.append(now)
        while self._next is not None and self._next <= now:
            self._out.append((b"%d" % self.sent, self.peer))
            self.sent += 1
            self._next = (self._next + self.interval) if self.sent < self.count else None

    def next_deadline(self) -> float | None:
        return self._next


class TimerNode(RecorderNode):
    """Asks to be polled at fixed times; records when it was polled."""

    def __init__(self, deadlines: list[float]) -> None:
        super().__init__()
        self.pending = sorted(deadlines)
        self.polls: list[float] = []

    def poll(self, now: float) -> None:
        self.polls.append(now)
        self.pending = [d for d in self.pending if d > now]

    def next_deadline(self) -> float | None:
        return self.pending[0] if self.pending else None


class PingNode(RecorderNode):
    """Stop-and-wait: sends ping i, resends after `retry` seconds, moves on at pong i."""

    def __init__(self, peer: Address, rounds: int, retry: float = 0.1) -> None:
        super().__init__()
        self.peer, self.rounds, self.retry = peer, rounds, retry
        self.done = 0
        self.sends = 0
        self._deadline: float | None = 0.0 if rounds else None

    def _ping(self, now: float) -> None:
        self._out.append((b"%d" % self.done, self.peer))
        self.sends += 1
        self._deadline = now + self.retry

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        if data == b"%d" % self.done:
            self.done += 1
            if self.done < self.rounds:
                self._ping(now)
            else:
                self._deadline = None

    def poll(self, now: float) -> None:
        if self._deadline is not None and self._deadline <= now:
            self._ping(now)

    def next_deadline(self) -> float | None:
        return self._deadline


class JumpingClock(ScaledClock):
    """A ScaledClock that `stall(seconds)` moves on at once: how a process that was not run
    for that long finds the clock when it runs again (a busy host), without a sleep."""

    __slots__ = ("offset",)

    def __init__(self, speed: float = 1.0) -> None:
        super().__init__(speed)
        self.offset = 0.0

    def now(self) -> float:
        return super().now() + self.offset

    def wall(self) -> float:
        return super().wall() + self.offset

    def stall(self, seconds: float) -> None:
        self.offset += seconds
