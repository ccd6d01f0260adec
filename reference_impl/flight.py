"""A simple, event-driven flight through the stored mission.

Enough physics to make progress reporting real: the vehicle flies in a straight line at a
fixed ground speed to each positional item, holds for the item's hold time, passes other
items at once (DO_JUMP jumps, with its repeat count), and reports through
`MissionProgress`. Instead of ticking, it computes when the next item will be reached and
asks to be woken then, so an hour of flight costs a handful of steps in virtual time.

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
DESCENT_SPEED = 2.0  # m/s: a divert's landing (a typical autopilot land speed, well above its final flare)


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


class FlightSim:
    def __init__(self, store: MissionStore, progress: MissionProgress, *,
                 home: Position = Position(47.397742, 8.545594, 0.0), speed: float = 10.0,
                 battery: FlightBattery | None = None) -> None:
        self.store = store
        self.progress = progress
        self.home = home
        self.speed = speed
        self.battery = battery
        self.position = Position(home.lat, home.lon, home.alt)
        self.odometer_m = 0.0         # horizontal metres flown up to `position`
        self._leg_start: Position | None = None
        self._leg_started = 0.0
        self._arrive_at: float | None = None
        self._reach_at = 0.0             # when the current leg reaches its item (a hold follows)
        self._jumps_left: dict[int, int] = {}
        # a divert: the points still to fly through (the refuge, then the ground there), when
        # the current one is reached; None when not diverting, [] when holding at the target
        self._divert: list[Position] | None = None
        self._divert_arrive: float | None = None
        self.divert_target: Position | None = None
        self._landing = True
        self.landed_at: float | None = None   # when the last divert touched down

    @property
    def flying(self) -> bool:
        return self.progress.running or self._divert is not None

    @property
    def diverting(self) -> bool:
        return self._divert is not None

    def start(self, now: float) -> list[Send]:
        """MAV_CMD_MISSION_START: fly from the current item (ending a divert: the mission
        resumes from where the vehicle is). Returns the announcements to send; an empty list
        means there was no mission to fly."""
        if self.store.count(MissionType.MISSION) == 0:
            return []
        if self._divert is not None:
            self._move_to(self.where(now))
            self._divert = self._divert_arrive = self.divert_target = None
        self.progress.running, self.progress.complete = True, False
        self.progress.seq = max(self.progress.seq, self.progress.first_seq)   # past a home item
        self._jumps_left = {}
        out = self.progress.announce(now)
        self._plan_leg(now)
        return out

    def retarget(self, now: float) -> None:
        """The current item changed (set current, new plan): head for the new one. A divert
        goes on: the mission is suspended until `start`."""
        if self._divert is not None:
            return
        if self.progress.running:
            self._move_to(self.where(now))
            self._plan_leg(now)
        else:
            self._arrive_at = None

    def divert(self, target: Position, now: float, *, land: bool = True) -> None:
        """Leave the mission for `target`: straight there at cruise speed and the current
        altitude, then down to the ground (home's altitude) at `DESCENT_SPEED` if `land`, else
        hold there. A divert while diverting replaces it."""
        here = self.where(now)
        self._move_to(here)
        self.progress.running = False
        self._arrive_at = None
        legs = [Position(target.lat, target.lon, here.alt)]
        if land:
            legs.append(Position(target.lat, target.lon, self.home.alt))
        self._divert, self.divert_target, self.landed_at, self._landing = legs, target, None, land
        self._plan_divert_leg(now)

    def distance_flown(self, now: float) -> float:
        """Horizontal metres flown since take-off (the battery's drain)."""
        return self.odometer_m + _ground_distance(self.position, self.where(now))

    def battery_at(self, now: float) -> BatteryState | None:
        """The charge left at `now` (None: no battery modelled)."""
        b = self.battery
        return None if b is None else b.initial.after(self.distance_flown(now), b.model)

    def next_deadline(self) -> float | None:
        if self._divert is not None:
            return self._divert_arrive
        return self._arrive_at if self.progress.running else None

    def poll(self, now: float) -> list[Send]:
        if self._divert is not None:
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
            if item.command in POSITIONAL_COMMANDS and item.frame in GLOBAL_FRAMES:
                self._move_to(Position(item.x / 1e7, item.y / 1e7, item.z))
            seq = item.seq
            out += self.progress.reached(seq, self._arrive_at)
            jump = self._jump_target(item)
            if jump is not None:
                out += self.progress.set_current(jump, self._arrive_at)
                self.progress.running = True
            self._plan_leg(self._arrive_at)
        return out

    def where(self, now: float) -> Position:
        if self._divert is not None:
            if not self._divert or self._divert_arrive is None or self._leg_start is None:
                return self.position
            return _between(self._leg_start, self._divert[0], self._leg_started, self._divert_arrive, now)
        if not self.progress.running or self._arrive_at is None or self._leg_start is None:
            return self.position
        item = self._current_item()
        if item is None or item.command not in POSITIONAL_COMMANDS or item.frame not in GLOBAL_FRAMES:
            return self.position
        return _between(self._leg_start, Position(item.x / 1e7, item.y / 1e7, item.z), self._leg_started,
                        self._reach_at, now)

    # --- internals ------------------------------------------------------------------------
    def _move_to(self, p: Position) -> None:
        """The vehicle is now at `p` (a leg's end, or where a leg was cut): count the metres."""
        self.odometer_m += _ground_distance(self.position, p)
        self.position = p

    def _plan_divert_leg(self, now: float) -> None:
        """Head for the next point of the divert: horizontally at cruise speed, down at the
        descent speed."""
        assert self._divert
        here, there = self.position, self._divert[0]
        horizontal = _ground_distance(here, there)
        travel = horizontal / self.speed if horizontal > 0 else abs(there.alt - here.alt) / DESCENT_SPEED
        self._leg_start, self._leg_started = here, now
        self._divert_arrive = now + travel

    def _poll_divert(self, now: float) -> None:
        for _ in range(4):   # bounded: a divert has at most two points
            if not self._divert or self._divert_arrive is None or now < self._divert_arrive:
                return
            arrived = self._divert_arrive
            self._move_to(self._divert.pop(0))
            if self._divert:
                self._plan_divert_leg(arrived)
            elif self._landing:
                self._divert = self._divert_arrive = None
                self.landed_at = arrived
                return
            else:
                self._divert_arrive = None   # holding at the target until `start`
                return

    def _current_item(self) -> MissionItem | None:
        items = self.store.items(MissionType.MISSION)
        seq = self.progress.seq
        return items[seq] if 0 <= seq < len(items) else None

    def _plan_leg(self, now: float) -> None:
        item = self._current_item()
        if item is None or not self.progress.running:
            self._arrive_at = None
            return
        travel = 0.0
        if item.command in POSITIONAL_COMMANDS and item.frame in GLOBAL_FRAMES:
            here = self.position
            dist = haversine_m(here.lat, here.lon, item.x / 1e7, item.y / 1e7)
            travel = math.hypot(dist, item.z - here.alt) / self.speed
        hold = item.param1 if item.command in HOLD_COMMANDS and math.isfinite(item.param1) else 0.0
        self._leg_start, self._leg_started = Position(self.position.lat, self.position.lon, self.position.alt), now
        self._reach_at = now + travel      # at the item; a hold is spent there, until _arrive_at
        self._arrive_at = now + max(MIN_ITEM_TIME, travel + max(0.0, hold))

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
