"""A simple, event-driven flight through the stored mission.

Enough physics to make progress reporting real: the vehicle flies in a straight line at a
fixed ground speed to each positional item, holds for the item's hold time, passes other
items at once (DO_JUMP jumps, with its repeat count), and reports through
`MissionProgress`. Instead of ticking, it computes when the next item will be reached and
asks to be woken then, so an hour of flight costs a handful of steps in virtual time.

Take-off and landing are modelled as autopilots fly them (issue 23): a take-off item
(NAV_TAKEOFF, NAV_VTOL_TAKEOFF) climbs to its altitude at `CLIMB_SPEED`, over its position or
straight up where it has none; a landing item (NAV_LAND, NAV_VTOL_LAND) flies over its spot
(or stays where it is) and descends to home's altitude at `DESCENT_SPEED`: it is reached on
touching down (`landed_at`), and the mission ends there. A ground vehicle (`ground`) keeps
home's altitude everywhere: it never climbs, and a landing item is one more place to drive to.
The autopilot (autopilot.py) also makes the vehicle `hold` where it is, `climb` outside the
mission (a guided take-off) and `stop` (disarmed).

Two additions serve the emergency procedure (handover/emergency_procedure.py):
- `divert(target, now)`: leave the mission (suspended: MISSION_CURRENT says paused), fly
  straight to `target` at cruise speed and altitude, then land there (descend at
  `DESCENT_SPEED`) or hold. RTL is a divert to home. `start` (MISSION_START) resumes the
  mission from where the vehicle is; nothing else ends a divert: the flight model obeys,
  the vehicle decides who may command it.
- a battery (`FlightBattery`), drained by the horizontal distance flown at the scenario's
  `consumption_wh_per_m`: the same ground-track metres `emergency.choose_refuge` counts range
  in, so the range the vehicle plans with is the range it has.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .handover.emergency import BatteryModel, BatteryState
from .handover.geo import EARTH_MEAN_RADIUS_M
from .mission.actions import Send
from .mission.constants import POSITIONAL_COMMANDS, Cmd
from .mission.items import GLOBAL_FRAMES, MissionItem, MissionType
from .mission.progress import MissionProgress
from .mission.store import MissionStore

EARTH_RADIUS_M = 6_371_000.0
MIN_ITEM_TIME = 0.1  # s: every item takes some time, so a DO_JUMP loop cannot spin in place
HOLD_COMMANDS = {Cmd.NAV_WAYPOINT: 1, Cmd.NAV_LOITER_TIME: 1, Cmd.NAV_DELAY: 1, Cmd.CONDITION_DELAY: 1}
DESCENT_SPEED = 2.0  # m/s: a landing's descent (a typical autopilot land speed, well above its final flare)
CLIMB_SPEED = 2.5    # m/s: a take-off's climb (ArduCopter WPNAV_SPEED_UP 250 cm/s; PX4 MPC_Z_V_AUTO_UP 3 m/s)
AIRBORNE_MARGIN = 0.5   # m above home: off the ground
TAKEOFF_COMMANDS = frozenset({Cmd.NAV_TAKEOFF, Cmd.NAV_VTOL_TAKEOFF})
LAND_COMMANDS = frozenset({Cmd.NAV_LAND, Cmd.NAV_VTOL_LAND})


def haversine_m(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    p1, p2 = math.radians(lat1), math.radians(lat2)
    dp, dl = p2 - p1, math.radians(lon2 - lon1)
    a = math.sin(dp / 2) ** 2 + math.cos(p1) * math.cos(p2) * math.sin(dl / 2) ** 2
    return 2 * EARTH_RADIUS_M * math.asin(min(1.0, math.sqrt(a)))


@dataclass(frozen=True)
class Position:
    lat: float
    lon: float
    alt: float


@dataclass(frozen=True)
class FlightBattery:
    """The pack the flight drains: the scenario's energy model and the charge at take-off."""

    model: BatteryModel
    initial: BatteryState


def _ground_distance(a: Position, b: Position) -> float:
    """Horizontal metres between two positions, as the energy model counts them: geo.haversine_m's
    formula and sphere, on plain floats (it runs at every step of the flight)."""
    phi1, phi2 = math.radians(a.lat), math.radians(b.lat)
    dlon = b.lon - a.lon
    dlon = dlon - 360 if dlon > 180 else dlon + 360 if dlon < -180 else dlon
    h = math.sin(math.radians(b.lat - a.lat) / 2) ** 2 + math.cos(phi1) * math.cos(phi2) * math.sin(
        math.radians(dlon) / 2) ** 2
    return 2 * EARTH_MEAN_RADIUS_M * math.asin(math.sqrt(min(1.0, h)))


class _Path:
    """Where a moving vehicle is: straight segments through timed points (a diagonal leg, a
    climb, a flight over then a descent), held at the last point once it is passed."""

    def __init__(self, start: Position, now: float) -> None:
        self.knots: list[tuple[float, Position]] = [(now, start)]

    def to(self, there: Position, seconds: float) -> _Path:
        t, _ = self.knots[-1]
        self.knots.append((t + max(0.0, seconds), there))
        return self

    @property
    def end(self) -> float:
        return self.knots[-1][0]

    @property
    def last(self) -> Position:
        return self.knots[-1][1]

    def at(self, now: float) -> Position:
        knots = self.knots
        for (t0, a), (t1, b) in zip(knots, knots[1:]):
            if now < t1:
                return _between(a, b, t0, t1, now)
        return knots[-1][1] if now >= knots[0][0] else knots[0][1]


class FlightSim:
    def __init__(self, store: MissionStore, progress: MissionProgress, *,
                 home: Position = Position(47.397742, 8.545594, 0.0), speed: float = 10.0,
                 battery: FlightBattery | None = None, ground: bool = False, speedup: float = 1.0) -> None:
        self.store = store
        self.progress = progress
        self.home = home
        # `speedup` (like SITL's --speedup, for motion only): every leg, climb and descent is
        # flown that many times faster; a hold or loiter lasts what the plan says, and the
        # protocol's timers are untouched (their timing is what the clauses judge)
        self.speed = speed * speedup
        self.climb_speed = CLIMB_SPEED * speedup
        self.descent_speed = DESCENT_SPEED * speedup
        self.battery = battery
        self.ground = ground             # a ground vehicle: every altitude is home's, it never climbs
        self.position = Position(home.lat, home.lon, home.alt)
        self.odometer_m = 0.0         # horizontal metres flown up to `position`
        self._path: _Path | None = None  # the current leg (mission item or divert); None: standing
        self._arrive_at: float | None = None   # the mission's current item is done (its hold spent)
        self._jumps_left: dict[int, int] = {}
        # a divert: flying `_path` to the target (`_divert_arrive` its end), then landing there or
        # holding (`_divert_arrive` None) until `start`
        self._diverting = False
        self._divert_knot = 0                  # the point of `_path` the divert heads for
        self._divert_arrive: float | None = None
        self.divert_target: Position | None = None
        self._landing = True
        self.landed_at: float | None = None   # when the vehicle last touched down (a divert's or a land item's landing)

    @property
    def flying(self) -> bool:
        return self.progress.running or self._diverting

    @property
    def diverting(self) -> bool:
        return self._diverting

    def airborne(self, now: float) -> bool:
        """Off the ground at `now` (a ground vehicle never is)."""
        return not self.ground and self.where(now).alt > self.home.alt + AIRBORNE_MARGIN

    def start(self, now: float) -> list[Send]:
        """MAV_CMD_MISSION_START: fly from the current item (ending a divert: the mission
        resumes from where the vehicle is). Returns the announcements to send; an empty list
        means there was no mission to fly."""
        if self.store.count(MissionType.MISSION) == 0:
            return []
        if self._diverting:
            self._end_divert(now)
        elif self.progress.running:
            self._move_to(self.where(now))   # started again mid-leg: from where it is
        self.progress.running, self.progress.complete = True, False
        self.progress.seq = max(self.progress.seq, self.progress.first_seq)   # past a home item
        self._jumps_left = {}
        out = self.progress.announce(now)
        self._plan_leg(now)
        return out

    def retarget(self, now: float) -> None:
        """The current item changed (set current, new plan): head for the new one. A divert
        goes on: the mission is suspended until `start`."""
        if self._diverting:
            return
        if self.progress.running:
            self._move_to(self.where(now))
            self._plan_leg(now)
        else:
            self._arrive_at = self._path = None

    def divert(self, target: Position, now: float, *, land: bool = True) -> None:
        """Leave the mission for `target`: straight there at cruise speed and the current
        altitude, then down to the ground (home's altitude) at `DESCENT_SPEED` if `land`, else
        hold there. A divert while diverting replaces it."""
        here = self.where(now)
        self._move_to(here)
        self.progress.running = False
        self._arrive_at = None
        above = Position(target.lat, target.lon, here.alt)
        horizontal = _ground_distance(here, above)
        path = _Path(here, now).to(above, horizontal / self.speed)
        if land:
            path.to(Position(target.lat, target.lon, self.home.alt), abs(here.alt - self.home.alt) / self.descent_speed)
        self._start_divert(path, target, land)

    def climb(self, altitude: float, now: float) -> None:
        """A take-off outside the mission (MAV_CMD_NAV_TAKEOFF in a guided mode): straight up to
        `altitude` above home at `CLIMB_SPEED` (never down), then hold there until `start` (a
        ground vehicle stays where it is)."""
        here = self.where(now)
        self._move_to(here)
        self.progress.running = False
        self._arrive_at = None
        top = Position(here.lat, here.lon, here.alt if self.ground else max(here.alt, self.home.alt + altitude))
        self._start_divert(_Path(here, now).to(top, abs(top.alt - here.alt) / self.climb_speed), top, False)

    def hold(self, now: float) -> None:
        """Stop where the vehicle is and stay (a hover, a loiter, a rover's hold) until `start`."""
        here = self.where(now)
        self.divert(here, now, land=False)

    def stop(self, now: float) -> None:
        """Everything stops (the motors are off): the mission is suspended, any divert ends, and
        the vehicle is on the ground where it is (disarmed in the air, it falls)."""
        here = self.where(now)
        self._move_to(Position(here.lat, here.lon, self.home.alt))
        self.progress.running = False
        self._arrive_at = self._path = None
        self._diverting, self._divert_arrive, self.divert_target = False, None, None

    def distance_flown(self, now: float) -> float:
        """Horizontal metres flown since take-off (the battery's drain)."""
        return self.odometer_m + _ground_distance(self.position, self.where(now))

    def battery_at(self, now: float) -> BatteryState | None:
        """The charge left at `now` (None: no battery modelled)."""
        b = self.battery
        return None if b is None else b.initial.after(self.distance_flown(now), b.model)

    def next_deadline(self) -> float | None:
        if self._diverting:
            return self._divert_arrive
        return self._arrive_at if self.progress.running else None

    def poll(self, now: float) -> list[Send]:
        if self._diverting:
            self._poll_divert(now)
            return []
        out: list[Send] = []
        for _ in range(64):  # bounded; each item takes >= MIN_ITEM_TIME, so one pass is usual
            if not self.progress.running or self._arrive_at is None or now < self._arrive_at:
                break
            item = self._current_item()
            if item is None:
                self.progress.running = False
                break
            arrived = self._arrive_at
            if self._path is not None:
                self._move_to(self._path.last)
            landed = item.command in LAND_COMMANDS and not self.ground
            out += self.progress.reached(item.seq, arrived, ends=landed, command=item.command)
            if landed:                        # touched down: the mission is over
                self.landed_at = arrived
                self._arrive_at = self._path = None
                break
            jump = self._jump_target(item)
            if jump is not None:
                out += self.progress.set_current(jump, arrived)
                self.progress.running = True
            self._plan_leg(arrived)
        return out

    def where(self, now: float) -> Position:
        if self._path is not None and (self._diverting or self.progress.running):
            return self._path.at(now)
        return self.position

    # --- internals ------------------------------------------------------------------------
    def _move_to(self, p: Position) -> None:
        """The vehicle is now at `p` (a leg's end, or where a leg was cut): count the metres."""
        self.odometer_m += _ground_distance(self.position, p)
        self.position = p

    def _start_divert(self, path: _Path, target: Position, land: bool) -> None:
        """Fly `path`, waking at each of its points (over the target, then on the ground)."""
        self._path, self._divert_knot, self._divert_arrive = path, 1, path.knots[1][0]
        self._diverting, self.divert_target, self.landed_at, self._landing = True, target, None, land

    def _end_divert(self, now: float) -> None:
        self._move_to(self.where(now))
        self._diverting, self._divert_arrive, self.divert_target, self._path = False, None, None, None

    def _poll_divert(self, now: float) -> None:
        for _ in range(len(self._path.knots) if self._path is not None else 0):   # bounded: one pass per point
            if self._divert_arrive is None or now < self._divert_arrive or self._path is None:
                return
            arrived, knots = self._divert_arrive, self._path.knots
            self._move_to(knots[self._divert_knot][1])
            self._divert_knot += 1
            if self._divert_knot < len(knots):
                self._divert_arrive = knots[self._divert_knot][0]
            elif self._landing:
                self._diverting, self._divert_arrive, self._path = False, None, None
                self.landed_at = arrived
            else:
                self._divert_arrive = None   # holding at the target until `start`

    def _current_item(self) -> MissionItem | None:
        items = self.store.items(MissionType.MISSION)
        seq = self.progress.seq
        return items[seq] if 0 <= seq < len(items) else None

    def _plan_leg(self, now: float) -> None:
        item = self._current_item()
        if item is None or not self.progress.running:
            self._arrive_at = self._path = None
            return
        path = self._leg(item, now)
        hold = item.param1 if item.command in HOLD_COMMANDS and math.isfinite(item.param1) else 0.0
        self._path = path
        travel = 0.0 if path is None else path.end - now   # at the item; a hold is spent there, until _arrive_at
        self._arrive_at = now + max(MIN_ITEM_TIME, travel + max(0.0, hold))

    def _leg(self, item: MissionItem, now: float) -> _Path | None:
        """The way to `item` from where the vehicle is; None for an item done in place."""
        if item.command not in POSITIONAL_COMMANDS or item.frame not in GLOBAL_FRAMES:
            return None
        here, ground = self.position, self.home.alt
        lat, lon = item.x / 1e7, item.y / 1e7
        if item.command in TAKEOFF_COMMANDS | LAND_COMMANDS and not (item.x or item.y):
            lat, lon = here.lat, here.lon     # a take-off or landing with no place: where the vehicle is
        path = _Path(here, now)
        if self.ground:                     # drives there; altitudes mean nothing
            there = Position(lat, lon, ground)
            return path.to(there, _ground_distance(here, there) / self.speed)
        if item.command in TAKEOFF_COMMANDS:   # climbs to the item's altitude (never descends)
            top = Position(lat, lon, max(here.alt, item.z))
            return path.to(top, max(_ground_distance(here, top) / self.speed, (top.alt - here.alt) / self.climb_speed))
        if item.command in LAND_COMMANDS:      # over the spot at the current altitude, then down
            above = Position(lat, lon, here.alt)
            path.to(above, _ground_distance(here, above) / self.speed)
            return path.to(Position(lat, lon, ground), abs(here.alt - ground) / self.descent_speed)
        there = Position(lat, lon, item.z)
        dist = haversine_m(here.lat, here.lon, there.lat, there.lon)
        return path.to(there, math.hypot(dist, item.z - here.alt) / self.speed)

    def _jump_target(self, item: MissionItem) -> int | None:
        if item.command != Cmd.DO_JUMP:
            return None
        target = int(item.param1)
        if not 0 <= target < self.store.count(MissionType.MISSION):
            return None
        left = self._jumps_left.setdefault(item.seq, int(item.param2))
        if left == 0:
            return None
        if left > 0:
            self._jumps_left[item.seq] = left - 1
        return target


def _between(a: Position, b: Position, started: float, arrive: float, now: float) -> Position:
    """Where a straight leg from `a` (left at `started`) to `b` (reached at `arrive`) is at `now`."""
    span = arrive - started
    f = 1.0 if span <= 0 else min(1.0, max(0.0, (now - started) / span))
    return Position(a.lat + (b.lat - a.lat) * f, a.lon + (b.lon - a.lon) * f, a.alt + (b.alt - a.alt) * f)
