"""The plan the progress clauses fly: a realistic one, laid out for the vehicle's class.

Realistic means what a GCS plans: a take-off, waypoints with DO commands between them (a
speed change, a camera trigger distance), a timed loiter and a landing. A DO command that
completes at once right after a waypoint is where a vehicle is most likely to lose that
waypoint's MISSION_ITEM_REACHED (MIS.PRG.01's business), so there are two such places.

Everything is laid out from the vehicle's HOME_POSITION (never a fixed place, nor a
position from before home was set), in metres north/east, with legs sized from the radii
the vehicle reports (acceptance and loiter; a fixed-wing turns on its loiter radius) and
altitudes relative to home (MAV_FRAME_GLOBAL_RELATIVE_ALT_INT):
- multicopter: take off to 10 m, two legs and a loiter, land at home;
- fixed-wing: take off north, a wide rectangle at 40 m, a loiter, then a straight-in
  landing from a waypoint 6 R north at 20 m (glide slope under 5 degrees, PX4's FW_LND_ANG);
- VTOL: vertical take-off to 30 m, the fixed-wing rectangle, vertical landing at home;
- ground: two legs, a loiter, back to home, all at ground level.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from mavconform.reference_impl.mission.commands import by_name
from mavconform.reference_impl.mission.constants import POSITIONAL_COMMANDS, Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.vehicle_class import VehicleClass
from mavconform.reference_impl.wire.dialect import mavlink as _d

RELATIVE = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT
ABSOLUTE = _d.MAV_FRAME_GLOBAL_INT
NO_FRAME = _d.MAV_FRAME_MISSION
VTOL_TAKEOFF = by_name("NAV_VTOL_TAKEOFF").value
VTOL_LAND = by_name("NAV_VTOL_LAND").value
CAM_TRIGG_DIST = by_name("DO_SET_CAM_TRIGG_DIST").value
METRES_PER_DEGREE = 111_320.0

# per class: (smallest radius R the legs are sized from in m, cruise speed for the DO
# command in m/s and whether it is airspeed, cruise altitude in m, the slowest ground
# speed the window allows for in m/s)
_CLASS = {
    VehicleClass.MULTICOPTER: (8.0, 5.0, False, 10.0, 1.5),
    VehicleClass.FIXED_WING: (50.0, 14.0, True, 40.0, 8.0),
    VehicleClass.VTOL: (50.0, 11.0, True, 40.0, 4.0),
    VehicleClass.GROUND: (4.0, 2.0, False, 0.0, 0.8),
}
MAX_RADIUS = 100.0         # m: larger reported radii would make the flight minutes long
LOITER_S = {VehicleClass.MULTICOPTER: 3.0, VehicleClass.GROUND: 3.0,
            VehicleClass.FIXED_WING: 10.0, VehicleClass.VTOL: 10.0}
WINDOW_MARGIN = 90.0       # s on top of the path at the slowest speed: take-off, landing, loiters


@dataclass(frozen=True)
class Home:
    lat: int        # degE7
    lon: int
    alt_m: float    # AMSL


@dataclass(frozen=True)
class FlightPlan:
    items: list[MissionItem]        # as uploaded (a home placeholder first where slot 0 is home)
    flown: list[int]                # seqs the vehicle flies, in order
    navigation: list[int]           # seqs of the items with a position (the ones "reached")
    approach: int | None            # the landing approach waypoint (fixed-wing), if any
    radius_m: float                 # R the legs were sized from
    path_m: float
    window_s: float                 # the bound on the whole flight
    summary: str

    @property
    def last(self) -> int:
        return self.items[-1].seq

    @property
    def lands(self) -> bool:
        """The plan ends with a landing (the vehicle is down when it is over)."""
        return self.items[-1].command in (Cmd.NAV_LAND, VTOL_LAND)


def radius(vehicle: VehicleClass, acceptance: float | None, loiter: float | None) -> float:
    """R: at least the class's floor, at least the vehicle's acceptance radius x 2 and its
    loiter (turn) radius, at most MAX_RADIUS."""
    floor = _CLASS[vehicle][0]
    wanted = max([floor] + [2 * acceptance for acceptance in [acceptance] if acceptance]
                 + [loiter for loiter in [loiter] if loiter and vehicle in (VehicleClass.FIXED_WING,
                                                                             VehicleClass.VTOL)])
    return min(MAX_RADIUS, wanted)


def layout(vehicle: VehicleClass, home: Home, r: float, *, home_slot: bool) -> FlightPlan:
    """The plan for `vehicle` from `home` with legs sized from `r`; `home_slot`: the target
    keeps its home in mission slot 0, so a placeholder at home goes first (as GCSs do)."""
    _, speed, airspeed, alt, slowest = _CLASS[vehicle]
    at = _Grid(home)
    speed_change = _item(Cmd.DO_CHANGE_SPEED, NO_FRAME, p=(0.0 if airspeed else 1.0, speed, -1.0, 0.0))
    trigger_off = _item(CAM_TRIGG_DIST, NO_FRAME, p=(0.0, 0.0, 0.0, 0.0))   # distance 0: off; no shot now
    loiter = LOITER_S[vehicle]
    if vehicle is VehicleClass.MULTICOPTER:
        leg = max(30.0, 4 * r)
        body = [takeoff_item(vehicle, home.lat, home.lon, alt), at.item(Cmd.NAV_WAYPOINT, leg, 0, alt), speed_change,
                at.item(Cmd.NAV_WAYPOINT, leg, leg, alt), trigger_off,
                at.item(Cmd.NAV_LOITER_TIME, 0, leg, alt, p=(loiter, 0.0, 0.0, 0.0)),
                landing_item(vehicle, home.lat, home.lon)]
        text = f"take off to {alt:g} m, {leg:g} m legs with a speed change and a camera trigger off between them, " \
               f"a {loiter:g} s loiter, land at home"
    elif vehicle is VehicleClass.GROUND:
        leg = max(20.0, 5 * r)
        body = [at.item(Cmd.NAV_WAYPOINT, leg, 0, 0.0), speed_change, at.item(Cmd.NAV_WAYPOINT, leg, leg, 0.0),
                trigger_off, at.item(Cmd.NAV_LOITER_TIME, 0, leg, 0.0, p=(loiter, 0.0, 0.0, 0.0)),
                at.item(Cmd.NAV_WAYPOINT, 0, 0, 0.0)]
        text = f"{leg:g} m legs with a speed change and a camera trigger off between them, a {loiter:g} s " \
               "stop, back home"
    else:
        vtol = vehicle is VehicleClass.VTOL
        takeoff = (takeoff_item(vehicle, home.lat, home.lon, 30.0) if vtol
                   else takeoff_item(vehicle, *at.xy(3 * r, 0), 30.0))
        body = [takeoff, at.item(Cmd.NAV_WAYPOINT, 6 * r, 0, alt), speed_change,
                at.item(Cmd.NAV_WAYPOINT, 6 * r, 4 * r, alt), trigger_off,
                at.item(Cmd.NAV_LOITER_TIME, 2 * r, 4 * r, alt, p=(loiter, 0.0, 0.0, 0.0))]
        if not vtol:
            body.append(at.item(Cmd.NAV_WAYPOINT, 6 * r, 0, 20.0))   # the approach
        body.append(landing_item(vehicle, home.lat, home.lon))
        text = (f"{'vertical take-off to 30 m' if vtol else 'take off north'}, a {6 * r:g} x {4 * r:g} m "
                f"rectangle at {alt:g} m with a speed change and a camera trigger off, a {loiter:g} s loiter, "
                + ("vertical landing at home" if vtol else f"land at home from {6 * r:g} m north"))
    first = 1 if home_slot else 0
    items = ([MissionItem(0, ABSOLUTE, Cmd.NAV_WAYPOINT, x=home.lat, y=home.lon, z=home.alt_m)] if home_slot else [])
    items += [replace(it, seq=first + i) for i, it in enumerate(body)]
    navigation = [it.seq for it in items[first:] if it.command in POSITIONAL_COMMANDS]
    approach = items[-2].seq if vehicle is VehicleClass.FIXED_WING else None
    path = _path(items[first:], home)
    window = path / slowest + sum(it.param1 for it in items if it.command == Cmd.NAV_LOITER_TIME) + WINDOW_MARGIN
    return FlightPlan(items, [it.seq for it in items[first:]], navigation, approach, r, round(path, 1),
                      round(window), text)


def takeoff_item(vehicle: VehicleClass, x: int, y: int, alt: float) -> MissionItem:
    """A take-off to `alt` m above home at x/y: vertical for a VTOL; a fixed-wing's with a
    climb pitch (15 degrees) and no yaw (NaN: its own course)."""
    if vehicle is VehicleClass.VTOL:
        return MissionItem(0, RELATIVE, VTOL_TAKEOFF, x=x, y=y, z=alt, mission_type=MissionType.MISSION)
    pitch = (15.0, 0.0, 0.0, math.nan) if vehicle is VehicleClass.FIXED_WING else (0.0, 0.0, 0.0, 0.0)
    return MissionItem(0, RELATIVE, Cmd.NAV_TAKEOFF, *pitch, x=x, y=y, z=alt, mission_type=MissionType.MISSION)


def landing_item(vehicle: VehicleClass, x: int, y: int) -> MissionItem:
    """A landing at x/y on home's level: vertical for a VTOL."""
    command = VTOL_LAND if vehicle is VehicleClass.VTOL else Cmd.NAV_LAND
    return MissionItem(0, RELATIVE, command, x=x, y=y, z=0.0, mission_type=MissionType.MISSION)


class _Grid:
    """Metres north/east of home -> degE7."""

    def __init__(self, home: Home) -> None:
        self.home = home
        self.east = METRES_PER_DEGREE * math.cos(math.radians(home.lat / 1e7))

    def xy(self, north: float, east: float) -> tuple[int, int]:
        return (self.home.lat + round(north / METRES_PER_DEGREE * 1e7),
                self.home.lon + round(east / self.east * 1e7))

    def item(self, command: int, north: float, east: float, alt: float,
             p: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)) -> MissionItem:
        x, y = self.xy(north, east)
        return MissionItem(0, RELATIVE, command, *p, x=x, y=y, z=alt, mission_type=MissionType.MISSION)


def _item(command: int, frame: int, p: tuple[float, float, float, float]) -> MissionItem:
    return MissionItem(0, frame, command, *p, mission_type=MissionType.MISSION)


def _path(items: list[MissionItem], home: Home) -> float:
    """Metres flown through the positional items, from home."""
    here = (home.lat, home.lon)
    total = 0.0
    east = METRES_PER_DEGREE * math.cos(math.radians(home.lat / 1e7))
    for it in items:
        if it.frame not in (RELATIVE, ABSOLUTE):
            continue
        dn = (it.x - here[0]) / 1e7 * METRES_PER_DEGREE
        de = (it.y - here[1]) / 1e7 * east
        total += math.hypot(dn, de)
        here = (it.x, it.y)
    return total
