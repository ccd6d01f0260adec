"""Hypothesis strategies of the protocol fuzzer: its steps, and the fault schedules they set.

The steps are JSON-safe dicts (they are what a saved case replays); their vocabulary is
documented in `fuzz/protocol/steps.py` and drawn here. What goes into them lives beside:

- `edge_values.py`: float32 and integer edge values, and the out-of-range floats with the
  conversion each breaks;
- `wire_items.py`: mission items as raw wire fields, valid and pushed to their edges, and plans
  of them with a wrong `seq` or `mission_type`;
- `float_items.py`: MISSION_ITEMs whose float fields (x and y too) are out of range;
- `stray_messages.py`: messages sent out of context;
- `control_strategies.py`: the operator-control steps (--operator-control);
- `valid_plans.py`: the plans the reference vehicle accepts, which the tool's own tests draw.

The names of the first four are importable from here too, as the tests use them (`fs.*`).
No strategy may hold a value whose hash is its identity, made anew per draw (a NaN once was): a
strategy's label decides which draws Hypothesis's mutator splices together, and such a label
hangs on the allocator. Without one, a seed explores the same examples however the code is
spread over modules (tests/fuzz/test_seeded_labels.py).
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.mission.items import MissionType
from .edge_values import (F32_EDGES, FLT_MAX, FLT_MIN_NORMAL, FLT_SUBNORMAL_MAX, FLT_SUBNORMAL_MIN,
                          OUT_OF_RANGE, OUT_OF_RANGE_F32, edge_f32, edge_i32, edge_ints, edge_u8, edge_u16,
                          edge_u32, out_of_range_f32, subnormal_f32)
from .float_items import (FLOAT_FIELDS, PAST_RANGE_XY, XY_KINDS, XY_OVERRIDES, exact_xy, float_item_fields,
                          float_overrides, float_wire_item, float_xy)
from .stray_messages import TARGETS, control_raw_message, raw_message
from .wire_items import (ITEM_FIELDS, KNOWN_COMMANDS, SEQ_FAULTS, TEMPLATES, clear_type, commands, edge_wire_item,
                         item_fields, plan_type, valid_wire_item, valid_wire_items, wire_item, wire_plan)

__all__ = [   # the steps, and the names of the modules beside them that the tests use
    "F32_EDGES", "FLT_MAX", "FLT_MIN_NORMAL", "FLT_SUBNORMAL_MAX", "FLT_SUBNORMAL_MIN", "OUT_OF_RANGE",
    "OUT_OF_RANGE_F32", "edge_f32", "edge_i32", "edge_ints", "edge_u8", "edge_u16", "edge_u32",
    "out_of_range_f32", "subnormal_f32",
    "FLOAT_FIELDS", "PAST_RANGE_XY", "XY_KINDS", "XY_OVERRIDES", "exact_xy", "float_item_fields",
    "float_overrides", "float_wire_item", "float_xy",
    "TARGETS", "control_raw_message", "raw_message",
    "ITEM_FIELDS", "KNOWN_COMMANDS", "SEQ_FAULTS", "TEMPLATES", "clear_type", "commands", "edge_wire_item",
    "item_fields", "plan_type", "valid_wire_item", "valid_wire_items", "wire_item", "wire_plan",
    "MISSION_MESSAGES", "fault_schedules", "upload_op", "download_op", "clear_op", "set_current_op",
    "operations", "seconds", "cancel_step", "second_gcs_step", "stray_step", "faults_step", "wait_step",
    "protocol_steps", "operation_sequences",
]

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


def stray_step(max_items: int = 20, max_after: float = 4.0, *,
               handover: bool = False) -> st.SearchStrategy[dict[str, Any]]:
    """Stray messages, sent between operations or `after` seconds into one (`during`); with
    `handover`, operator-control requests and MISSION_START among them."""
    message = st.one_of(raw_message(), control_raw_message()) if handover else raw_message()
    return st.fixed_dictionaries({
        "op": st.just("stray"), "messages": st.lists(message, min_size=1, max_size=3),
        "during": st.one_of(st.none(), operations(max_items)), "after": seconds(max_after)})


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
