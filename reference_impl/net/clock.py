"""Injected time: the only way protocol code learns what time it is.

Engines and nodes never call `time.*` themselves; a driver hands them `now`. Two clocks
exist: `SimClock`, virtual time moved only by `SimNetwork` (so a 7.5 s retry sequence costs
microseconds and replays exactly), and `MonotonicClock`, real time for the UDP driver.
`ScaledClock` is real time run faster: when both ends of a real socket are ours (an
in-process vehicle), they can agree to live `speed` seconds in every real one.
`wall()` exists because MAVLink 2 signing timestamps are Unix time; under `SimClock` it is
a fixed epoch plus virtual time, so signed traffic is deterministic too.
"""

from __future__ import annotations

import math
import time
from typing import Protocol

DEFAULT_WALL_EPOCH = 1767225600.0  # 2026-01-01T00:00:00Z


class Clock(Protocol):
    def now(self) -> float:
        """Monotonic seconds; only differences are meaningful."""

    def wall(self) -> float:
        """Unix seconds, for MAVLink signing timestamps."""


class SimClock:
    """Virtual time. Moves only when told to, and never backwards."""

    __slots__ = ("_now", "wall_epoch")

    def __init__(self, start: float = 0.0, wall_epoch: float = DEFAULT_WALL_EPOCH) -> None:
        if not math.isfinite(start):
            raise ValueError(f"SimClock start must be finite, got {start!r}")
        self._now = float(start)
        self.wall_epoch = float(wall_epoch)

    def now(self) -> float:
        return self._now

    def wall(self) -> float:
        return self.wall_epoch + self._now

    def advance_to(self, t: float) -> None:
        """Jump to `t`. Going backwards is a harness bug, so it raises."""
        if t < self._now:
            raise ValueError(f"SimClock cannot go backwards: now {self._now}, asked for {t}")
        if not math.isfinite(t):
            raise ValueError(f"SimClock time must be finite, got {t!r}")
        self._now = float(t)

    def advance(self, dt: float) -> None:
        if dt < 0:
            raise ValueError(f"SimClock cannot advance by a negative amount ({dt})")
        self.advance_to(self._now + dt)

    def __repr__(self) -> str:
        return f"SimClock(now={self._now})"


class MonotonicClock:
    """Real time: `time.monotonic()` for deadlines, `time.time()` for signing."""

    __slots__ = ()
    speed = 1.0   # clock seconds per real second: what a driver divides a real wait by

    def now(self) -> float:
        return time.monotonic()

    def wall(self) -> float:
        return time.time()


class ScaledClock:
    """Real time `speed` times faster, from the moment it is made: `now()` and `wall()` both
    move `speed` clock seconds per real second (signing timestamps stay in step with the
    deadlines). Only for runs where every node reading it is ours: an external target lives
    in real time."""

    __slots__ = ("speed", "_origin", "_wall_origin")

    def __init__(self, speed: float) -> None:
        if not (math.isfinite(speed) and speed > 0.0):
            raise ValueError(f"ScaledClock speed must be a finite number > 0, got {speed!r}")
        self.speed = float(speed)
        self._origin = time.monotonic()
        self._wall_origin = time.time()

    def now(self) -> float:
        return self._origin + (time.monotonic() - self._origin) * self.speed

    def wall(self) -> float:
        return self._wall_origin + (time.monotonic() - self._origin) * self.speed

    def __repr__(self) -> str:
        return f"ScaledClock(speed={self.speed:g})"
