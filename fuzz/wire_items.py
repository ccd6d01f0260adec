"""What a fuzzing GCS puts on the wire as mission items: dicts of raw MISSION_ITEM_INT field
values, valid ones and ones with fields pushed to their edges (NaN, +-inf, subnormals, float32
and int32 extremes, unknown commands and frames, `current`/`autocontinue` outside 0/1), and at
plan level a `seq` or `mission_type` that is not what the transfer expects (gaps, repeats, seq
65535, another plan type). Dicts, because the `MissionItem` model is the vehicle's canonical
form and a fuzz item is exactly what it refuses to be (valid_plans.py draws those).
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.mission.constants import FENCE_COMMANDS, MISSION_COMMANDS, RALLY_COMMANDS
from mavconform.reference_impl.mission.items import (
    FRAME_MISSION, GLOBAL_FRAMES, LOCAL_FRAMES, PLAN_TYPES, MissionItem, MissionType,
)
from .edge_values import edge_f32, edge_i32, edge_u8, edge_u16
from .seeded import cached_strategy_builder
from .valid_plans import mission_item


plan_type = st.sampled_from([int(t) for t in PLAN_TYPES])
clear_type = st.sampled_from([int(t) for t in PLAN_TYPES] + [int(MissionType.ALL)])

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
