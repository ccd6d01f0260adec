"""Hypothesis strategies: valid plans, edge-value items, fault models and schedules, steps.

Two kinds of item. `mission_item` draws a `MissionItem` the reference vehicle accepts
(float32-exact values, so a round trip compares exactly); the tool's own tests use these.
`wire_item` draws what a fuzzing GCS may put on the wire: a dict of raw MISSION_ITEM_INT
field values, every field pushed to its edges (NaN, +-inf, subnormals, float32 extremes,
int32 extremes and negatives, unknown commands and frames, `current`/`autocontinue`
outside 0/1), and, at plan level, a `seq` or `mission_type` that is not what the transfer
expects (gaps, repeats, seq 65535, another plan type). Dicts, because the `MissionItem`
model is the vehicle's canonical form and a fuzz item is exactly what it refuses to be.

Floats that are valid float32 but out of range for the integers autopilots convert them to
(`OUT_OF_RANGE`: 1e10, +-inf, NaN, 215 deg, 2^31, ...) reach every float field of
MISSION_ITEM: params and z through `edge_f32`; x and y, which a MISSION_ITEM_INT carries as
int32, through a wire item's "fx"/"fy" keys (`float_wire_item`: what goes out in
MISSION_ITEM.x/y instead of the int x/y converted, in "float" uploads) and through the x/y
of stray MISSION_ITEMs (`float_item_fields`).

The protocol fuzzer's steps are JSON-safe dicts (they are what a saved case replays);
their vocabulary is documented in `fuzz/protocol/steps.py` and drawn here.

Past the house's ~500 lines on purpose: the order in which the module-level strategies are
created decides which draws share a cached strategy object, and that steers Hypothesis's
mutator. Moving the edge values to a module imported first changed what a seed explores
(the seeded CI campaign ran 1137 or 1165 examples instead of 1133), even with the filter's
lambda kept here; the valid plans (valid_plans.py), which came first and are imported first,
moved without a change. Moving the step functions of the operator-control section (plain
functions, called when the state machine is built) changed it too (1145 examples). A seed must
keep its findings: split further only with campaigns that show it does.
"""

from __future__ import annotations

import math
import struct
from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.mission.constants import (
    FENCE_COMMANDS, MISSION_COMMANDS, POSITIONAL_COMMANDS, RALLY_COMMANDS, Cmd, MissionResult,
)
from mavconform.reference_impl.mission.items import (
    FRAME_MISSION, GLOBAL_FRAMES, INT32_MAX, INT32_MIN, LOCAL_FRAMES, PLAN_TYPES, MissionItem,
    MissionType,
)
from mavconform.reference_impl.handover import control_messages as cm
from .seeded import cached_strategy_builder
from .valid_plans import GLOBAL, mission_item

# --- edge values --------------------------------------------------------------------------

def _f32(bits: int) -> float:
    return struct.unpack("<f", struct.pack("<I", bits))[0]


FLT_MAX = _f32(0x7F7FFFFF)
FLT_MIN_NORMAL = _f32(0x00800000)
FLT_SUBNORMAL_MIN = _f32(0x00000001)
FLT_SUBNORMAL_MAX = _f32(0x007FFFFF)
F32_EDGES = (float("nan"), float("inf"), float("-inf"), 0.0, -0.0, 1.0, -1.0, FLT_MAX, -FLT_MAX,
             FLT_MIN_NORMAL, FLT_SUBNORMAL_MIN, -FLT_SUBNORMAL_MIN, FLT_SUBNORMAL_MAX, _f32(0x7FC00001))

# Floats a float32 field carries exactly (so the wire delivers them unchanged) that no
# integer the receiver converts them to can hold. Autopilots turn MISSION_ITEM's floats into
# integers: latitude/longitude degrees * 1e7 into int32 degE7, local metres * 1e4 into
# int32, altitudes into int32 cm or mm, params used as indices or counts (DO_JUMP's target
# seq and repeat count, a fence polygon's vertex count) into int32/uint16/uint32. In C a
# float-to-int conversion of a value out of the integer's range (NaN and +-inf included) is
# undefined behaviour: on ARM it saturates, on x86 it gives INT_MIN, either way a stored
# value nobody sent. Each value with the conversion it breaks:
OUT_OF_RANGE: tuple[tuple[float, str], ...] = (
    (math.nan, "no integer at all; and every comparison with it is false, so a range check "
               "written as `v < lo || v > hi` lets it through"),
    (math.inf, "no integer: converting it is undefined in C, so a range check done after the "
               "conversion checks INT32_MIN (x86) or INT32_MAX (ARM) instead"),
    (-math.inf, "as +inf, downwards"),
    (1e10, "2^10 * 5^10, exact in float32: overflows int32 in every conversion (degE7 1e17, "
           "local 1e14, cm 1e12, mm 1e13, or taken as a plain integer)"),
    (-1e10, "as 1e10, downwards"),
    (215.0, "the first whole degree whose degE7 overflows int32 (2.15e9 > INT32_MAX; the limit "
            "is 214.7483647 deg): a longitude/latitude check done after the conversion sees a "
            "wrapped value"),
    (-215.0, "as 215, downwards (-2.15e9 < INT32_MIN)"),
    (214749.0, "the first whole metre whose local-frame value (metres * 1e4) overflows int32 "
               "(2147490000 > INT32_MAX); fits a plain int32, so only the scaled path breaks"),
    (2147484.0, "the first whole metre whose altitude in mm overflows int32 (2147484000)"),
    (21474838.0, "the first float32 whole metre whose altitude in cm overflows int32 "
                 "(2147483800; 21474837 is no float32)"),
    (65536.0, "UINT16_MAX + 1: a seq, jump target or count kept in 16 bits wraps to 0"),
    (2.0**31, "INT32_MAX + 1: an index or count kept in int32 overflows by one (and "
              "(float)INT32_MAX rounds to it, so `v <= (float)INT32_MAX` lets it through)"),
    (-2.0**31 - 256, "the float32 just below INT32_MIN (float32 spacing there is 256): "
                     "overflows int32 downwards; INT32_MIN itself still fits"),
    (3e9, "fits uint32 but not int32: a signed/unsigned mix-up stores it negative"),
    (2.0**32, "UINT32_MAX + 1: overflows uint32 too"),
    (FLT_MAX, "the largest finite float32: overflows every integer, and * 1e7 in float32 "
              "arithmetic is inf"),
    (-FLT_MAX, "as FLT_MAX, downwards"),
)
OUT_OF_RANGE_F32: tuple[float, ...] = tuple(v for v, _ in OUT_OF_RANGE)
out_of_range_f32 = st.sampled_from(OUT_OF_RANGE_F32)

subnormal_f32 = st.floats(-FLT_MIN_NORMAL, FLT_MIN_NORMAL, width=32, exclude_min=True,
                          exclude_max=True).filter(lambda v: v != 0.0)
# Every float32 a field can carry, biased to the values that break parsers, validators and
# the float-to-integer conversions after them (`OUT_OF_RANGE`; its NaN, +-inf and +-FLT_MAX
# are edges already). A second NaN branch here made two same-seed searches in one process
# shrink differently (seen with Hypothesis 6.170, whose shrinker compares values nested in
# dicts with ==, and NaN != NaN), so only the values F32_EDGES lacks are added.
_BEYOND_EDGES = tuple(v for v in OUT_OF_RANGE_F32 if v == v and v not in F32_EDGES)
edge_f32 = st.one_of(st.sampled_from(F32_EDGES), st.sampled_from(_BEYOND_EDGES), subnormal_f32,
                     st.floats(width=32))


def edge_ints(lo: int, hi: int, *extra: int) -> st.SearchStrategy[int]:
    """Integers in [lo, hi], biased to both ends, -1/0/1 and the given values."""
    marks = sorted({v for v in (lo, lo + 1, -1, 0, 1, hi - 1, hi, *extra) if lo <= v <= hi})
    return st.one_of(st.sampled_from(marks), st.integers(lo, hi))


edge_u8 = edge_ints(0, 255, 2, 127, 128)
edge_u16 = edge_ints(0, 65535, 255, 256, 32767, 32768)
edge_u32 = edge_ints(0, 2**32 - 1, 2**31)
# x/y: int32 extremes and the first values past +-90 / +-180 degrees in degE7.
edge_i32 = edge_ints(INT32_MIN, INT32_MAX, 900_000_000, 900_000_001, -900_000_001,
                     1_800_000_000, 1_800_000_001, -1_800_000_001)

KNOWN_COMMANDS = frozenset(int(c) for c in (*MISSION_COMMANDS, *FENCE_COMMANDS, *RALLY_COMMANDS))
_COMMANDS_BY_TYPE = {MissionType.MISSION: MISSION_COMMANDS, MissionType.FENCE: FENCE_COMMANDS,
                     MissionType.RALLY: RALLY_COMMANDS}
unknown_command = edge_u16.filter(lambda c: c not in KNOWN_COMMANDS)


@cached_strategy_builder
def commands(mission_type: MissionType) -> st.SearchStrategy[int]:
    """Commands of the plan type, of another plan type, and unknown ones."""
    own = sorted(int(c) for c in _COMMANDS_BY_TYPE[mission_type])
    other = sorted(KNOWN_COMMANDS - set(own))
    return st.one_of(st.sampled_from(own), st.sampled_from(other), unknown_command)


frames = st.one_of(st.sampled_from(sorted(GLOBAL_FRAMES | {FRAME_MISSION})),
                   st.sampled_from(sorted(LOCAL_FRAMES)), edge_u8)

ITEM_FIELDS = ("frame", "command", "current", "autocontinue", "param1", "param2", "param3",
               "param4", "x", "y", "z")
_EDGE_FIELD = {
    "frame": frames, "current": edge_u8, "autocontinue": edge_u8,
    "param1": edge_f32, "param2": edge_f32, "param3": edge_f32, "param4": edge_f32,
    "x": edge_i32, "y": edge_i32, "z": edge_f32,
}


def item_fields(item: MissionItem) -> dict[str, Any]:
    """The wire fields of a valid item (seq and mission_type are the transfer's)."""
    return {name: getattr(item, name) for name in ITEM_FIELDS}


@cached_strategy_builder
def valid_wire_item(mission_type: MissionType) -> st.SearchStrategy[dict[str, Any]]:
    return mission_item(mission_type).map(item_fields)


TEMPLATES = 2   # items of a plan drawn field by field; the rest of the plan copies them
_GLOBAL_ORDER = sorted(GLOBAL_FRAMES)   # the frames a copy of a positional item steps through
_STEP_X = 97    # degE7 a copy moves per index: no two items of a plan alike


@st.composite
def valid_wire_items(draw, mission_type: MissionType, min_size: int = 0,
                     max_size: int = 20) -> list[dict[str, Any]]:
    """A plan of items the spec vehicle accepts, for the price of a few: up to TEMPLATES
    items are drawn in full (and shrink), and the rest copy them in turn, each moved along
    x by its index (so no copy equals its template or another copy of it: one returned in
    another's place shows) and, if its frame is a global one, put in the template's next
    global frame, copy by copy (so a long plan carries every frame though only a few items
    were drawn). Drawn field by field, a 50-item plan cost the protocol
    fuzzer more than everything the vehicle and the oracles did with it
    (bench/protocol_fuzz.py)."""
    # the plan's length as a list of its size draws it (no item drawn): the same lengths,
    # empty plans as often, shrinking by dropping items; a fixed size draws nothing
    n = min_size if min_size == max_size else len(draw(st.lists(st.just(None), min_size=min_size,
                                                                  max_size=max_size)))
    templates = [draw(valid_wire_item(mission_type)) for _ in range(min(n, TEMPLATES))]
    items = list(templates)
    for i in range(len(templates), n):
        item = dict(templates[i % len(templates)])
        shift = _STEP_X * i
        item["x"] = item["x"] + shift if item["x"] + shift <= 900_000_000 else item["x"] - shift
        if item["frame"] in GLOBAL_FRAMES:
            turn = i // len(templates)
            item["frame"] = _GLOBAL_ORDER[(_GLOBAL_ORDER.index(item["frame"]) + turn) % len(_GLOBAL_ORDER)]
        items.append(item)
    return items


@cached_strategy_builder
@st.composite
def edge_wire_item(draw, mission_type: MissionType) -> dict[str, Any]:
    """A valid item with one to three fields replaced by edge values."""
    fields = item_fields(draw(mission_item(mission_type)))
    names = draw(st.lists(st.sampled_from(ITEM_FIELDS), min_size=1, max_size=3, unique=True))
    for name in names:
        fields[name] = draw(commands(mission_type) if name == "command" else _EDGE_FIELD[name])
    return fields


def wire_item(mission_type: MissionType) -> st.SearchStrategy[dict[str, Any]]:
    """Either a valid item or an edge one, as raw MISSION_ITEM_INT fields."""
    return st.one_of(valid_wire_item(mission_type), edge_wire_item(mission_type))


# --- float MISSION_ITEM: every float32 field out of range -----------------------------------

# MISSION_ITEM's float32 fields (MISSION_ITEM_INT carries x and y as int32).
FLOAT_FIELDS = ("param1", "param2", "param3", "param4", "x", "y", "z")
# Wire-item keys that replace MISSION_ITEM's x/y (fuzz/protocol/gcs.py applies them).
XY_OVERRIDES = {"x": "fx", "y": "fy"}
# Where x/y mean a position and how the vehicle scales them, or mean nothing at all.
XY_KINDS = ("global", "local", "no-location")
NO_LOCATION_COMMANDS = (Cmd.DO_CHANGE_SPEED, Cmd.CONDITION_DELAY)   # x/y are params 5/6
# Inside int32 after the conversion, outside the valid range: the validator's job, not the
# conversion's (a global frame's 91 deg latitude, 181 deg longitude).
PAST_RANGE_XY = (91.0, -91.0, 181.0, -181.0)
# In-range x/y whose conversion is exact: k / 2^m where 2^m divides the frame's scale (1e7 =
# 2^7 * 5^7, 1e4 = 2^4 * 5^4, 1), so rounding, truncation and flooring all give the same
# integer and a correct vehicle can store only one value.
_EXACT_XY = {   # (kind, axis) -> (largest magnitude, 2^m)
    ("global", "x"): (90, 128), ("global", "y"): (180, 128),
    ("local", "x"): (100_000, 16), ("local", "y"): (100_000, 16),
    ("no-location", "x"): (1_000_000, 1), ("no-location", "y"): (1_000_000, 1),
}


@cached_strategy_builder
def exact_xy(kind: str, axis: str) -> st.SearchStrategy[float]:
    """In-range x or y of an item of `kind` whose conversion to the int form is exact."""
    limit, denominator = _EXACT_XY[(kind, axis)]
    return st.integers(-limit * denominator, limit * denominator).map(lambda k: k / denominator)


# A float field pushed to its edges, most often out of every integer's range.
out_of_range_or_edge = st.one_of(out_of_range_f32, edge_f32)
_PARAMS_Z = ("param1", "param2", "param3", "param4", "z")
_SOME_XY = st.lists(st.sampled_from(("x", "y")), min_size=1, max_size=2, unique=True)
_FEW_PARAMS_Z = st.lists(st.sampled_from(_PARAMS_Z), max_size=2, unique=True)
_ANY_PARAMS_Z = st.lists(st.sampled_from(_PARAMS_Z), max_size=5, unique=True)


@cached_strategy_builder   # drawn from inside composites: build each strategy once
def float_xy(kind: str, axis: str) -> st.SearchStrategy[float]:
    """What a MISSION_ITEM may carry in x or y for an item of `kind`: out-of-range values,
    in-range ones the vehicle converts exactly, values just past the valid range, the float32
    edges. No arbitrary in-range float: whether a vehicle rounds or truncates it is no
    protocol matter, and the oracle could then expect the wrong one of two integers."""
    return st.one_of(out_of_range_f32, st.one_of(exact_xy(kind, axis), st.sampled_from(PAST_RANGE_XY)),
                     st.one_of(st.sampled_from(F32_EDGES), subnormal_f32))


@cached_strategy_builder
@st.composite
def float_wire_item(draw, mission_type: MissionType) -> dict[str, Any]:
    """A wire item for a float upload (MISSION_ITEM) with its float32 fields pushed out of
    range: x and/or y as "fx"/"fy" keys, the floats that go out in MISSION_ITEM.x/y instead
    of the item's int x/y converted (a MISSION_ITEM_INT of the same item keeps its int x/y;
    an in-range override is converted exactly), and up to two of the params and z as
    themselves. The item has a location in a global frame (x/y degrees, * 1e7 on the
    vehicle), in a local frame (metres, * 1e4), or none: a command whose x/y are plain
    params 5/6 in MAV_FRAME_MISSION (DO_CHANGE_SPEED, CONDITION_DELAY)."""
    kind = draw(st.sampled_from(XY_KINDS))
    fields = item_fields(draw(mission_item(mission_type)))
    if kind == "no-location":
        fields.update(frame=FRAME_MISSION, command=int(draw(st.sampled_from(NO_LOCATION_COMMANDS))))
    else:
        if mission_type is MissionType.MISSION and fields["command"] not in POSITIONAL_COMMANDS:
            fields.update(command=int(Cmd.NAV_WAYPOINT), param1=0.0)
        fields["frame"] = draw(GLOBAL if kind == "global" else st.sampled_from(sorted(LOCAL_FRAMES)))
    fields.update(draw(_FLOAT_OVERRIDES[kind]))
    return fields


@cached_strategy_builder
@st.composite
def float_overrides(draw, kind: str) -> dict[str, float]:
    """What a `float_wire_item` of `kind` carries instead of its own floats: "fx" and/or
    "fy" (`float_xy`), and up to two of the params and z, out of range most often."""
    out = {XY_OVERRIDES[axis]: draw(float_xy(kind, axis)) for axis in draw(_SOME_XY)}
    for name in draw(_FEW_PARAMS_Z):
        out[name] = draw(out_of_range_or_edge)
    return out


_FLOAT_OVERRIDES = {kind: float_overrides(kind) for kind in XY_KINDS}


@st.composite
def float_item_fields(draw) -> dict[str, float]:
    """Float fields of a stray MISSION_ITEM: x and y always (a float32 carries them, not
    the int they stand for), params and z some of the time, out of range most often."""
    fields = {"x": draw(out_of_range_or_edge), "y": draw(out_of_range_or_edge)}
    for name in draw(_ANY_PARAMS_Z):
        fields[name] = draw(out_of_range_or_edge)
    return fields


SEQ_FAULTS = ("gap", "repeat", "far", "other-type")


@st.composite
def wire_plan(draw, mission_type: MissionType, max_size: int = 20, *,
              edges: bool = True, min_size: int = 0) -> list[dict[str, Any]]:
    """A plan as wire items: valid ones, and (in about one plan in three, fewer as it
    shrinks) edge items spliced in or one item whose `seq` or `mission_type` is wrong on the
    wire. An item's "seq" or "mission_type" key, when present, is what goes out instead of
    the transfer's own. `edges=False`: only items the spec vehicle accepts."""
    items = draw(valid_wire_items(mission_type, min_size, max_size))
    if not items or not edges:
        return items
    last = len(items) - 1
    if draw(st.integers(0, 4)) >= 3:
        for index, edge in draw(st.lists(st.tuples(st.integers(0, last), edge_wire_item(mission_type)),
                                         min_size=1, max_size=2)):
            items[index] = edge
    if draw(st.integers(0, 7)) == 7:
        index, fault = draw(st.integers(0, last)), draw(st.sampled_from(SEQ_FAULTS))
        item = items[index] = dict(items[index])
        if fault == "gap":
            item["seq"] = index + draw(st.integers(1, 3))
        elif fault == "repeat":
            item["seq"] = index - 1 if index else 1
        elif fault == "far":
            item["seq"] = draw(st.sampled_from([65535, 32768, len(items)]))
        else:
            item["mission_type"] = draw(st.sampled_from(
                [int(t) for t in PLAN_TYPES if t is not mission_type] + [3, 254, 255]))
    return items


# --- fault schedules (JSON-safe; fuzz/protocol/faults.py turns them into FaultModels) -----

MISSION_MESSAGES = ("MISSION_ACK", "MISSION_COUNT", "MISSION_REQUEST_INT", "MISSION_REQUEST",
                    "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_LIST",
                    "MISSION_CLEAR_ALL", "MISSION_CURRENT", "MISSION_SET_CURRENT")
_prob = st.floats(0, 1).map(lambda p: round(p, 3))


@st.composite
def fault_schedules(draw, max_loss: float = 0.3, max_burst: float = 30.0) -> dict[str, Any]:
    """One direction's faults: random loss, duplication, reordering, delay, jitter and
    corruption; bursts (short total outages, `[start, length]` seconds after the schedule
    is set); scripted drops ("the 2nd MISSION_ACK", "MISSION_ITEM_INT from the 3rd on");
    and a cut: from the nth message called NAME on, the next `span` messages are all lost
    (a partition that begins at a chosen message). Keys at their zero value are left out."""
    spec = {
        "loss": round(draw(st.floats(0, max_loss)), 3),
        "duplicate": round(draw(st.floats(0, 0.2)), 3),
        "reorder": round(draw(st.floats(0, 0.2)), 3),
        "reorder_delay": round(draw(st.floats(0, 0.2)), 3),
        "delay": round(draw(st.floats(0, 0.05)), 3),
        "jitter": round(draw(st.floats(0, 0.05)), 3),
        "corrupt": round(draw(st.floats(0, 0.05)), 3),
        "bursts": [[round(s, 2), round(n, 2)] for s, n in draw(st.lists(
            st.tuples(st.floats(0, min(20.0, max_burst)), st.floats(0.05, max_burst)), max_size=2))],
        "drops": draw(st.lists(st.fixed_dictionaries({
            "name": st.sampled_from(MISSION_MESSAGES), "nth": st.integers(1, 6),
            "onwards": st.booleans()}), max_size=2)),
        "cut": draw(st.one_of(st.none(), st.fixed_dictionaries({
            "name": st.sampled_from(MISSION_MESSAGES), "nth": st.integers(1, 6),
            "span": st.integers(1, 40)}))),
    }
    return {k: v for k, v in spec.items() if v}


# --- protocol steps -------------------------------------------------------------------------

plan_type = st.sampled_from([int(t) for t in PLAN_TYPES])
clear_type = st.sampled_from([int(t) for t in PLAN_TYPES] + [int(MissionType.ALL)])


@st.composite
def upload_op(draw, max_items: int = 20, *, edges: bool = True, min_items: int = 0) -> dict[str, Any]:
    """An upload; about one in five "float" (MISSION_ITEM), and three in four of those
    (with `edges`) with one or two `float_wire_item`s spliced in: out-of-range floats in the
    float fields, x/y included, inside a transfer. Shrinking drops them (the choice shrinks
    to none)."""
    t = draw(plan_type)
    items = draw(wire_plan(MissionType(t), max_items, edges=edges, min_size=min_items))
    op = {"op": "upload", "type": t, "items": items}
    if draw(st.integers(0, 4)) == 4:
        op["float"] = True   # answer with MISSION_ITEM (float x/y) even when asked for _INT
        if edges and items and draw(st.integers(0, 3)) > 0:
            for index, item in draw(st.lists(st.tuples(st.integers(0, len(items) - 1),
                                                       float_wire_item(MissionType(t))),
                                             min_size=1, max_size=2)):
                items[index] = item
    return op


def download_op() -> st.SearchStrategy[dict[str, Any]]:
    return st.fixed_dictionaries({"op": st.just("download"), "type": plan_type})


def clear_op() -> st.SearchStrategy[dict[str, Any]]:
    return st.fixed_dictionaries({"op": st.just("clear"), "type": clear_type})


def set_current_op() -> st.SearchStrategy[dict[str, Any]]:
    return st.fixed_dictionaries({"op": st.just("set_current"),
                                  "seq": st.one_of(st.integers(0, 60), edge_u16),
                                  "command": st.booleans()})


def operations(max_items: int = 20) -> st.SearchStrategy[dict[str, Any]]:
    """One GCS operation, of any kind and plan type."""
    return st.one_of(upload_op(max_items), download_op(), clear_op(), set_current_op())


def seconds(max_s: float) -> st.SearchStrategy[float]:
    return st.floats(0, max_s).map(lambda s: round(s, 3))


def cancel_step(max_items: int = 20, max_after: float = 4.0) -> st.SearchStrategy[dict[str, Any]]:
    """Start an operation and cancel it `after` seconds in (if it is still running)."""
    return st.fixed_dictionaries({"op": st.just("cancel"), "of": operations(max_items),
                                  "after": seconds(max_after)})


def second_gcs_step(max_items: int = 20, max_after: float = 4.0) -> st.SearchStrategy[dict[str, Any]]:
    """GCS A starts `first`; `after` seconds later GCS B (another system id) starts `second`."""
    return st.fixed_dictionaries({"op": st.just("second_gcs"), "first": operations(max_items),
                                  "second": operations(max_items), "after": seconds(max_after)})


TARGETS = ("target", "broadcast", "other-system", "other-component")
_any_type = st.one_of(plan_type, st.sampled_from([255, 3, 254]), edge_u8)


@st.composite
def raw_message(draw) -> dict[str, Any]:
    """A message a GCS sends out of context: ACK/ITEM/REQUEST nobody asked for, a COUNT of
    65535, a wrong mission_type, a seq beyond the count, or the right message addressed to
    someone else. `to` names the addressee (resolved against the target's ids), `from` the
    GCS that sends it ("a", whose operations run; "b"; or "mute", which never answers)."""
    name = draw(st.sampled_from([
        "MISSION_ACK", "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_INT", "MISSION_REQUEST",
        "MISSION_COUNT", "MISSION_REQUEST_LIST", "MISSION_CLEAR_ALL", "MISSION_SET_CURRENT",
        "COMMAND_LONG"]))
    if name == "MISSION_ACK":
        fields = {"type": draw(st.one_of(st.sampled_from([int(r) for r in MissionResult]), edge_u8)),
                  "mission_type": draw(_any_type), "opaque_id": draw(edge_u32)}
    elif name in ("MISSION_ITEM_INT", "MISSION_ITEM"):
        t = draw(st.sampled_from(PLAN_TYPES))
        fields = dict(draw(wire_item(t)), seq=draw(st.one_of(st.integers(0, 60), edge_u16)),
                      mission_type=draw(st.one_of(st.just(int(t)), _any_type)))
        if name == "MISSION_ITEM":   # float x/y: anything a float32 holds; any float field out of range
            fields.update(draw(float_item_fields()))
    elif name in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
        fields = {"seq": draw(st.one_of(st.integers(0, 60), edge_u16)), "mission_type": draw(_any_type)}
    elif name == "MISSION_COUNT":
        fields = {"count": draw(st.one_of(st.sampled_from([65535, 0, 1, 1001, 257, 65]), edge_u16)),
                  "mission_type": draw(_any_type), "opaque_id": draw(edge_u32)}
    elif name in ("MISSION_REQUEST_LIST", "MISSION_CLEAR_ALL"):
        fields = {"mission_type": draw(_any_type)}
    elif name == "MISSION_SET_CURRENT":
        fields = {"seq": draw(st.one_of(st.integers(0, 60), edge_u16))}
    else:   # MAV_CMD_DO_SET_MISSION_CURRENT with any param1
        fields = {"command": int(Cmd.DO_SET_MISSION_CURRENT), "confirmation": 0,
                  "param1": draw(edge_f32), "param2": draw(st.sampled_from([0.0, 1.0])),
                  "param3": 0.0, "param4": 0.0, "param5": 0.0, "param6": 0.0, "param7": 0.0}
    return {"msg": name, "fields": fields, "to": draw(st.sampled_from(TARGETS)),
            "from": draw(st.sampled_from(["a", "b", "mute"]))}


def stray_step(max_items: int = 20, max_after: float = 4.0, *,
               handover: bool = False) -> st.SearchStrategy[dict[str, Any]]:
    """Stray messages, sent between operations or `after` seconds into one (`during`); with
    `handover`, operator-control requests and MISSION_START among them."""
    message = st.one_of(raw_message(), control_raw_message()) if handover else raw_message()
    return st.fixed_dictionaries({
        "op": st.just("stray"), "messages": st.lists(message, min_size=1, max_size=3),
        "during": st.one_of(st.none(), operations(max_items)), "after": seconds(max_after)})


# --- operator control (--operator-control) -----------------------------------------------------------

REQUEST_OPERATOR_CONTROL = cm.REQUEST_CONTROL   # MAV_CMD_REQUEST_OPERATOR_CONTROL (development.xml)
CONTROL_ACTIONS = ("request", "release", "allow", "disallow")
OWNER_ANSWERS = (None, "allow", "release", "refuse")
FUZZ_GCS_IDS = (245.0, 246.0, 248.0)   # A, B, the mute GCS (fuzz/protocol/world.py)


def control_step(max_timeout: float = 10.0, actions: tuple[str, ...] = CONTROL_ACTIONS
                 ) -> st.SearchStrategy[dict[str, Any]]:
    """GCS A or B asks for control (param 2: allow takeover; param 3: its timeout; with
    `wait_for_owner` a refusal waits for the owner's answer), releases it, or, as the owner,
    allows or disallows takeover. `answer` is what the owner answers a request the vehicle
    forwards to it meanwhile."""
    timeouts = [t for t in (3.0, 5.0, 10.0) if t <= max(3.0, max_timeout)]
    return st.fixed_dictionaries({
        "op": st.just("control"), "gcs": st.sampled_from(["a", "b"]),
        "action": st.sampled_from(actions), "allow": st.booleans(),
        "timeout": st.sampled_from(timeouts), "wait_for_owner": st.booleans(),
        "answer": st.sampled_from(OWNER_ANSWERS)})


def gcs_loss_step(max_silence: float = 12.0, max_wait: float = 20.0) -> st.SearchStrategy[dict[str, Any]]:
    """GCS A or B sends no HEARTBEAT for `seconds` (then beats again); `wait` seconds pass.
    Half the draws are 7 s, beyond the 5 s owner loss plus a status period, so a silent
    owner's loss is met as often as a short gap it must survive (not where the bounds are
    shorter: over UDP, where time is real)."""
    lost = 7.0
    if max_silence < lost or max_wait < lost:   # over UDP: short gaps only, no emphasis
        return st.fixed_dictionaries({"op": st.just("gcs_loss"), "gcs": st.sampled_from(["a", "b"]),
                                      "seconds": seconds(max_silence), "wait": seconds(max_wait)})
    return st.fixed_dictionaries({
        "op": st.just("gcs_loss"), "gcs": st.sampled_from(["a", "b"]),
        "seconds": st.one_of(st.just(lost), seconds(max_silence)),
        "wait": st.one_of(st.just(lost), seconds(max_wait))})


def b_operation(max_items: int = 20) -> st.SearchStrategy[dict[str, Any]]:
    """An operation of GCS B on its own (with operator control: maybe not the owner's)."""
    return operations(max_items).map(lambda op: {**op, "gcs": "b"})


@st.composite
def control_raw_message(draw) -> dict[str, Any]:
    """MAV_CMD_REQUEST_OPERATOR_CONTROL with any params (release, request, param 2 and 4 out of
    range, param 3 at and beyond the XML's 3..60 s), or MAV_CMD_MISSION_START, as a stray."""
    if draw(st.booleans()):
        fields = {"command": REQUEST_OPERATOR_CONTROL, "confirmation": draw(st.sampled_from([0, 1, 255])),
                  "param1": draw(st.one_of(st.sampled_from([1.0, 0.0]), edge_f32)),
                  "param2": draw(st.one_of(st.sampled_from([0.0, 1.0]), edge_f32)),
                  "param3": draw(st.one_of(st.sampled_from([10.0, 0.0, 3.0, 60.0]), edge_f32)),
                  "param4": draw(st.one_of(st.sampled_from((0.0, *FUZZ_GCS_IDS)), edge_f32)),
                  "param5": 0.0, "param6": 0.0, "param7": 0.0}
    else:
        fields = {"command": int(Cmd.MISSION_START), "confirmation": 0,
                  "param1": draw(st.sampled_from([0.0, 1.0])), "param2": draw(st.sampled_from([0.0, 5.0])),
                  "param3": 0.0, "param4": 0.0, "param5": 0.0, "param6": 0.0, "param7": 0.0}
    return {"msg": "COMMAND_LONG", "fields": fields, "to": draw(st.sampled_from(TARGETS)),
            "from": draw(st.sampled_from(["a", "b", "mute"]))}


def faults_step(max_loss: float = 0.3, max_burst: float = 30.0) -> st.SearchStrategy[dict[str, Any]]:
    """New faults on GCS A's link: `up` (A -> vehicle) and `down`; null is a clean direction."""
    direction = st.one_of(st.none(), fault_schedules(max_loss, max_burst))
    return st.fixed_dictionaries({"op": st.just("faults"), "up": direction, "down": direction})


def wait_step(max_seconds: float = 20.0) -> st.SearchStrategy[dict[str, Any]]:
    """Let time pass (partitions end, abandoned transfers time out)."""
    return st.fixed_dictionaries({"op": st.just("wait"), "seconds": seconds(max_seconds)})


def protocol_steps(max_items: int = 20, *, faults: bool = True,
                   max_wait: float = 20.0) -> st.SearchStrategy[dict[str, Any]]:
    """Any one step of the protocol fuzzer."""
    after = min(4.0, max_wait)
    kinds = [operations(max_items), cancel_step(max_items, after), second_gcs_step(max_items, after),
             stray_step(max_items, after), wait_step(max_wait)]
    if faults:
        kinds.append(faults_step())
    return st.one_of(*kinds)


def operation_sequences(max_items: int = 20, max_steps: int = 10, *, faults: bool = True,
                        max_wait: float = 20.0) -> st.SearchStrategy[list[dict[str, Any]]]:
    """A whole program for the protocol fuzzer: a list of steps `replay` can run."""
    return st.lists(protocol_steps(max_items, faults=faults, max_wait=max_wait),
                    min_size=1, max_size=max_steps)
