"""Between `MissionItem`s and the dialect's mission messages.

One place builds every mission message the engines send, so field order and the meaning
of extension fields (mission_type, opaque_id) are written down once.
"""

from __future__ import annotations

from typing import Any

from ..wire.dialect import mavlink as _d
from .constants import Cmd
from .items import MISSION_PLAN, PLAN_TYPE_BY_VALUE, MissionItem, MissionType

ITEM_INT = "MISSION_ITEM_INT"
ITEM_FLOAT = "MISSION_ITEM"
REQUEST_INT = "MISSION_REQUEST_INT"
REQUEST_FLOAT = "MISSION_REQUEST"


def item_message(item: MissionItem, target: tuple[int, int], *, as_int: bool = True) -> Any:
    """MISSION_ITEM_INT (default) or MISSION_ITEM for `item`, addressed to `target`."""
    ts, tc = target
    if as_int:
        return _d.MAVLink_mission_item_int_message(
            ts, tc, item.seq, item.frame, item.command, item.current, item.autocontinue,
            item.param1, item.param2, item.param3, item.param4, item.x, item.y, item.z,
            int(item.mission_type))
    fx, fy = item.float_xy()
    return _d.MAVLink_mission_item_message(
        ts, tc, item.seq, item.frame, item.command, item.current, item.autocontinue,
        item.param1, item.param2, item.param3, item.param4, fx, fy, item.z,
        int(item.mission_type))


def item_from_message(msg: Any) -> MissionItem | None:
    """The canonical item a MISSION_ITEM(_INT) carries; None if its x/y cannot be an int32."""
    if msg._type == ITEM_INT:
        x, y = msg.x, msg.y
    else:
        x, y = MissionItem.int_xy_from_float(msg.frame, msg.x, msg.y)
        if x is None or y is None:
            return None
    # positional, in MissionItem's field order (cheaper than keywords on this hot path)
    return MissionItem(msg.seq, msg.frame, msg.command, msg.param1, msg.param2, msg.param3,
                       msg.param4, x, y, msg.z, msg.current, msg.autocontinue,
                       PLAN_TYPE_BY_VALUE.get(msg.mission_type, MISSION_PLAN))


def float_xy_defect(msg: Any) -> int | None:
    """For a MISSION_ITEM: 5 if its x, 6 if its y cannot be stored as MISSION_ITEM_INT."""
    x, y = MissionItem.int_xy_from_float(msg.frame, msg.x, msg.y)
    if x is None:
        return 5
    if y is None:
        return 6
    return None


def request_message(seq: int, mission_type: MissionType, target: tuple[int, int], *,
                    as_int: bool = True) -> Any:
    ts, tc = target
    cls = _d.MAVLink_mission_request_int_message if as_int else _d.MAVLink_mission_request_message
    return cls(ts, tc, seq, int(mission_type))


def count_message(count: int, mission_type: MissionType, target: tuple[int, int],
                  opaque_id: int = 0) -> Any:
    ts, tc = target
    return _d.MAVLink_mission_count_message(ts, tc, count, int(mission_type), opaque_id)


def ack_message(result: int, mission_type: MissionType | int, target: tuple[int, int],
                opaque_id: int = 0) -> Any:
    ts, tc = target
    return _d.MAVLink_mission_ack_message(ts, tc, int(result), int(mission_type), opaque_id)


def request_list_message(mission_type: MissionType, target: tuple[int, int]) -> Any:
    return _d.MAVLink_mission_request_list_message(target[0], target[1], int(mission_type))


def clear_all_message(mission_type: MissionType, target: tuple[int, int]) -> Any:
    return _d.MAVLink_mission_clear_all_message(target[0], target[1], int(mission_type))


def set_current_message(seq: int, target: tuple[int, int]) -> Any:
    return _d.MAVLink_mission_set_current_message(target[0], target[1], seq)


# --- presence: who is a GCS and who a vehicle ------------------------------------------------
HEARTBEAT_PERIOD = 1.0      # s between a ground station's HEARTBEATs


def gcs_heartbeat_message() -> Any:
    """The HEARTBEAT a ground station sends: MAV_TYPE_GCS, no autopilot, MAV_STATE_ACTIVE."""
    return _d.MAVLink_heartbeat_message(_d.MAV_TYPE_GCS, _d.MAV_AUTOPILOT_INVALID, 0, 0, _d.MAV_STATE_ACTIVE, 3)


def is_vehicle_heartbeat(msg: Any) -> bool:
    """A HEARTBEAT that names an autopilot and is not a GCS's: the target to discover."""
    return msg._type == "HEARTBEAT" and msg.type != _d.MAV_TYPE_GCS and msg.autopilot != _d.MAV_AUTOPILOT_INVALID


def command_long_message(command: int, target: tuple[int, int], *params: float) -> Any:
    """COMMAND_LONG `command` to `target` (first transmission), params 1..7; missing ones 0."""
    if len(params) > 7:
        raise ValueError(f"COMMAND_LONG has 7 params, got {len(params)}")
    return _d.MAVLink_command_long_message(target[0], target[1], int(command), 0,
                                          *params, *([0.0] * (7 - len(params))))


def set_current_command(seq: int, target: tuple[int, int]) -> Any:
    """COMMAND_LONG MAV_CMD_DO_SET_MISSION_CURRENT (param1 = seq, param2 = 0: no reset)."""
    return command_long_message(Cmd.DO_SET_MISSION_CURRENT, target, float(seq))


def current_message(seq: int, total: int, state: int, mode: int, ids: tuple[int, int, int]) -> Any:
    return _d.MAVLink_mission_current_message(seq, total, state, mode, *ids)


def item_reached_message(seq: int) -> Any:
    return _d.MAVLink_mission_item_reached_message(seq)


def statustext_message(severity: int, text: str) -> Any:
    return _d.MAVLink_statustext_message(severity, text.encode()[:50], 0, 0)


def command_ack_message(command: int, result: int, target: tuple[int, int]) -> Any:
    return _d.MAVLink_command_ack_message(command, result, 0, 0, target[0], target[1])

