"""What PX4 keeps of a mission item: its `mission_item_s` record and the way back (P28).

PX4 v1.16.0 (src/modules/mavlink/mavlink_mission.cpp) parses an uploaded item into the
navigator's `mission_item_s` (src/modules/navigator/navigation.h:136-188) and builds the
download from that record, so a param the record has no field for comes back 0, and one it
keeps as a flag comes back 0 or 1:

- global frames (parse_mavlink_mission_item L1432-1528, format_mavlink_mission_item
  L1718-1815): params 1-4 come back 0 except, per command, the fields the record holds: a
  waypoint its hold time, acceptance radius and yaw; NAV_LOITER_UNLIM its radius and yaw;
  NAV_LOITER_TIME its time, radius and two flags (param2 > 0, param4 > 0); NAV_LAND its
  precision (param2, a uint16) and yaw; NAV_TAKEOFF, NAV_VTOL_TAKEOFF and NAV_VTOL_LAND their
  yaw; NAV_LOITER_TO_ALT a flag (param1 > 0), its radius and a flag (param4 > 0). A yaw is
  kept in radians wrapped to [0, 2 pi) (`wrap_2pi(radians(param4))`, float32) and read back in
  degrees: -12.375 comes back 347.625. NAV_ROI is stored as DO_SET_ROI (201);
- MAV_FRAME_MISSION (L1539-1630, L1666-1700): params 1-7 kept in `params[7]`, float32 each, so
  x and y pass through a float (INT32_MAX comes back as INT32_MIN: `round(2147483648.0f)`
  overflows the int32); DO_JUMP keeps its target as an int16 and its repeat count as a uint16
  (C conversions: 7.5 -> 7, -1 -> 65535 on x86-64); NAV_ROI is stored as DO_SET_ROI.
Fence and rally items are left alone here (their record is another: the frame matrix's cells).
"""

from __future__ import annotations

import math
from dataclasses import replace

from .c_numbers import i16, i32, u16
from .items import MissionItem, MissionType, to_float32

GLOBAL = (0, 3, 5, 6)
MISSION_FRAME = 2
NAV_ROI, DO_SET_ROI, DO_JUMP = 80, 201, 177
_PI = to_float32(math.pi)
_TWO_PI = to_float32(2 * math.pi)
_DEG2RAD = to_float32(_PI / to_float32(180.0))
_RAD2DEG = to_float32(to_float32(180.0) / _PI)


def _wrap_2pi(x: float) -> float:
    """matrix::wrap(x, 0, 2 pi) in float32 (PX4's src/lib/matrix/matrix/helper_functions.hpp)."""
    if not math.isfinite(x) or 0.0 <= x < _TWO_PI:
        return x
    inv = to_float32(1.0 / _TWO_PI)
    wraps = math.floor(to_float32(x * inv))
    return to_float32(x - to_float32(_TWO_PI * wraps))


def yaw_round_trip(degrees: float) -> float:
    """A yaw param through `wrap_2pi(math::radians(p))` and back through `math::degrees`."""
    if degrees != degrees:
        return degrees
    return to_float32(_wrap_2pi(to_float32(to_float32(degrees) * _DEG2RAD)) * _RAD2DEG)


def _flag(v: float) -> float:
    return 1.0 if v > 0 else 0.0      # NaN > 0 is false


def _c_round_int32(v: float) -> int:
    """`item_int->x = round(params[4])` of a float32 param: out of int32 range gives INT32_MIN."""
    return i32(float(math.floor(v + 0.5) if v >= 0 else math.ceil(v - 0.5)))


# command -> (param1..param4 as the download gives them), from params (p1, p2, p3, p4)
_GLOBAL_KEPT = {
    16: lambda p: (p[0], p[1], 0.0, yaw_round_trip(p[3])),                   # NAV_WAYPOINT
    17: lambda p: (0.0, 0.0, p[2], yaw_round_trip(p[3])),                    # NAV_LOITER_UNLIM
    19: lambda p: (p[0], _flag(p[1]), p[2], _flag(p[3])),                    # NAV_LOITER_TIME
    21: lambda p: (0.0, float(u16(p[1])), 0.0, yaw_round_trip(p[3])),  # NAV_LAND
    22: lambda p: (0.0, 0.0, 0.0, yaw_round_trip(p[3])),                     # NAV_TAKEOFF
    31: lambda p: (_flag(p[0]), p[1], 0.0, _flag(p[3])),                     # NAV_LOITER_TO_ALT
    84: lambda p: (0.0, 0.0, 0.0, yaw_round_trip(p[3])),                     # NAV_VTOL_TAKEOFF
    85: lambda p: (0.0, 0.0, 0.0, yaw_round_trip(p[3])),                     # NAV_VTOL_LAND
}


def px4_mission_item(item: MissionItem) -> MissionItem:
    """The item as PX4 v1.16 returns it after storing it (see the module's text)."""
    if item.mission_type is not MissionType.MISSION:
        return item
    command = DO_SET_ROI if int(item.command) == NAV_ROI else int(item.command)
    p = (item.param1, item.param2, item.param3, item.param4)
    if item.frame in GLOBAL:
        kept = _GLOBAL_KEPT.get(int(item.command), lambda _: (0.0, 0.0, 0.0, 0.0))(p)
        return replace(item, command=command, param1=kept[0], param2=kept[1], param3=kept[2], param4=kept[3])
    if item.frame == MISSION_FRAME:
        p1, p2 = item.param1, item.param2
        if command == DO_JUMP:
            p1, p2 = float(i16(p1)), float(u16(p2))
        return replace(item, command=command, param1=p1, param2=p2,
                       x=_c_round_int32(to_float32(float(item.x))), y=_c_round_int32(to_float32(float(item.y))))
    return item
