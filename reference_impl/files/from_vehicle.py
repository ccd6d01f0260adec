"""What a download knows about the vehicle beside its plans, for the .plan it writes: the
vehicle's home and who it is.

QGroundControl fills a plan it loads from a vehicle the same way: `firmwareType` and
`vehicleType` are the HEARTBEAT's autopilot and type (Vehicle::firmwareType/vehicleType,
written by MissionController::save), the planned home is the vehicle's HOME_POSITION, and on
a firmware that keeps home in mission item 0 (ArduPilot; FirmwarePlugin::
sendHomePositionToVehicle) the item 0 of the download unless it is at 0, 0
(MissionController::_newMissionItemsAvailableFromVehicle). With neither, the writer falls
back to QGC's own guess (qgc_plan.fallback_home).
"""

from __future__ import annotations

from typing import Any, Iterable

from mavconform.reference_impl.files.plan import MissionSettings
from mavconform.reference_impl.files.qgc_json import Home
from mavconform.reference_impl.mission.items import GLOBAL_FRAMES, MissionType

ITEM_MESSAGES = {"MISSION_ITEM_INT": 1e7, "MISSION_ITEM": 1.0}   # x/y scale to degrees


def settings_from_heartbeat(heartbeat: Any | None, base: MissionSettings = MissionSettings()) -> MissionSettings:
    """`base` with the firmware and vehicle type of a HEARTBEAT (unchanged without one)."""
    if heartbeat is None:
        return base
    return MissionSettings(firmware_type=int(heartbeat.autopilot), vehicle_type=int(heartbeat.type),
                           cruise_speed=base.cruise_speed, hover_speed=base.hover_speed)


def home_from_messages(received: Iterable[Any], *, home_at_seq0: bool) -> Home | None:
    """The vehicle's home from the messages it sent (the last word wins): HOME_POSITION, else,
    where the vehicle keeps home at mission seq 0, that item as it was downloaded."""
    position = item0 = None
    for msg in received:
        kind = msg.get_type()
        if kind == "HOME_POSITION":
            position = (msg.latitude / 1e7, msg.longitude / 1e7, msg.altitude / 1000)
        elif (home_at_seq0 and kind in ITEM_MESSAGES and msg.seq == 0
              and getattr(msg, "mission_type", 0) == MissionType.MISSION and msg.frame in GLOBAL_FRAMES):
            scale = ITEM_MESSAGES[kind]
            item0 = (msg.x / scale, msg.y / scale, float(msg.z))
    if position is not None:
        return position
    if item0 is not None and (item0[0] != 0 or item0[1] != 0):   # QGC ignores a home at 0, 0
        return item0
    return None


def facts_from_gcs(gcs: Any) -> tuple[Home | None, MissionSettings]:
    """Home and settings for a plan the reference GCS (`GcsNode`) just downloaded."""
    home = home_from_messages(gcs.received, home_at_seq0=gcs.adaptations.home_at_seq0)
    return home, settings_from_heartbeat(gcs.target_heartbeat)
