"""What the target's own streams say about it while it flies: mode, armed, height, speed.

A flight is judged from MISSION_ITEM_REACHED and MISSION_CURRENT, but started and ended
from the vehicle's HEARTBEAT (the mode it is in, MAV_MODE_FLAG_SAFETY_ARMED) and its
GLOBAL_POSITION_INT (height above home, ground speed): the suite arms only once the
HEARTBEAT shows the mode it asked for, and a flight ends only once the HEARTBEAT shows the
vehicle disarmed. The watch reads the tester's inbox forward, each frame once.
"""

from __future__ import annotations

import bisect
import math
from typing import Any, Callable

from mavconform.reference_impl.mission.messages import is_vehicle_heartbeat
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.wire.frame import Frame

from .tester import Tester

ARMED = _d.MAV_MODE_FLAG_SAFETY_ARMED
ON_GROUND_M = 1.0       # m above home below which a vehicle that has stopped is on the ground
STOPPED_MS = 1.0        # m/s ground speed below which it has stopped


class InboxReader:
    """A tester's inbox read forward from a time (frames at that time included): what came
    since the last look. The inbox may be trimmed under it (`Tester.mark` forgets old frames
    of a chatty target): then it finds its place again after the last frame it returned."""

    def __init__(self, t: Tester, since: float) -> None:
        self.t, self.last = t, since
        self._pos: int | None = None

    def new(self) -> list[tuple[float, Frame]]:
        inbox = self.t.node.inbox
        if self._pos is None:   # first look: from `since` on
            self._pos = bisect.bisect_left(inbox, self.last, key=lambda entry: entry[0])
        elif self._pos > len(inbox):   # trimmed: after the last frame returned
            self._pos = bisect.bisect_right(inbox, self.last, key=lambda entry: entry[0])
        out = inbox[self._pos:]
        self._pos = len(inbox)
        if out:
            self.last = out[-1][0]
        return out


class VehicleWatch:
    """The target's latest HEARTBEAT and GLOBAL_POSITION_INT from `since` on, and whether
    it has ever shown itself armed. `on_frame` sees every other frame read (the flight
    collects its progress messages there)."""

    def __init__(self, t: Tester, since: float | None = None,
                 on_frame: Callable[[float, Frame], None] | None = None) -> None:
        self.t = t
        self.since = t.now() if since is None else since
        self._reader = InboxReader(t, self.since)
        self.on_frame = on_frame
        self.heartbeat: Any = None
        self.heartbeat_at: float | None = None
        self.position: Any = None
        self.ever_armed = False
        self._still_since: float | None = None   # on the ground and stopped since

    def update(self) -> None:
        target = self.t.target
        for at, frame in self._reader.new():
            msg = frame.msg
            if (frame.src_system, frame.src_component) != tuple(target):
                continue
            name = msg._type
            if name == "HEARTBEAT" and is_vehicle_heartbeat(msg):
                self.heartbeat, self.heartbeat_at = msg, at
                self.ever_armed |= bool(msg.base_mode & ARMED)
            elif name == "GLOBAL_POSITION_INT":
                self.position = msg
                still = self._on_ground_and_stopped(msg)
                self._still_since = (self._still_since or at) if still else None
            elif self.on_frame is not None:
                self.on_frame(at, frame)

    # --- what it says -----------------------------------------------------------------------
    @property
    def armed(self) -> bool | None:
        """Armed by the latest HEARTBEAT (None: no HEARTBEAT read yet)."""
        self.update()
        return None if self.heartbeat is None else bool(self.heartbeat.base_mode & ARMED)

    @property
    def mode(self) -> int | None:
        self.update()
        return None if self.heartbeat is None else self.heartbeat.custom_mode

    @property
    def height_m(self) -> float | None:
        """Height above home by the latest GLOBAL_POSITION_INT (relative_alt, mm)."""
        self.update()
        return None if self.position is None else self.position.relative_alt / 1000.0

    def still_for(self) -> float:
        """How long the vehicle has been on the ground and stopped (0: it is not)."""
        self.update()
        return 0.0 if self._still_since is None else self.t.now() - self._still_since

    def heartbeat_since(self, when: float) -> bool:
        self.update()
        return self.heartbeat_at is not None and self.heartbeat_at >= when

    @staticmethod
    def _on_ground_and_stopped(msg: Any) -> bool:
        speed = math.hypot(msg.vx, msg.vy) / 100.0   # cm/s
        return msg.relative_alt / 1000.0 < ON_GROUND_M and speed < STOPPED_MS

    def describe(self) -> str:
        """The latest HEARTBEAT and height, for a note."""
        self.update()
        if self.heartbeat is None:
            return "no HEARTBEAT yet"
        hb = self.heartbeat
        state = "armed" if hb.base_mode & ARMED else "disarmed"
        height = "" if self.position is None else f", {self.position.relative_alt / 1000.0:.1f} m above home"
        return f"HEARTBEAT custom_mode {hb.custom_mode}, {state}{height}"
