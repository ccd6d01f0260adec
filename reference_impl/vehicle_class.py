"""What kind of flying (or driving) a MAV_TYPE stands for: one shared classification.

The vehicle's flight model and the suite's flight procedure both need to know how a vehicle
gets into the air and out of it (a multicopter climbs straight up and hovers, a fixed-wing
needs forward speed and a landing approach, a VTOL does both, a ground vehicle never leaves
the ground), not which of the fifty MAV_TYPEs of common.xml it is. Values are the
upstream MAV_TYPE entries (our dialect carries the whole enum).
"""

from __future__ import annotations

from enum import Enum

from .wire.dialect import mavlink as _d


class VehicleClass(Enum):
    MULTICOPTER = "multicopter"
    FIXED_WING = "fixed-wing"
    VTOL = "vtol"
    GROUND = "ground"
    OTHER = "other"


# Rotorcraft that hover (a helicopter and a coaxial too: they take off and land vertically).
_MULTICOPTER = frozenset({
    _d.MAV_TYPE_QUADROTOR, _d.MAV_TYPE_COAXIAL, _d.MAV_TYPE_HELICOPTER, _d.MAV_TYPE_HEXAROTOR,
    _d.MAV_TYPE_OCTOROTOR, _d.MAV_TYPE_TRICOPTER, _d.MAV_TYPE_DODECAROTOR, _d.MAV_TYPE_DECAROTOR,
    _d.MAV_TYPE_GENERIC_MULTIROTOR,
})
# Forward flight only, no hover: a flapping wing flies like a plane for take-off, loiter and landing.
_FIXED_WING = frozenset({_d.MAV_TYPE_FIXED_WING, _d.MAV_TYPE_FLAPPING_WING})
_VTOL = frozenset({
    _d.MAV_TYPE_VTOL_TAILSITTER_DUOROTOR, _d.MAV_TYPE_VTOL_TAILSITTER_QUADROTOR, _d.MAV_TYPE_VTOL_TILTROTOR,
    _d.MAV_TYPE_VTOL_FIXEDROTOR, _d.MAV_TYPE_VTOL_TAILSITTER, _d.MAV_TYPE_VTOL_TILTWING,
    _d.MAV_TYPE_VTOL_RESERVED5, _d.MAV_TYPE_VTOL_GYRODYNE,
})
# Never leaves the ground (or the water surface).
_GROUND = frozenset({_d.MAV_TYPE_GROUND_ROVER, _d.MAV_TYPE_SURFACE_BOAT, _d.MAV_TYPE_GROUND_QUADRUPED})


def vehicle_class(mav_type: int | None) -> VehicleClass:
    """The class of a HEARTBEAT.type (MAV_TYPE); OTHER for everything that is no vehicle the
    mission flight knows (airships, balloons, rockets, submarines, kites, gimbals, GCSs, ...)."""
    if mav_type in _MULTICOPTER:
        return VehicleClass.MULTICOPTER
    if mav_type in _FIXED_WING:
        return VehicleClass.FIXED_WING
    if mav_type in _VTOL:
        return VehicleClass.VTOL
    if mav_type in _GROUND:
        return VehicleClass.GROUND
    return VehicleClass.OTHER


def type_name(mav_type: int | None) -> str:
    """MAV_TYPE_X's X for a report, or the number as given."""
    entry = _d.enums.get("MAV_TYPE", {}).get(mav_type) if mav_type is not None else None
    return entry.name.removeprefix("MAV_TYPE_") if entry is not None else str(mav_type)
