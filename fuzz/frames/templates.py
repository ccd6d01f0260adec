"""The valid frames the mutators start from: every mission message type, a few field values
each (ordinary ones and edge ones), addressed to the target, from plausible GCS ids.

A template is a (name, build) pair: `build(target)` returns the message. The list is data,
indexed by the fuzz program, so a saved case names its templates and a shrunk program
drifts towards the first entries (a GCS HEARTBEAT, then plain requests).
"""

from __future__ import annotations

from typing import Any, Callable

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

Target = tuple[int, int]
Template = tuple[str, Callable[[Target], Any]]

# Where fuzz frames claim to come from: GCSs (255, 254, 246), any component, a companion
# computer on the vehicle's own system (1/191). The oracle GCS (rig.py, 250/190) is none of
# these, so no fuzz frame can touch its transfers or its signing stream, and no reply to a
# fuzz frame is addressed to it. (Not system 0: a reply to it would be a broadcast, which
# the oracle's download would rightly take as its own answer.)
GCS_IDS: tuple[tuple[int, int], ...] = ((255, 190), (255, 0), (246, 190), (255, 1),
                                        (1, 191), (253, 190), (254, 190), (255, 190))

MISSION, FENCE, RALLY, ALL = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY, MissionType.ALL
NAN, INF = float("nan"), float("inf")


def _item(seq: int, command: int = Cmd.NAV_WAYPOINT, mt: MissionType = MISSION, frame: int = 3,
          x: int = 473977420, y: int = 85455940, z: float = 10.0, p1: float = 0.0, p4: float = 0.0) -> MissionItem:
    return MissionItem(seq, frame, command, param1=p1, param4=p4, x=x, y=y, z=z, mission_type=mt)


def _heartbeat(_t: Target) -> Any:
    return m.gcs_heartbeat_message()


def _cmd_long(command: int, p1: float = 0.0) -> Callable[[Target], Any]:
    return lambda t: _d.MAVLink_command_long_message(t[0], t[1], command, 0, p1, 0, 0, 0, 0, 0, 0)


def _cmd_int(command: int, p1: float = 0.0) -> Callable[[Target], Any]:
    return lambda t: _d.MAVLink_command_int_message(t[0], t[1], 0, command, 0, 0, p1, 0, 0, 0, 0, 0, 0)


TEMPLATES: tuple[Template, ...] = (
    ("HEARTBEAT", _heartbeat),
    ("MISSION_REQUEST_LIST mission", lambda t: m.request_list_message(MISSION, t)),
    ("MISSION_REQUEST_LIST fence", lambda t: m.request_list_message(FENCE, t)),
    ("MISSION_REQUEST_LIST rally", lambda t: m.request_list_message(RALLY, t)),
    ("MISSION_REQUEST_LIST type 255", lambda t: _d.MAVLink_mission_request_list_message(t[0], t[1], 255)),
    ("MISSION_COUNT 3 mission", lambda t: m.count_message(3, MISSION, t)),
    ("MISSION_COUNT 0 mission", lambda t: m.count_message(0, MISSION, t)),
    ("MISSION_COUNT 4 fence", lambda t: m.count_message(4, FENCE, t)),
    ("MISSION_COUNT 1 rally", lambda t: m.count_message(1, RALLY, t)),
    ("MISSION_COUNT 65535 mission", lambda t: m.count_message(65535, MISSION, t)),
    ("MISSION_COUNT 2 type 7", lambda t: _d.MAVLink_mission_count_message(t[0], t[1], 2, 7, 0)),
    ("MISSION_ITEM_INT 0 waypoint", lambda t: m.item_message(_item(0), t)),
    ("MISSION_ITEM_INT 1 NaN params", lambda t: m.item_message(_item(1, p1=NAN, p4=NAN, z=NAN), t)),
    ("MISSION_ITEM_INT 65535 inf", lambda t: m.item_message(_item(65535, p1=INF, z=-INF), t)),
    ("MISSION_ITEM_INT 0 unknown command", lambda t: m.item_message(_item(0, command=65000), t)),
    ("MISSION_ITEM_INT 0 fence vertex", lambda t: m.item_message(
        _item(0, Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION, FENCE, p1=4.0), t)),
    ("MISSION_ITEM_INT 0 rally point", lambda t: m.item_message(_item(0, Cmd.NAV_RALLY_POINT, RALLY), t)),
    ("MISSION_ITEM_INT 2 frame 99", lambda t: m.item_message(_item(2, frame=99, x=-2**31, y=2**31 - 1), t)),
    ("MISSION_ITEM 0 waypoint", lambda t: m.item_message(_item(0), t, as_int=False)),
    ("MISSION_ITEM 1 huge x", lambda t: _d.MAVLink_mission_item_message(
        t[0], t[1], 1, 3, 16, 0, 1, 0, 0, 0, 0, 1e30, -1e30, 10.0, 0)),
    ("MISSION_REQUEST_INT 0 mission", lambda t: m.request_message(0, MISSION, t)),
    ("MISSION_REQUEST_INT 1000 rally", lambda t: m.request_message(1000, RALLY, t)),
    ("MISSION_REQUEST 0 fence", lambda t: m.request_message(0, FENCE, t, as_int=False)),
    ("MISSION_ACK accepted mission", lambda t: m.ack_message(0, MISSION, t)),
    ("MISSION_ACK cancelled fence", lambda t: m.ack_message(15, FENCE, t)),
    ("MISSION_ACK code 200 type 255", lambda t: m.ack_message(200, 255, t, 0xFFFFFFFF)),
    ("MISSION_CLEAR_ALL mission", lambda t: m.clear_all_message(MISSION, t)),
    ("MISSION_CLEAR_ALL fence", lambda t: m.clear_all_message(FENCE, t)),
    ("MISSION_CLEAR_ALL rally", lambda t: m.clear_all_message(RALLY, t)),
    ("MISSION_CLEAR_ALL all", lambda t: m.clear_all_message(ALL, t)),
    ("MISSION_SET_CURRENT 1", lambda t: m.set_current_message(1, t)),
    ("MISSION_SET_CURRENT 65535", lambda t: m.set_current_message(65535, t)),
    ("MISSION_WRITE_PARTIAL_LIST 0-1", lambda t: _d.MAVLink_mission_write_partial_list_message(
        t[0], t[1], 0, 1, 0)),
    ("MISSION_REQUEST_PARTIAL_LIST 0-2", lambda t: _d.MAVLink_mission_request_partial_list_message(
        t[0], t[1], 0, 2, 0)),
    ("MISSION_CURRENT 0", lambda t: m.current_message(0, 3, 0, 0, (0, 0, 0))),
    ("MISSION_ITEM_REACHED 1", lambda t: m.item_reached_message(1)),
    ("COMMAND_LONG DO_SET_MISSION_CURRENT 2", _cmd_long(Cmd.DO_SET_MISSION_CURRENT, 2.0)),
    ("COMMAND_LONG MISSION_START", _cmd_long(Cmd.MISSION_START)),
    ("COMMAND_LONG unknown command", _cmd_long(65001)),
    ("COMMAND_INT DO_SET_MISSION_CURRENT 0", _cmd_int(Cmd.DO_SET_MISSION_CURRENT)),
    ("MISSION_COUNT 3 mission (broadcast)", lambda _t: m.count_message(3, MISSION, (0, 0))),
    ("MISSION_CLEAR_ALL all (other system)", lambda t: m.clear_all_message(ALL, ((t[0] + 1) & 0xFF, t[1]))),
)

TEMPLATE_NAMES: tuple[str, ...] = tuple(name for name, _ in TEMPLATES)
