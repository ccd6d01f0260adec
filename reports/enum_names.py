"""Enum names for field values ("command=16" -> "MAV_CMD_NAV_WAYPOINT"), from the dialect.

A report that says `result=15` makes the reader look the number up; one that says
`type=15 (MAV_MISSION_OPERATION_CANCELLED)` does not. The names come from the generated
dialect's metadata (`enums`, and each message class's `fieldenums_by_name`), never from a
hand list, so they follow the XML. Our dialect carries only the values the suite uses, so a
value it lacks (a MAV_CMD a vehicle sends on its own) is looked up in pymavlink's `common`
dialect under the same enum name.
"""

from __future__ import annotations

from functools import lru_cache
from types import ModuleType
from typing import Any

from mavconform.reference_impl.wire.dialect import mavlink as _ours

_END = "_ENUM_END"   # mavgen's sentinel entry: one past the last value, not a value


def _dialects() -> tuple[ModuleType, ...]:
    try:
        from pymavlink.dialects.v20 import common
    except ImportError:   # pragma: no cover - pymavlink is a dependency; names are a nicety
        return (_ours,)
    return (_ours, common)


@lru_cache(maxsize=None)
def _message_classes() -> dict[str, type]:
    """Message name -> generated class, ours first (it is the superset for mission traffic)."""
    classes: dict[str, type] = {}
    for dialect in reversed(_dialects()):
        classes.update({cls.msgname: cls for cls in dialect.mavlink_map.values()})
    return classes


def field_order(msg: str) -> list[str]:
    """The message's fields in definition order ([] for a message no dialect knows)."""
    cls = _message_classes().get(msg)
    return list(getattr(cls, "fieldnames", [])) if cls is not None else []


def field_enum(msg: str, field: str) -> str | None:
    """The enum `field` of message `msg` takes its values from ("MAV_CMD"), or None."""
    cls = _message_classes().get(msg)
    return getattr(cls, "fieldenums_by_name", {}).get(field) if cls is not None else None


@lru_cache(maxsize=None)
def _entries(enum: str) -> dict[int, str]:
    """value -> name over the dialects (ours wins), without the ENUM_END sentinel."""
    names: dict[int, str] = {}
    for dialect in reversed(_dialects()):
        for value, entry in dialect.enums.get(enum, {}).items():
            if not entry.name.endswith(_END):
                names[value] = entry.name
    return names


def enum_value_name(enum: str, value: Any) -> str | None:
    """The name of `value` in `enum`: "MAV_FRAME_GLOBAL_RELATIVE_ALT"; flags of a bitmask
    joined with "|"; "not a MAV_FRAME" for an integer the enum lacks; None for a non-integer
    (a NaN string, a float) or an enum no dialect knows."""
    if not isinstance(value, int) or isinstance(value, bool):
        return None
    entries = _entries(enum)
    if not entries:
        return None
    if value in entries:
        return entries[value]
    flags = [v for v in entries if v > 0]
    if value > 0 and flags and all(v & (v - 1) == 0 for v in flags):   # a bitmask enum
        set_bits = [entries[v] for v in sorted(flags) if value & v]
        if sum(v for v in flags if value & v) == value:
            return "|".join(set_bits)
    return f"not a {enum}"


def field_value_name(msg: str, field: str, value: Any) -> str | None:
    """The enum name of `msg.field == value` ("MAV_CMD_NAV_WAYPOINT"), or None."""
    enum = field_enum(msg, field)
    return enum_value_name(enum, value) if enum is not None else None
