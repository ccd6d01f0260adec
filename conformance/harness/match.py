"""Predicates over received frames that can say what they wait for.

`expect(msg("MISSION_REQUEST_INT", seq=0))` fails with "expected MISSION_REQUEST_INT
{seq=0}", so every verdict reads without the check's source. A field condition is a value
(equality), a set/tuple/frozenset (membership) or a callable (any test).
"""

from __future__ import annotations

from typing import Any, Callable, Iterable

from mavconform.reference_impl.wire.frame import Frame

REQUESTS = ("MISSION_REQUEST_INT", "MISSION_REQUEST")
ITEMS = ("MISSION_ITEM_INT", "MISSION_ITEM")


class Match:
    __slots__ = ("names", "fields", "test", "label")

    def __init__(self, names: str | Iterable[str] | None, fields: dict[str, Any],
                 test: Callable[[Frame], bool] | None = None, label: str | None = None) -> None:
        if isinstance(names, str):
            names = (names,)
        self.names = frozenset(names) if names is not None else None
        self.fields = fields
        self.test = test
        self.label = label

    def __call__(self, frame: Frame) -> bool:
        if self.names is not None and frame.msg._type not in self.names:
            return False
        msg = frame.msg
        for name, want in self.fields.items():
            have = getattr(msg, name, None)
            if callable(want):
                if not want(have):
                    return False
            elif isinstance(want, (set, frozenset, tuple)):
                if have not in want:
                    return False
            elif have != want:
                return False
        return self.test is None or self.test(frame)

    def __or__(self, other: "Match") -> "Match":
        return Match(None, {}, lambda f: self(f) or other(f), f"{self} or {other}")

    def __str__(self) -> str:
        if self.label:
            return self.label
        name = "/".join(sorted(self.names)) if self.names else "any message"
        if not self.fields:
            return name
        parts = ", ".join(f"{k}={_show(v)}" for k, v in self.fields.items())
        return f"{name}{{{parts}}}"


def msg(names: str | Iterable[str] | None, *, label: str | None = None,
        where: Callable[[Frame], bool] | None = None, **fields: Any) -> Match:
    """Frames named `names` (one or several) whose fields satisfy `fields`."""
    return Match(names, fields, where, label)


def request(seq: int | None = None, **fields: Any) -> Match:
    """A request for an item, in either form (MISSION_REQUEST_INT or MISSION_REQUEST)."""
    if seq is not None:
        fields["seq"] = seq
    return Match(REQUESTS, fields)


def item(seq: int | None = None, **fields: Any) -> Match:
    if seq is not None:
        fields["seq"] = seq
    return Match(ITEMS, fields)


def ack(**fields: Any) -> Match:
    return Match("MISSION_ACK", fields)


def _show(value: Any) -> str:
    if callable(value):
        return getattr(value, "__doc__", None) or getattr(value, "__name__", "?")
    if isinstance(value, (set, frozenset, tuple)):
        return "{" + "|".join(str(v) for v in sorted(value, key=str)) + "}"
    return str(value)


def not_equal(value: Any) -> Callable[[Any], bool]:
    def test(have: Any) -> bool:
        return have != value
    test.__doc__ = f"!={value}"
    return test
