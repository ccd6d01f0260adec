"""Link faults: what a bad radio link does to datagrams, as a deterministic schedule.

A `FaultModel` sits on one direction of a link. Given a datagram, the time and the link's
own `random.Random`, it says which copies to deliver and after what delay; the driver
(SimNetwork or the UDP driver) does the delivering. It never looks at a clock or a global
RNG, so the same seed gives the same faults under either driver.

Order of decisions (each only draws from the RNG if that fault is configured, so adding
e.g. a partition does not shift the random sequence of an otherwise equal model):
  scripted rules -> partitions -> loss -> corruption -> delay+jitter -> reorder -> duplicate.
Rules run first so that "the 2nd MISSION_REQUEST_INT" means the 2nd one the node *sent*,
whatever chance did to the first.
"""

from __future__ import annotations

import dataclasses
import math
import random
import re
from dataclasses import dataclass, field
from typing import Any, Callable

from ..errors import UsageError


@dataclass(slots=True)
class LinkStats:
    """Counters for one direction of a link. Drivers count sent/delivered; schedule the rest."""

    sent: int = 0
    delivered: int = 0
    dropped: int = 0
    duplicated: int = 0
    corrupted: int = 0
    reordered: int = 0
    errors: int = 0  # socket errors on send (UDP only)


class MessageRule:
    """A scripted drop decision on decoded messages. Holds counters: one direction only."""

    def observe(self, msg: Any) -> bool:
        """Count `msg` (a pymavlink message) and say whether its datagram must be dropped."""
        raise NotImplementedError

    def fresh(self) -> "MessageRule":
        """The same rule with its counters reset (for the other direction of a link)."""
        raise NotImplementedError


@dataclass(eq=False)
class DropMessage(MessageRule):
    """Drop messages called `name`: all of them, only the `nth`, or the `nth` onwards."""

    name: str
    nth: int | None = None
    onwards: bool = False
    seen: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("DropMessage needs a message name")
        if self.nth is not None and self.nth < 1:
            raise ValueError(f"DropMessage occurrence counts from 1, got nth={self.nth}")
        if self.onwards and self.nth is None:
            raise ValueError("DropMessage(onwards=True) needs nth")

    def observe(self, msg: Any) -> bool:
        if msg.get_type() != self.name:
            return False
        self.seen += 1
        nth = self.nth
        return nth is None or self.seen == nth or (self.onwards and self.seen > nth)

    def fresh(self) -> "DropMessage":
        return DropMessage(self.name, self.nth, self.onwards)

    def __str__(self) -> str:
        if self.nth is None:
            return self.name
        return f"{self.name}#{self.nth}{'+' if self.onwards else ''}"


@dataclass(eq=False)
class DropWhere(MessageRule):
    """Drop messages for which `predicate(msg)` holds, at most `limit` of them."""

    predicate: Callable[[Any], bool]
    limit: int | None = None
    dropped: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        if self.limit is not None and self.limit < 0:
            raise ValueError(f"DropWhere limit must be >= 0, got {self.limit}")

    def observe(self, msg: Any) -> bool:
        if self.limit is not None and self.dropped >= self.limit:
            return False
        if not self.predicate(msg):
            return False
        self.dropped += 1
        return True

    def fresh(self) -> "DropWhere":
        return DropWhere(self.predicate, self.limit)


_PROBABILITIES = ("loss", "duplicate", "reorder", "corrupt")
_DURATIONS = ("reorder_delay", "delay", "jitter")


@dataclass
class FaultModel:
    """Faults on one direction of a link. Rules keep counters: use `copy()` for the other."""

    loss: float = 0.0           # P(drop)
    duplicate: float = 0.0      # P(an extra copy)
    reorder: float = 0.0        # P(held back by reorder_delay, so later datagrams overtake it)
    reorder_delay: float = 0.05
    delay: float = 0.0          # base one-way latency, seconds
    jitter: float = 0.0         # + uniform(0, jitter)
    corrupt: float = 0.0        # P(flip 1..3 random bytes)
    partitions: tuple[tuple[float, float], ...] = ()   # [start, end): everything dropped
    rules: tuple[MessageRule, ...] = ()
    dialect: Any = field(default=None, repr=False, compare=False)  # for rules; None = project's
    _decoder: Any = field(default=None, init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in _PROBABILITIES:
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:  # also rejects NaN
                raise ValueError(f"FaultModel.{name} is a probability in [0, 1], got {value!r}")
        for name in _DURATIONS:
            value = getattr(self, name)
            if not (value >= 0.0 and math.isfinite(value)):
                raise ValueError(f"FaultModel.{name} is a time >= 0 seconds, got {value!r}")
        windows = []
        for window in self.partitions:
            try:
                start, end = (float(x) for x in window)
            except (TypeError, ValueError):
                raise ValueError(f"FaultModel partition {window!r} is not a (start, end) pair") from None
            if not (0.0 <= start <= end) or math.isnan(end):
                raise ValueError(f"FaultModel partition {window!r} needs 0 <= start <= end")
            windows.append((start, end))
        self.partitions = tuple(windows)
        self.rules = tuple(self.rules)
        for rule in self.rules:
            if not isinstance(rule, MessageRule):
                raise ValueError(f"FaultModel rule {rule!r} is not a MessageRule")

    @property
    def is_clean(self) -> bool:
        """True when `schedule` always returns [(0.0, data)]: drivers may skip it."""
        return not (self.loss or self.duplicate or self.reorder or self.corrupt or self.delay
                    or self.jitter or self.partitions or self.rules)

    def copy(self) -> "FaultModel":
        """An equal model with fresh rule counters, for the other direction of a link."""
        return dataclasses.replace(self, rules=tuple(r.fresh() for r in self.rules))

    def schedule(
        self, data: bytes, now: float, rng: random.Random, stats: LinkStats | None = None
    ) -> list[tuple[float, bytes]]:
        """(delay_seconds, bytes) per copy to deliver; [] means dropped. Counts into `stats`."""
        if stats is None:
            stats = LinkStats()
        if self.rules and self._ruled_out(data):
            stats.dropped += 1
            return []
        for start, end in self.partitions:
            if start <= now < end:
                stats.dropped += 1
                return []
        if self.loss and rng.random() < self.loss:
            stats.dropped += 1
            return []
        if self.corrupt and data and rng.random() < self.corrupt:
            data = _corrupt(data, rng)
            stats.corrupted += 1
        jitter = self.jitter
        t = self.delay + rng.uniform(0.0, jitter) if jitter else self.delay
        if self.reorder and rng.random() < self.reorder:
            t += self.reorder_delay
            stats.reordered += 1
        if self.duplicate and rng.random() < self.duplicate:
            stats.duplicated += 1
            t2 = self.delay + rng.uniform(0.0, jitter) if jitter else self.delay
            return [(t, data), (t2, data)]
        return [(t, data)]

    def _ruled_out(self, data: bytes) -> bool:
        """Whether any frame in the datagram matches a rule. Every rule sees every frame,
        so counters stay true whichever rule fires first."""
        decoder = self._decoder
        if decoder is None:
            from ..wire.codec import FrameDecoder

            decoder = self._decoder = FrameDecoder(dialect=self.dialect)
        drop = False
        for item in decoder.feed(data):
            msg = getattr(item, "msg", None)
            if msg is None:
                continue
            for rule in self.rules:
                if rule.observe(msg):
                    drop = True
        return drop


def _corrupt(data: bytes, rng: random.Random) -> bytes:
    """Flip 1..3 distinct bytes, each by a non-zero XOR, so the datagram surely changes."""
    buf = bytearray(data)
    for pos in rng.sample(range(len(buf)), rng.randint(1, min(3, len(buf)))):
        buf[pos] ^= rng.randint(1, 255)
    return bytes(buf)


_RULE_RE = re.compile(r"([A-Za-z][A-Za-z0-9_]*)(?:#(\d+)(\+)?)?")
_NAMES: dict[int, frozenset[str]] = {}


def _message_names(dialect: Any) -> frozenset[str]:
    names = _NAMES.get(id(dialect))
    if names is None:
        names = _NAMES[id(dialect)] = frozenset(
            cls.msgname for cls in dialect.mavlink_map.values())
    return names


def parse_drop_rule(text: str, dialect: Any = None) -> DropMessage:
    """'MISSION_ACK' (every one), 'MISSION_REQUEST_INT#2' (the 2nd), 'MISSION_ITEM_INT#3+'
    (the 3rd and later). A bad rule is a user mistake: one-line UsageError naming it."""
    m = _RULE_RE.fullmatch(text.strip())
    if m is None:
        raise UsageError(f"bad drop rule {text!r}: expected NAME, NAME#N or NAME#N+ "
                         f"(e.g. MISSION_REQUEST_INT#2)")
    name, nth_text, plus = m.group(1).upper(), m.group(2), m.group(3)
    nth = int(nth_text) if nth_text is not None else None
    if nth is not None and nth < 1:
        raise UsageError(f"bad drop rule {text!r}: occurrences count from 1, got #{nth}")
    if dialect is None:
        from ..wire.codec import default_dialect

        dialect = default_dialect()
    if name not in _message_names(dialect):
        raise UsageError(f"bad drop rule {text!r}: no message named {name} in the dialect")
    return DropMessage(name, nth, onwards=bool(plus))
