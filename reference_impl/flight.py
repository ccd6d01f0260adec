"""A simple, event-driven flight through the stored mission.

Enough physics to make progress reporting real: the vehicle flies in a straight line at a
fixed ground speed to each positional item, holds for the item's hold time, passes other
items at once (DO_JUMP jumps, with its repeat count), and reports through
`MissionProgress`. Instead of ticking, it computes when the next item will be reached and
asks to be woken then, so an hour of flight costs a handful of steps in virtual time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .mission.actions import Send
from .mission.constants import POSITIONAL_COMMANDS, Cmd
from .mission.items import GLOBAL_FRAMES, MissionItem, MissionType
from .mission.progress import MissionProgress
from .mission.store import MissionStore

EARTH_RADIUS_M = 6_371_000.0
MIN_ITEM_TIME = 0.1  # s: every item takes some time, so a DO_JUMP loop cannot spin in place
HOLD_COMMANDS = {Cmd.NAV_WAYPOINT: 1, Cmd.NAV_LOITER_TIME: 1, Cmd.NAV_DELAY: 1, Cmd.CONDITION_DELAY: 1}


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


class FlightSim:
    def __init__(self, store: MissionStore, progress: MissionProgress, *,
                 home: Position = Position(47.397742, 8.545594, 0.0), speed: float = 10.0) -> None:
        self.store = store
        self.progress = progress
        self.home = home
        self.speed = speed
        self.position = Position(home.lat, home.lon, home.alt)
        self._leg_start: Position | None = None
        self._leg_started = 0.0
        self._arrive_at: float | None = None
        self._jumps_left: dict[int, int] = {}

    @property
    def flying(self) -> bool:
        return self.progress.running

    def start(self, now: float) -> list[Send]:
        """MAV_CMD_MISSION_START: fly from the current item. Returns the announcements to
        send; an empty list means there was no mission to fly."""
        if self.store.count(MissionType.MISSION) == 0:
            return []
        self.progress.running, self.progress.complete = True, False
        self.progress.seq = max(self.progress.seq, self.progress.first_seq)   # past a home item
        self._jumps_left = {}
        out = self.progress.announce(now)
        self._plan_leg(now)
        return out

    def retarget(self, now: float) -> None:
        """The current item changed (set current, new plan): head for the new one."""
        if self.progress.running:
            self.position = self.where(now)
            self._plan_leg(now)
        else:
            self._arrive_at = None

    def next_deadline(self) -> float | None:
        return self._arrive_at if self.progress.running else None

    def poll(self, now: float) -> list[Send]:
        out: list[Send] = []
        for _ in range(64):  # bounded; each item takes >= MIN_ITEM_TIME, so one pass is usual
            if not self.progress.running or self._arrive_at is None or now < self._arrive_at:
                break
            item = self._current_item()
            if item is None:
                self.progress.running = False
                break
            if item.command in POSITIONAL_COMMANDS and item.frame in GLOBAL_FRAMES:
                self.position = Position(item.x / 1e7, item.y / 1e7, item.z)
            seq = item.seq
            out += self.progress.reached(seq, self._arrive_at)
            jump = self._jump_target(item)
            if jump is not None:
                out += self.progress.set_current(jump, self._arrive_at)
                self.progress.running = True
            self._plan_leg(self._arrive_at)
        return out

    def where(self, now: float) -> Position:
        if not self.progress.running or self._arrive_at is None or self._leg_start is None:
            return self.position
        item = self._current_item()
        if item is None or item.command not in POSITIONAL_COMMANDS or item.frame not in GLOBAL_FRAMES:
            return self.position
        span = self._arrive_at - self._leg_started
        f = 1.0 if span <= 0 else min(1.0, max(0.0, (now - self._leg_started) / span))
        a, b = self._leg_start, Position(item.x / 1e7, item.y / 1e7, item.z)
        return Position(a.lat + (b.lat - a.lat) * f, a.lon + (b.lon - a.lon) * f, a.alt + (b.alt - a.alt) * f)

    # --- internals ------------------------------------------------------------------------
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
