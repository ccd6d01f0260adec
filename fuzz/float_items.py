"""MISSION_ITEM with every float32 field out of range: x and y included, which a
MISSION_ITEM_INT carries as int32 but a MISSION_ITEM as floats the vehicle converts.

Out-of-range values (edge_values.OUT_OF_RANGE: 1e10, +-inf, NaN, 215 deg, 2^31, ...) reach x and
y through a wire item's "fx"/"fy" keys (`float_wire_item`: what goes out in MISSION_ITEM.x/y
instead of the int x/y converted, in "float" uploads) and through the x/y of stray MISSION_ITEMs
(`float_item_fields`); params and z through `edge_f32` too.
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.mission.constants import POSITIONAL_COMMANDS, Cmd
from mavconform.reference_impl.mission.items import FRAME_MISSION, LOCAL_FRAMES, MissionType
from .edge_values import F32_EDGES, edge_f32, out_of_range_f32, subnormal_f32
from .seeded import cached_strategy_builder
from .valid_plans import GLOBAL, mission_item
from .wire_items import item_fields


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
