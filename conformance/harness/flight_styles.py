"""How each autopilot flies each kind of vehicle: the suite's knowledge, as data with sources.

A flight for the progress clauses must be started the way the vehicle accepts and must end
with the vehicle on the ground and disarmed. Flight-mode numbers differ per autopilot *and*
per vehicle type (ArduCopter's GUIDED is 4, which is ACRO on ArduPlane), so a style names
every mode it uses with the number the HEARTBEAT will show, and the suite confirms that
number before it arms. Each style was flown on the autopilot's SITL (docs/real-targets.md).

- ArduCopter: GUIDED, arm, MAV_CMD_MISSION_START 0 0 (switches to AUTO; AUTO refuses arming,
  `ModeAuto::allows_arming`); its NAV_LAND lands and disarms it.
- ArduPlane: AUTO, arm: arming in AUTO flies the mission from its NAV_TAKEOFF; its NAV_LAND
  lands and disarms it ("Auto disarmed"). A DO_LAND_START item makes arming fail unless
  RTL_AUTOLAND is set, so plans have none.
- ArduRover: AUTO, arm (retried while "Need Position Estimate"): it drives the mission and
  then holds, still armed: the suite disarms it.
- PX4 (every airframe): AUTO.MISSION by MAV_CMD_DO_SET_MODE (1, 4, 4), arm: it flies the
  mission; after its landing item it disarms (COM_DISARM_LAND). Fixed-wing and VTOL
  airframes refuse a mission without a landing (MIS_TKO_LAND_REQ = 2).
- Any other autopilot: no mode step, MAV_CMD_MISSION_START 0 0 (common.xml's generic start),
  as the reference vehicle does; a generic landing (MAV_CMD_NAV_LAND) to end.
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.vehicle_class import VehicleClass
from mavconform.reference_impl.wire.dialect import mavlink as _d

ARDUPILOT = _d.MAV_AUTOPILOT_ARDUPILOTMEGA
PX4 = _d.MAV_AUTOPILOT_PX4
CUSTOM = float(_d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED)


@dataclass(frozen=True)
class Mode:
    """A flight mode: its name, the HEARTBEAT.custom_mode that shows it, and the
    MAV_CMD_DO_SET_MODE params that ask for it."""
    name: str
    custom_mode: int
    params: tuple[float, ...]
    source: str

    def __str__(self) -> str:
        return f"{self.name} ({self.custom_mode})"


def ardupilot_mode(name: str, number: int, source: str) -> Mode:
    """ArduPilot: param1 base_mode (custom enabled), param2 the mode number
    (libraries/GCS_MAVLink/GCS_Common.cpp GCS_MAVLINK::handle_command_do_set_mode)."""
    return Mode(name, number, (CUSTOM, float(number)), source)


def px4_mode(name: str, main: int, sub: int, source: str) -> Mode:
    """PX4: param2 main mode, param3 sub mode; custom_mode = main << 16 | sub << 24
    (src/modules/commander/Commander.cpp VEHICLE_CMD_DO_SET_MODE; px4_custom_mode.h)."""
    return Mode(name, main << 16 | sub << 24, (CUSTOM, float(main), float(sub)), source)


_COPTER = "ArduPilot ArduCopter/mode.h Mode::Number"
_PLANE = "ArduPilot ArduPlane/mode.h Mode::Number"
_ROVER = "ArduPilot Rover/mode.h Mode::Number"
_PX4 = "PX4 src/modules/commander/px4_custom_mode.h PX4_CUSTOM_MAIN_MODE_AUTO = 4, PX4_CUSTOM_SUB_MODE_AUTO_*"


@dataclass(frozen=True)
class FlightStyle:
    """How one autopilot flies one vehicle class's mission.

    `arm_in`: the mode set (and confirmed from the HEARTBEAT) before arming; None: no mode
    or arming step, MAV_CMD_MISSION_START alone. `start_after_arming`: send
    MAV_CMD_MISSION_START 0 0 once armed (else arming in `arm_in` starts the mission).
    `land`: the mode that brings a vehicle still flying down where it is (None: the
    generic MAV_CMD_NAV_LAND); `fixed_wing_landing`: it lands by flying the plan's own
    landing approach (set current to it, in `arm_in`); `stop`: a ground vehicle's mode to
    stop in before it is disarmed. `radius_params`: parameters read to size the legs, each
    (name, metres per unit), the first one answered wins per role (acceptance, loiter)."""
    name: str
    vehicle: VehicleClass
    arm_in: Mode | None
    start_after_arming: bool = False
    land: Mode | None = None
    fixed_wing_landing: bool = False
    stop: Mode | None = None
    acceptance_params: tuple[tuple[str, float], ...] = ()
    loiter_params: tuple[tuple[str, float], ...] = ()
    source: str = ""


_AP_COPTER = FlightStyle(
    "ArduCopter", VehicleClass.MULTICOPTER,
    arm_in=ardupilot_mode("GUIDED", 4, _COPTER), start_after_arming=True,
    land=ardupilot_mode("LAND", 9, _COPTER),
    acceptance_params=(("WP_RADIUS_M", 1.0), ("WPNAV_RADIUS", 0.01)),
    source="ArduCopter/GCS_MAVLink_Copter.cpp handle_MAV_CMD_MISSION_START (params 0, 0; sets AUTO, "
           "auto_armed); ArduCopter/mode.h ModeAuto::allows_arming (false)")
_AP_PLANE = FlightStyle(
    "ArduPlane", VehicleClass.FIXED_WING,
    arm_in=ardupilot_mode("AUTO", 10, _PLANE), fixed_wing_landing=True,
    acceptance_params=(("WP_RADIUS", 1.0),), loiter_params=(("WP_LOITER_RAD", 1.0),),
    source="ArduPlane: arming in AUTO flies the mission from its NAV_TAKEOFF (seen on SITL); "
           "AP_Arming_Plane refuses arming with DO_LAND_START unless RTL_AUTOLAND")
_AP_QUADPLANE = FlightStyle(
    "ArduPlane (QuadPlane)", VehicleClass.VTOL,
    arm_in=ardupilot_mode("AUTO", 10, _PLANE), land=ardupilot_mode("QLAND", 20, _PLANE),
    acceptance_params=(("WP_RADIUS", 1.0),), loiter_params=(("WP_LOITER_RAD", 1.0),),
    source="ArduPlane/mode.h (QLAND = 20); ArduPlane/GCS_MAVLink_Plane.cpp frame_type (QuadPlane: a VTOL MAV_TYPE)")
_AP_ROVER = FlightStyle(
    "ArduRover", VehicleClass.GROUND,
    arm_in=ardupilot_mode("AUTO", 10, _ROVER), stop=ardupilot_mode("HOLD", 4, _ROVER),
    acceptance_params=(("WP_RADIUS", 1.0),),
    source="Rover/mode.h (AUTO allows arming; RTL, SMART_RTL, INITIALISING do not); the mission ends "
           "in AUTO, armed (seen on SITL)")


def _px4(vehicle: VehicleClass, name: str, *, fixed_wing: bool = False) -> FlightStyle:
    return FlightStyle(
        name, vehicle, arm_in=px4_mode("AUTO.MISSION", 4, 4, _PX4),
        land=None if fixed_wing or vehicle is VehicleClass.GROUND else px4_mode("AUTO.LAND", 4, 6, _PX4),
        fixed_wing_landing=fixed_wing,
        stop=px4_mode("AUTO.LOITER", 4, 3, _PX4) if vehicle is VehicleClass.GROUND else None,
        acceptance_params=(("NAV_ACC_RAD", 1.0),), loiter_params=(("NAV_LOITER_RAD", 1.0),),
        source="PX4: arming in AUTO.MISSION flies the mission (seen on SIH); "
               "src/modules/navigator/MissionFeasibility/FeasibilityChecker.cpp checkTakeoffLandAvailable "
               "(MIS_TKO_LAND_REQ = 2 on fixed-wing and VTOL airframes: a landing is required)")


STYLES: dict[tuple[int, VehicleClass], FlightStyle] = {
    (ARDUPILOT, VehicleClass.MULTICOPTER): _AP_COPTER,
    (ARDUPILOT, VehicleClass.FIXED_WING): _AP_PLANE,
    (ARDUPILOT, VehicleClass.VTOL): _AP_QUADPLANE,
    (ARDUPILOT, VehicleClass.GROUND): _AP_ROVER,
    (PX4, VehicleClass.MULTICOPTER): _px4(VehicleClass.MULTICOPTER, "PX4 multicopter"),
    (PX4, VehicleClass.FIXED_WING): _px4(VehicleClass.FIXED_WING, "PX4 fixed-wing", fixed_wing=True),
    (PX4, VehicleClass.VTOL): _px4(VehicleClass.VTOL, "PX4 VTOL"),
    (PX4, VehicleClass.GROUND): _px4(VehicleClass.GROUND, "PX4 rover"),
}


def generic_style(vehicle: VehicleClass) -> FlightStyle:
    """An autopilot the suite has no style for: MAV_CMD_MISSION_START alone (common.xml)."""
    return FlightStyle("generic MAVLink", vehicle, arm_in=None,
                       fixed_wing_landing=vehicle is VehicleClass.FIXED_WING,
                       source="common.xml MAV_CMD_MISSION_START, MAV_CMD_NAV_LAND")


def style_for(autopilot: int | None, vehicle: VehicleClass) -> FlightStyle | None:
    """The style for a HEARTBEAT's autopilot and vehicle class; None: a class not flown."""
    if vehicle is VehicleClass.OTHER:
        return None
    return STYLES.get((autopilot, vehicle)) or generic_style(vehicle)
