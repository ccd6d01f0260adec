"""What ArduCopter does to one MISSION_ITEM_INT mission item on upload and download.

A sans-IO model of ArduPilot master 531699d652 built as ArduCopter (SITL, x86-64 g++ -O3
-fsingle-precision-constant), written from a reading of (line numbers at that commit):

* libraries/AP_Mission/AP_Mission.cpp
  - sanity_check_params, L1013-1060: NaN allowed only in the params of a per-command mask,
    +-inf refused in any of params 1-4;
  - mavlink_int_to_mission_cmd, L1064-1524: the per-command switch packing params into the
    Mission_Command (uint16 p1 + the 12-byte Content union), L1081-1472 (the APM_BUILD
    ArduCopter branches: NAV_WAYPOINT L1102-1107, NAV_SPLINE_WAYPOINT L1183-1188), then the
    location block L1476-1521 (lat/lng/alt checks, alt in int32 cm, frame -> alt flags);
  - stored_in_location, L897-929; read/write_cmd_to_storage, L818-895 / L935-998 (alt kept
    in 24 bits; 16-bit command ids keep 10 content bytes: every such struct here fits);
  - mission_cmd_to_mavlink_int, L1613-2037: the unpacking on download (packet zeroed,
    autocontinue 1, frame 0 unless a location sets 3 or 10, L1998-2031).
* libraries/AP_Mission/AP_Mission.h L66-303: the field types of the Content structs.
* libraries/GCS_MAVLink/MissionItemProtocol_Waypoints.cpp L31-51 and L97-118: DO_JUMP's
  target check after the conversion (MAV_MISSION_ERROR).

C conversions are emulated as that build does them on x86-64 (checked with a g++ -O3 probe):
float -> (u)int8/(u)int16/int32 is cvttss2si into 32 bits (truncate; NaN or out of range ->
INT32_MIN) then the low bits; float -> uint32 or an unsigned enum goes through 64 bits; float
arithmetic is float32 (every literal is a float under -fsingle-precision-constant).
"""

from __future__ import annotations

import math
import struct
from typing import Callable, Sequence

from mavconform.reference_impl.mission.c_numbers import Number, i8, i16, i32, u8, u16, u16_via64, u32, wrap
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType, to_float32

__all__ = ["ACCEPTED_COMMANDS", "LOCATION_COMMANDS", "refusal", "round_trip"]

Slots = tuple[float, float, float, float, int, int, float]  # param1-4, x, y, z on download

# --- C conversions --------------------------------------------------------------------------

_F32 = struct.Struct("<f")
_U32 = struct.Struct("<I")
FLT_EPSILON = 2.0 ** -23
_CENTI = to_float32(0.01)  # 0.01f


def f32(value: Number) -> float:
    return to_float32(float(value))


def fmul(a: Number, b: Number) -> float:
    """a * b in float32 (exact in double, so one rounding gives the float32 product)."""
    return to_float32(f32(a) * f32(b))


def is_negative(value: float) -> bool:  # AP_Math.h L76-79
    return value <= -FLT_EPSILON


def _f16_set(value: float) -> int:
    """Float16_t::set (AP_Common/float16.cpp L32-70), bit for bit."""
    u = _U32.unpack(_F32.pack(value))[0]
    sign, u = u & 0x80000000, u & 0x7FFFFFFF
    if u >= 0x7F800000:
        v16 = 0x7FFF if u > 0x7F800000 else 0x7C00
    else:
        u &= 0xFFFFF000
        f = fmul(_F32.unpack(_U32.pack(u))[0], _F32.unpack(_U32.pack(15 << 23))[0])
        u = (_U32.unpack(_F32.pack(f))[0] - 0xFFFFF000) & 0xFFFFFFFF
        v16 = min(u, 31 << 23) >> 13
    return (v16 | (sign >> 16)) & 0xFFFF


def _f16_get(v16: int) -> float:
    """Float16_t::get (AP_Common/float16.cpp L12-30)."""
    f = fmul(_F32.unpack(_U32.pack((v16 & 0x7FFF) << 13))[0], 2.0 ** 112)
    u = _U32.unpack(_F32.pack(f))[0]
    if f >= 2.0 ** 16:
        u |= 255 << 23
    u |= (v16 & 0x8000) << 16
    return _F32.unpack(_U32.pack(u))[0]


def _f16(value: float) -> float:
    return _f16_get(_f16_set(value))


# --- the per-command table --------------------------------------------------------------------

# How each of param1-4, x, y, z is stored (and so comes back): a C conversion, or None for a
# field the command drops (0 on download). Storage place (p1 or Content) does not matter for a
# round trip, only the type. Lines: mavlink_int_to_mission_cmd case / mission_cmd_to_mavlink_int case.
Conv = Callable[[Number], Number]
DROP = None
STORE: dict[int, tuple[Conv | None, ...]] = {
    16: (u16,),                      # NAV_WAYPOINT: copter delay, L1102-1107 / L1630-1640
    20: (),                          # NAV_RETURN_TO_LAUNCH L1150 / L1674
    22: (u16,),                      # NAV_TAKEOFF L1160 / L1682
    30: (u16,),                      # NAV_CONTINUE_AND_CHANGE_ALT L1164 / L1686
    82: (u16,),                      # NAV_SPLINE_WAYPOINT (non-Plane) L1182-1188 / L1706
    83: (f32, f32, u8),              # NAV_ALTITUDE_WAIT L1341 / L1869
    84: (),                          # NAV_VTOL_TAKEOFF L1347 / L1875
    85: (u16_via64,),                # NAV_VTOL_LAND (enum cast) L1350 / L1878
    92: (u16,),                      # NAV_GUIDED_ENABLE L1190 / L1710
    93: (f32, i8, i8, i8),           # NAV_DELAY L1194 / L1714
    112: (f32,),                     # CONDITION_DELAY L1201 / L1721
    114: (f32,),                     # CONDITION_DISTANCE L1205 / L1725
    115: (f32, f32, i8, u8),         # CONDITION_YAW L1209 / L1729
    177: (u16, i16),                 # DO_JUMP L1216 / L1736
    178: (u8, f32, f32),             # DO_CHANGE_SPEED L1226 / L1746
    179: (u16,),                     # DO_SET_HOME L1232 / L1752
    181: (u8, u8),                   # DO_SET_RELAY L1236 / L1756
    182: (u8, i16, f32),             # DO_REPEAT_RELAY L1241 / L1761
    183: (u8, u16),                  # DO_SET_SERVO L1247 / L1767
    184: (u8, u16, i16, f32),        # DO_REPEAT_SERVO L1252 / L1772
    188: (), 189: (), 191: (),       # DO_RETURN_PATH_START, DO_LAND_START, DO_GO_AROUND L1259-1264
    193: (u16,),                     # DO_PAUSE_CONTINUE L1422 / L1944
    194: (u16,),                     # DO_SET_REVERSE L1358 / L1865
    195: (u16,), 197: (u16,),        # DO_SET_ROI_LOCATION / _NONE L1266 / L1786
    201: (u16,),                     # DO_SET_ROI L1271 / L1791
    202: (u8, u16, u8, u16, u8, u8, f32),  # DO_DIGICAM_CONFIGURE L1275 / L1795
    203: (u8, u8, i8, u8, u8, u8),   # DO_DIGICAM_CONTROL L1285 / L1805
    206: (f32, DROP, u8),            # DO_SET_CAM_TRIGG_DIST L1301 / L1821
    207: (u16,), 208: (u16,), 210: (u16,), 212: (u16,),  # FENCE_ENABLE, PARACHUTE, INVERTED, AUTOTUNE
    211: (u8, u8),                   # DO_GRIPPER L1324 / L1848
    213: (f32, f32, u8),             # NAV_SET_YAW_SPEED L1375 / L1901
    215: (u16,), 216: (u16,),        # DO_SET_RESUME_REPEAT_DIST, DO_SPRAYER L1388-1394
    217: (u16, f32, f32, f32),       # DO_SEND_SCRIPT_MESSAGE L1396 / L1918
    218: (u16, u8),                  # DO_AUX_FUNCTION L1310 / L1838
    222: (u16, f32, f32, f32),       # DO_GUIDED_LIMITS L1330 / L1854
    531: (u8, f32), 532: (u8, f32),  # SET_CAMERA_ZOOM / _FOCUS L1446-1454 / L1968-1976
    534: (u8, u8, u8),               # SET_CAMERA_SOURCE L1456 / L1978
    600: (u16,),                     # JUMP_TAG L1222 / L1742
    601: (u16, i16),                 # DO_JUMP_TAG L1217 / L1737
    1000: (i8, i16, i8, i8, u8, DROP, u8),  # DO_GIMBAL_MANAGER_PITCHYAW L1426 / L1948
    2000: (u8, f32, u16, u16),       # IMAGE_START_CAPTURE L1435 / L1957
    2001: (u16,),                    # IMAGE_STOP_CAPTURE L1442 / L1964
    2500: (u8,), 2501: (u8,),        # VIDEO_START/STOP_CAPTURE L1462-1468 / L1984-1990
    3000: (u8,),                     # DO_VTOL_TRANSITION L1354 / L1882
    42600: (u8, u8, f32, f32),       # DO_WINCH L1381 / L1907
}


def _sign(negative: bool, value: float) -> float:
    return -value if negative else value


def _loiter_unlim(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1112 / L1642
    r = u16(abs(p[2]))
    return (0.0, 0.0, _sign(p[2] < 0, float(r)), 0.0, 0, 0, 0.0)


def _loiter_turns(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1117-1142 / L1649-1662
    turns, bits = p[0], 0
    if 0 < turns < 1:
        turns, bits = fmul(turns, 256.0), bits | 2
    p1 = u16(turns if turns < 255 else 255.0)  # MIN(255, float) is a float
    radius = abs(p[2])
    if radius <= 255:
        radius_m = u8(radius)
    else:
        tenth = fmul(radius, to_float32(0.1))
        radius_m, bits = u8(tenth if tenth < 255 else 255.0), bits | 1
    p1 = (p1 | (radius_m << 8)) & 0xFFFF
    param1, param3 = float(p1 & 0xFF), _sign(p[2] < 0, float(p1 >> 8))
    if bits & 1:
        param3 = fmul(param3, 10)
    if bits & 2:
        param1 = to_float32(param1 / 256.0)
    return (param1, 0.0, param3, float(p[3] > 0), 0, 0, 0.0)


def _loiter_time(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1144 / L1664
    return (float(u16(p[0])), 0.0, -1.0 if p[2] < 0 else 1.0, float(p[3] > 0), 0, 0, 0.0)


def _land(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1153-1158 / L1677-1680
    ccw = not math.isnan(p[3]) and is_negative(p[3])
    return (float(u16(p[0])), 0.0, 0.0, -1.0 if ccw else 1.0, 0, 0, 0.0)


def _loiter_to_alt(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1171 / L1693
    return (0.0, _sign(p[1] < 0, float(u16(abs(p[1])))), 0.0, float(p[3] > 0), 0, 0, 0.0)


def _arc_waypoint(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1177 / L1701
    return (fmul(u16(abs(p[0])), -1.0 if is_negative(p[0]) else 1.0), 0.0, 0.0, 0.0, 0, 0, 0.0)


def _payload_place(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1370 / L1896
    return (fmul(u16(fmul(p[0], 100)), _CENTI), 0.0, 0.0, 0.0, 0, 0, 0.0)


def _mount_control(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1294 / L1814-1819
    return (p[0], p[1], p[2], 0.0, 0, 0, 2.0)  # z = MAV_MOUNT_MODE_MAVLINK_TARGETING


def _engine_control(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1362 / L1886
    height_cm = u16(fmul(p[2], 100))
    allow = u32(p[3]) & 1  # ENGINE_CONTROL_OPTIONS_ALLOW_START_WHILE_DISARMED
    return (float(p[0] > 0), float(p[1] > 0), fmul(height_cm, _CENTI), float(allow), 0, 0, 0.0)


def _script_time(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1404-1411 / L1926-1933
    return (float(u8(p[0])), float(u8(p[1])), _f16(p[2]), _f16(p[3]), i16(x), i16(y), 0.0)


def _attitude_time(p: Sequence[float], x: int, y: int, z: float) -> Slots:  # L1414-1420 / L1936
    return (float(u16(min(max(p[0], 0.0), 65535.0))),
            float(i16(p[1] if abs(p[1]) <= 180 else 0.0)),
            float(i8(p[2] if abs(p[2]) <= 90 else 0.0)),
            float(i16(p[3] if -180 <= p[3] <= 360 else 0.0)), i16(x), 0, 0.0)


SPECIAL: dict[int, Callable[[Sequence[float], int, int, float], Slots]] = {
    17: _loiter_unlim, 18: _loiter_turns, 19: _loiter_time, 21: _land, 31: _loiter_to_alt,
    36: _arc_waypoint, 94: _payload_place, 205: _mount_control, 223: _engine_control,  # 205: f32 x3
    42702: _script_time, 42703: _attitude_time,
}
ACCEPTED_COMMANDS = frozenset(STORE) | frozenset(SPECIAL)

# stored_in_location (L897-929), less the fence/rally commands the mission switch refuses.
LOCATION_COMMANDS = frozenset({16, 17, 18, 19, 21, 22, 30, 31, 36, 82, 84, 85, 92, 94, 179,
                               188, 189, 191, 195, 201})
# sanity_check_params (L1013-1039): the params (1-4) that may be NaN; all others may not.
NAN_ALLOWED: dict[int, frozenset[int]] = {
    16: frozenset({4}), 17: frozenset({4}), 21: frozenset({4}), 22: frozenset({4}),
    36: frozenset({2, 3, 4}), 84: frozenset({4}), 85: frozenset({3, 4}),
}
# The location frame switch (L1494-1520) -> the frame mission_cmd_to_mavlink_int reports
# (L2003-2021): absolute -> GLOBAL, relative -> GLOBAL_RELATIVE_ALT, terrain -> TERRAIN_ALT.
DOWNLOAD_FRAME = {2: 0, 0: 0, 5: 0, 3: 3, 6: 3, 10: 10, 11: 10}
LOCATION_ALT_MAX_M = 83000  # AP_Common/Location.h L5
_PARAM_RESULT = (MissionResult.INVALID_PARAM1, MissionResult.INVALID_PARAM2,
                 MissionResult.INVALID_PARAM3, MissionResult.INVALID_PARAM4)


def _params(item: MissionItem) -> tuple[float, float, float, float]:
    return (f32(item.param1), f32(item.param2), f32(item.param3), f32(item.param4))


def _check_lat(lat: int) -> bool:  # AP_Math/location.cpp L47-50: labs(lat) <= 90*1e7f, in float
    return f32(abs(lat)) <= 9e8


def _check_lng(lng: int) -> bool:  # L51-54
    return f32(abs(lng)) <= 1.8e9


def refusal(item: MissionItem, *, mission_count: int | None = None) -> MissionResult | None:
    """The MISSION_ACK type ArduCopter refuses `item` with, or None if it stores it.

    `mission_count` is the upload's MISSION_COUNT (default: `item` is its last item); only
    DO_JUMP's target check depends on it.
    """
    if item.mission_type is not MissionType.MISSION:
        raise ValueError("this models the mission plan type only")
    p = _params(item)
    allowed = NAN_ALLOWED.get(item.command, frozenset())
    for n, value in enumerate(p, start=1):  # sanity_check_params L1041-1059
        if math.isinf(value) or (math.isnan(value) and n not in allowed):
            return _PARAM_RESULT[n - 1]
    if item.command in (0, 1):  # L1081-1083: reserved for 16-bit ids
        return MissionResult.INVALID
    if item.command not in ACCEPTED_COMMANDS:  # L1470-1472
        return MissionResult.UNSUPPORTED
    if item.command == 16 and not 0 <= p[0] <= 65535:  # L1104-1106 (copter branch)
        return MissionResult.INVALID_PARAM1
    if item.command in LOCATION_COMMANDS:  # L1476-1521
        if not _check_lat(item.x):
            return MissionResult.INVALID_PARAM5_X
        if not _check_lng(item.y):
            return MissionResult.INVALID_PARAM6_Y
        z = f32(item.z)
        if math.isnan(z) or abs(z) >= LOCATION_ALT_MAX_M:
            return MissionResult.INVALID_PARAM7
        if item.frame not in DOWNLOAD_FRAME:
            return MissionResult.UNSUPPORTED_FRAME
    if item.command == 177:  # MissionItemProtocol_Waypoints.cpp L40-44 / L107-111
        # item_count() <= MISSION_COUNT after truncate(), so the check reduces to the count.
        request_last = (item.seq + 1 if mission_count is None else mission_count) - 1
        target = u16(p[0])
        if target == 0 or target > request_last:
            return MissionResult.ERROR
    return None


def round_trip(item: MissionItem) -> MissionItem:
    """The item a MISSION_ITEM_INT download returns for an accepted `item` (seq >= 1)."""
    result = refusal(item)
    if result is not None:
        raise ValueError(f"ArduCopter refuses this item: {result.name}")
    p, cmd = _params(item), item.command
    if cmd in SPECIAL:
        slots = list(SPECIAL[cmd](p, item.x, item.y, f32(item.z)))
    else:
        sources: tuple[Number, ...] = (*p, item.x, item.y, f32(item.z))
        slots = [0.0, 0.0, 0.0, 0.0, 0, 0, 0.0]
        for i, conv in enumerate(STORE[cmd]):
            if conv is not None:
                slots[i] = conv(sources[i])
    frame = 0
    if cmd in LOCATION_COMMANDS:
        alt_cm = wrap(i32(fmul(item.z, 100)), 24, signed=True)  # L1491, 24-bit storage
        slots[4], slots[5] = item.x, item.y
        slots[6] = fmul(alt_cm, _CENTI)  # L2002
        frame = DOWNLOAD_FRAME[item.frame]
    params = [f32(v) for v in slots[:4]]
    return MissionItem(seq=item.seq, frame=frame, command=cmd, param1=params[0],
                       param2=params[1], param3=params[2], param4=params[3],
                       x=int(slots[4]), y=int(slots[5]), z=f32(slots[6]), current=0,
                       autocontinue=1, mission_type=MissionType.MISSION)
