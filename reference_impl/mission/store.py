"""The vehicle's stored plans: one per mission type, each replaced whole.

Stored separately and independently by type (seed 000, "Mission Types"). `commit` is the
only way a plan changes, so an upload that fails can never leave a mix of old and new
(seed 000: "A new mission should be fully uploaded and accepted before the old mission is
replaced").
Each commit produces a new `opaque_id` (upstream MISSION_ACK.opaque_id: it "must change
when there is any change to the on-vehicle plan type").
"""

from __future__ import annotations

import math
import struct
import zlib
from dataclasses import replace
from typing import Callable, Iterable, Sequence

from .ardupilot_commands import round_trip as ardupilot_round_trip
from .c_numbers import i32, u16
from .constants import Cmd
from .items import FRAME_MISSION, PLAIN_FRAME, PLAN_TYPES, MissionItem, MissionType, to_float32
from .px4_storage import px4_mission_item

_ITEM = struct.Struct("<HBHffffiifBBB")


def plan_digest(items: Sequence[MissionItem]) -> int:
    """CRC32 over the items' canonical bytes: equal plans, equal digest."""
    crc = 0
    for it in items:
        crc = zlib.crc32(_ITEM.pack(
            it.seq, it.frame, it.command, it.param1, it.param2, it.param3, it.param4,
            it.x, it.y, it.z, it.current, it.autocontinue, int(it.mission_type)), crc)
    return crc


class MissionStore:
    def __init__(self) -> None:
        self._plans: dict[MissionType, tuple[MissionItem, ...]] = {t: () for t in PLAN_TYPES}
        self._ids: dict[MissionType, int] = {t: 0 for t in PLAN_TYPES}
        self.version = 0   # bumped on every commit: a cheap "did anything change?"

    def items(self, mission_type: MissionType) -> tuple[MissionItem, ...]:
        return self._plans[mission_type]

    def count(self, mission_type: MissionType) -> int:
        return len(self._plans[mission_type])

    def opaque_id(self, mission_type: MissionType) -> int:
        """Id of the stored plan; 0 when none is stored (upstream: 0 = no plan loaded)."""
        return self._ids[mission_type]

    def commit(self, mission_type: MissionType, items: Iterable[MissionItem]) -> int:
        """Replace the plan whole; returns its new opaque id."""
        plan = tuple(items)
        self._plans[mission_type] = plan
        self.version += 1
        if not plan:
            self._ids[mission_type] = 0
            return 0
        new_id = plan_digest(plan) or 1
        self._ids[mission_type] = new_id
        return new_id

    def clear(self, mission_type: MissionType) -> None:
        self.commit(mission_type, ())

    def snapshot(self) -> dict[MissionType, tuple[MissionItem, ...]]:
        return dict(self._plans)


# --- storage forms (ServerBehaviour.item_storage) ------------------------------------------
_INT16 = 32767


def _whole(value: float, low: float, high: float) -> float:
    """Truncated toward zero and clamped, as a float-to-integer store does; NaN -> 0."""
    if value != value:
        return 0.0
    return float(min(high, max(low, math.trunc(value)))) if math.isfinite(value) else (
        high if value > 0 else low)


def _compact15(item: MissionItem) -> MissionItem:
    """A 15-byte command record (VARIANTS.md A13): what survives a round trip through it.

    Altitude is kept in whole centimetres (rally points: whole metres, int16); a waypoint
    keeps only its hold time, in whole seconds (0..65535); fence items keep param1 (vertex
    count or radius); *_INT frames come back as their plain frames. x/y are int32 already.
    """
    frame = PLAIN_FRAME.get(item.frame, item.frame)
    t = item.mission_type
    if t is MissionType.RALLY:
        return replace(item, frame=frame, param1=0.0, param2=0.0, param3=0.0, param4=0.0,
                       z=_whole(item.z, -_INT16 - 1, _INT16))
    if t is MissionType.FENCE:
        return replace(item, frame=frame, param2=0.0, param3=0.0, param4=0.0, z=0.0)
    z = item.z
    if math.isfinite(z):
        z = to_float32(math.trunc(to_float32(z) * 100) / 100)
    if item.command == Cmd.NAV_WAYPOINT:
        return replace(item, frame=frame, param1=_whole(item.param1, 0, 65535),
                       param2=0.0, param3=0.0, param4=0.0, z=z)
    return replace(item, frame=frame, z=z)


def _compact15_plane(item: MissionItem) -> MissionItem:
    """ArduPlane's build of the same record: a waypoint's 16-bit p1 holds its acceptance radius
    (param2) in the low byte and its pass-by distance (param3) in the high byte, each a whole
    number of metres, at most 255; the hold time (param1) and yaw (param4) are not kept
    (ArduPilot libraries/AP_Mission/AP_Mission.cpp mavlink_int_to_mission_cmd and
    mission_cmd_to_mavlink_int, the APM_BUILD_ArduPlane branches for MAV_CMD_NAV_WAYPOINT).
    Everything else as `_compact15`."""
    kept = _compact15(item)
    if item.command != Cmd.NAV_WAYPOINT or item.mission_type is not MissionType.MISSION:
        return kept
    return replace(kept, param1=0.0, param2=_whole(item.param2, 0, 255), param3=_whole(item.param3, 0, 255),
                   param4=0.0)


def _ardupilot(item: MissionItem) -> MissionItem:
    """ArduCopter's and ArduRover's record read back (VARIANTS.md A13): a mission item through
    AP_Mission's per-command packing (ardupilot_commands.py: uint8/uint16 params, flags, whole
    centimetres, a plain frame; a command without a location comes back in frame 0 with x, y, z
    0), rally items as `_compact15`, fence items rebuilt from their position and radius or
    vertex count (GCS_MAVLink/MissionItemProtocol_Fence.cpp L15-78: frame GLOBAL, no altitude,
    autocontinue 0). An item ArduCopter would refuse (a profile may take more) is kept as
    `_compact15` keeps it."""
    if item.mission_type is MissionType.FENCE:
        return replace(_compact15(item), frame=0, autocontinue=0)
    if item.mission_type is not MissionType.MISSION:
        return _compact15(item)
    try:
        return replace(ardupilot_round_trip(item), seq=item.seq, current=item.current)
    except ValueError:
        return _compact15(item)


def _ardupilot_plane(item: MissionItem) -> MissionItem:
    """ArduPlane's build of the same (VARIANTS.md A31): a waypoint's 16-bit p1 holds its
    acceptance radius (param2) in the low byte and its pass-by distance (param3) in the high
    byte, each `MIN(0xFF, (uint16_t)param)` (-1 comes back 255), and no hold time, which is not
    checked (AP_Mission.cpp L1091-1100 / L1630-1634, the APM_BUILD_ArduPlane branches)."""
    if item.mission_type is not MissionType.MISSION or int(item.command) != Cmd.NAV_WAYPOINT:
        return _ardupilot(item)
    kept = _ardupilot(replace(item, param1=0.0))
    return replace(kept, param1=0.0, param2=float(min(0xFF, u16(item.param2))),
                   param3=float(min(0xFF, u16(item.param3))), param4=0.0)


def _float32_cm(item: MissionItem) -> MissionItem:
    """A waypoint record filled from MISSION_ITEM in float32 arithmetic and read back the same
    way (INAV 9.1 src/main/telemetry/mavlink.c:1124-1131 and 1191-1201): latitude and longitude
    `(int32)(x * 1e7f)`, altitude `(int32)(z * 100.0f)` whole cm, params 1-4 dropped, current 0,
    autocontinue 1; an RTL comes back in MAV_FRAME_MISSION (x/y then plain numbers, as a GCS
    reads them there), any other item in frame 3. Fence and rally items are left alone."""
    if item.mission_type is not MissionType.MISSION:
        return item
    fx, fy = item.float_xy()
    lat, lon = i32(to_float32(fx * 1e7)), i32(to_float32(fy * 1e7))
    alt = i32(to_float32(to_float32(item.z) * 100.0))
    frame = FRAME_MISSION if item.command == Cmd.NAV_RETURN_TO_LAUNCH else 3
    x, y = MissionItem.int_xy_from_float(frame, to_float32(to_float32(lat) / 1e7), to_float32(to_float32(lon) / 1e7))
    return replace(item, frame=frame, param1=0.0, param2=0.0, param3=0.0, param4=0.0, x=x or 0, y=y or 0,
                   z=to_float32(to_float32(alt) / 100.0), current=0, autocontinue=1)


STORAGE_FORMS: dict[str, Callable[[MissionItem], MissionItem]] = {
    "exact": lambda item: item,
    "compact15": _compact15,
    "compact15-plane": _compact15_plane,
    "float32-cm": _float32_cm,
    "px4": px4_mission_item,
    "ardupilot": _ardupilot,
    "ardupilot-plane": _ardupilot_plane,
}
