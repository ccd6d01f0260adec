"""Messages a GCS sends out of context, for the protocol fuzzer's stray steps: an ACK, ITEM or
REQUEST nobody asked for, a COUNT of 65535, a wrong mission_type, a seq beyond the count, the
right message addressed to someone else; with operator control, MAV_CMD_REQUEST_OPERATOR_CONTROL
with any params and MAV_CMD_MISSION_START.
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES
from .edge_values import edge_f32, edge_u8, edge_u16, edge_u32
from .float_items import float_item_fields
from .wire_items import plan_type, wire_item


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


REQUEST_OPERATOR_CONTROL = cm.REQUEST_CONTROL   # MAV_CMD_REQUEST_OPERATOR_CONTROL (development.xml)
FUZZ_GCS_IDS = (245.0, 246.0, 248.0)   # A, B, the mute GCS (fuzz/protocol/world.py)


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
