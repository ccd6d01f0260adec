"""The cells of the command × param matrix: every mission command, each param probed with values
chosen from its upstream definition (issue 26; the facts: command_facts.py).

A command's first cell is its `nominal` item: every param at a value its definition allows
(reserved 0, an enum's first value, a bound's minimum, otherwise 0), a location near home in
MAV_FRAME_GLOBAL_RELATIVE_ALT_INT (6) for a command with hasLocation, MAV_FRAME_MISSION (2)
otherwise. Every other cell changes one param of the nominal item (`probe` names which and how,
"p<i>:<kind>"; params 5-7 travel as x, y, z):

    reserved          a non-zero value in a param upstream marks reserved (it carries nothing,
                      so a vehicle may drop it) and NaN where that is its upstream default
    min, max          the bounds (minValue, maxValue)
    below, above      one increment (or 1) outside them
    inside            within the bounds, off a bound; `off-increment`: half an increment off
                      the step where upstream gives one
    enum-first/-last  the enum's lowest and highest value; `enum-invalid`: one past the highest
    flags-all         a bitmask enum's every flag; `flags-unknown`: the next bit
    value, negative   a param with no bounds: 1234.5677 (float32: the precision a round trip
                      keeps) and -12.375; whole numbers in x and y of a command without a location
    nan               NaN where upstream says what NaN means (default / current)
    int32_max         x or y at INT32_MAX where upstream makes it "no location"

Values are exact float32 numbers, so a difference on the way back is the vehicle's.
"""

from __future__ import annotations

import math
from dataclasses import replace

from mavconform.reference_impl.mission.items import MissionItem, MissionType, to_float32

from .cells import HOME_X, HOME_Y, Cell
from .command_facts import COMMANDS, P

NAN = float("nan")
INT32_MAX = 2**31 - 1
LOCATION_FRAME, PLAIN_FRAME = 6, 2
VALUE, NEGATIVE = to_float32(1234.5678), -12.375
FIELD = {1: "param1", 2: "param2", 3: "param3", 4: "param4", 5: "x", 6: "y", 7: "z"}


def _nominal_value(p: P) -> float:
    if p.reserved:
        return 0.0
    if p.enum:
        return 0.0 if p.bitmask else float(p.enum[0])
    if p.min is not None:
        return p.min
    if p.max is not None:
        return min(0.0, p.max)
    return 0.0


def nominal(value: int) -> MissionItem:
    fact = COMMANDS[value]
    v = [_nominal_value(p) for p in fact.params]
    if fact.has_location:
        x, y, z, frame = HOME_X + 1234, HOME_Y - 2345, 25.0, LOCATION_FRAME
    else:
        x, y, z, frame = int(v[4]), int(v[5]), v[6], PLAIN_FRAME
    return MissionItem(0, frame, value, v[0], v[1], v[2], v[3], x, y, z, 0, 1)


def _bounded(p: P) -> list[tuple[str, float]]:
    step = p.increment or 1.0
    out: list[tuple[str, float]] = []
    if p.min is not None:
        out += [("min", p.min), ("below", p.min - step)]
    if p.max is not None:
        out += [("max", p.max), ("above", p.max + step)]
    if p.min is not None and p.max is not None:
        inside = p.min + math.floor((p.max - p.min) / step / 2) * step
    elif p.min is not None:
        inside = p.min + 7 * step if p.increment else p.min + 12.375
    else:
        inside = p.max - 7 * step if p.increment else p.max - 12.375   # type: ignore[operator]
    if inside not in (p.min, p.max):
        out.append(("inside", inside))
    if p.increment:
        out.append(("off-increment", inside + p.increment / 2))
    return out


def _kinds(p: P, index: int, has_location: bool) -> list[tuple[str, float]]:
    whole = index in (5, 6)                 # x and y are int32 in MISSION_ITEM_INT
    if whole and has_location:
        return [("int32_max", float(INT32_MAX))] if p.int32_max else []
    if p.reserved:
        out = [("reserved", 1.0)]
        if p.default is not None and p.default != p.default and not whole:
            out.append(("reserved-nan", NAN))
        return out
    out = []
    if p.enum and p.bitmask:
        every = 0
        for v in p.enum:
            every |= v
        out += [("flags-all", float(every)), ("flags-unknown", float(1 << every.bit_length()))]
    elif p.enum:
        out += [("enum-first", float(p.enum[0]))]
        if p.enum[-1] != p.enum[0]:
            out.append(("enum-last", float(p.enum[-1])))
        out.append(("enum-invalid", float(p.enum[-1] + 1)))
    elif p.min is not None or p.max is not None:
        out += _bounded(p)
    elif index == 7 and has_location:
        out.append(("value", 12.375))
    else:
        out += [("value", 12345.0 if whole else VALUE), ("negative", -12345.0 if whole else NEGATIVE)]
    if whole:
        out = [(k, v) for k, v in out if v == int(v)]
    if p.int32_max and whole:
        out.append(("int32_max", float(INT32_MAX)))
    if p.nan_default and not whole:
        out.append(("nan", NAN))
    return out


def _with(item: MissionItem, index: int, value: float) -> MissionItem:
    if index in (5, 6):
        return replace(item, **{FIELD[index]: int(value)})
    return replace(item, **{FIELD[index]: to_float32(value) if value == value else value})


def command_cells(commands: list[int] | None = None) -> list[Cell]:
    """The nominal cell of each mission command, then one cell per probe of each param."""
    cells: list[Cell] = []
    for value in commands or sorted(COMMANDS):
        fact = COMMANDS[value]
        base = nominal(value)
        cells.append(Cell(MissionType.MISSION, base.frame, value, (base,), "nominal"))
        for index, p in enumerate(fact.params, start=1):
            for kind, v in _kinds(p, index, fact.has_location):
                probed = _with(base, index, v)
                if probed != base or v != v:
                    cells.append(Cell(MissionType.MISSION, base.frame, value, (probed,), f"p{index}:{kind}"))
    return cells
