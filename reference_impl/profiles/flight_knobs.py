"""Parsers of the vehicle-model knobs (issue 23): flight modes, arming, starting, take-off,
landing, parameters, speed. Each turns a TOML value into what `FlightRules` or `VehicleConfig`
holds, or raises `ValueError` saying what was expected; knobs.py names the knobs."""

from __future__ import annotations

import math
from typing import Any, Callable

from ..flight_rules import (MISSION_RESETS, MISSION_STARTS, SET_MODE_ENCODINGS, TAKEOFF_COMMANDS, TEXT_EVENTS, Mode,
                            ModeKind)
from ..mission.constants import CommandResult
from ..vehicle_info import PARAM_ID_LEN, Param
from ..wire.dialect import mavlink as _d

_KINDS = {k.value: k for k in ModeKind}
_PARAM_TYPES = {e.name.removeprefix("MAV_PARAM_TYPE_"): value for value, e in _d.enums["MAV_PARAM_TYPE"].items()
                if not e.name.endswith("_ENUM_END")}
STATUSTEXT_BYTES = 200   # a longer text goes out in 50-byte chunks (STATUSTEXT id, chunk_seq)


def _flag(v: Any) -> bool:
    if not isinstance(v, bool):
        raise ValueError(f"expected true or false, got {v!r}")
    return v


def _number(v: Any, what: str, *, low: float = 0.0, open_low: bool = True) -> float:
    number = not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v)
    ok = number and (v > low if open_low else v >= low)
    if not ok:
        raise ValueError(f"expected {what} {'>' if open_low else '>='} {low:g}, got {v!r}")
    return float(v)


def one_of(choices: tuple[str, ...]) -> Callable[[Any], str]:
    def parse(v: Any) -> str:
        if v not in choices:
            raise ValueError(f"expected one of {', '.join(repr(c) for c in choices)}, got {v!r}")
        return v
    return parse


def modes(v: Any) -> tuple[Mode, ...]:
    """modes = [{name = "AUTO", number = 3, does = "mission"}, ...]: the autopilot's flight
    modes, HEARTBEAT.custom_mode numbers and what the vehicle does in each."""
    if not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v)):
        raise ValueError(f"expected a non-empty list of tables {{name, number, does}}, got {v!r}")
    out = []
    for i, entry in enumerate(v):
        if set(entry) != {"name", "number", "does"}:
            raise ValueError(f"mode {i}: expected the keys name, number and does, got {sorted(entry)}")
        name, number, does = entry["name"], entry["number"], entry["does"]
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"mode {i}: name must be a non-empty string, got {name!r}")
        if isinstance(number, bool) or not isinstance(number, int) or not 0 <= number <= 0xFFFFFFFF:
            raise ValueError(f"mode {name}: number must be a custom_mode in 0..4294967295, got {number!r}")
        if does not in _KINDS:
            raise ValueError(f"mode {name}: does must be one of {', '.join(_KINDS)}, got {does!r}")
        out.append(Mode(name.strip(), number, _KINDS[does]))
    return tuple(out)


def mode_name(v: Any) -> str:
    """A mode of the profile's mode table, by name (checked against the table when the profile is built)."""
    if not isinstance(v, str) or not v.strip():
        raise ValueError(f"expected a mode name from the profile's modes, got {v!r}")
    return v.strip()


def mode_or_stay(v: Any) -> str:
    """mission_end_mode = a mode name, or "stay" (the mission mode, holding where it ended)."""
    return "" if v == "stay" else mode_name(v)


def mode_names(v: Any) -> frozenset[str]:
    if not isinstance(v, list) or not all(isinstance(x, str) and x.strip() for x in v):
        raise ValueError(f"expected a list of mode names, got {v!r}")
    return frozenset(x.strip() for x in v)


def command_result(v: Any) -> CommandResult:
    """A MAV_RESULT by name (FAILED, TEMPORARILY_REJECTED, DENIED)."""
    try:
        result = CommandResult[str(v).upper().removeprefix("MAV_RESULT_")]
    except KeyError:
        result = None
    if result in (None, CommandResult.ACCEPTED, CommandResult.IN_PROGRESS):
        raise ValueError(f"expected a refusing MAV_RESULT name (FAILED, TEMPORARILY_REJECTED, DENIED), got {v!r}")
    return result


def seconds_or_none(v: Any) -> float | None:
    """A delay in seconds (0: at once), or "none": never."""
    return None if v == "none" else _number(v, "a number of seconds", open_low=False)


def metres(v: Any) -> float:
    return _number(v, "a number of metres")


def speed(v: Any) -> float:
    return _number(v, "a speed in m/s")


def texts(v: Any) -> tuple[tuple[str, str], ...]:
    """statustexts = {event = "text", ...}: the autopilot's words (a STATUSTEXT; over 50 bytes, chunks)."""
    if not isinstance(v, dict):
        raise ValueError(f"expected a table of events ({', '.join(TEXT_EVENTS)}) -> texts, got {v!r}")
    out = []
    for event, text in v.items():
        if event not in TEXT_EVENTS:
            raise ValueError(f"unknown event {event!r} (known: {', '.join(TEXT_EVENTS)})")
        if not isinstance(text, str) or not text or len(text.encode()) > STATUSTEXT_BYTES:
            raise ValueError(f"{event}: expected a STATUSTEXT of 1 to {STATUSTEXT_BYTES} bytes, got {text!r}")
        out.append((event, text))
    return tuple(out)


def params(v: Any) -> tuple[Param, ...]:
    """params = {NAME = value, ...} (a float parameter) or {NAME = {value = 90, type = "INT16"}}
    (MAV_PARAM_TYPE without its prefix): what PARAM_REQUEST_READ is answered with."""
    if not isinstance(v, dict) or not v:
        raise ValueError(f"expected a table of parameter names -> values, got {v!r}")
    out = []
    for name, spec in v.items():
        kind = "REAL32"
        if isinstance(spec, dict):
            if set(spec) != {"value", "type"}:
                raise ValueError(f"{name}: expected {{value, type}}, got {sorted(spec)}")
            spec, kind = spec["value"], spec["type"]
        if kind not in _PARAM_TYPES:
            raise ValueError(f"{name}: type must be a MAV_PARAM_TYPE ({', '.join(_PARAM_TYPES)}), got {kind!r}")
        if isinstance(spec, bool) or not isinstance(spec, (int, float)) or not math.isfinite(spec):
            raise ValueError(f"{name}: expected a finite number, got {spec!r}")
        if not name or len(name.encode()) > PARAM_ID_LEN:
            raise ValueError(f"{name!r}: a parameter name has 1 to {PARAM_ID_LEN} bytes")
        out.append(Param(name, float(spec), _PARAM_TYPES[kind]))
    return tuple(out)


set_mode_params = one_of(SET_MODE_ENCODINGS)
mission_start = one_of(MISSION_STARTS)
takeoff_command = one_of(TAKEOFF_COMMANDS)
disarm_resets_mission = one_of(MISSION_RESETS)
flag = _flag
