"""An MSP flight controller's waypoint store, sans-IO, as INAV 9.1's SITL answered it.

`builtin:msp` (issue 25) is this model behind a link. Every rule is what the SITL did when
probed over MSP on TCP 5760 (2026-11-28, INAV 9.1.0 e7d5cceb; tests/msp/test_flight_controller.py
replays each answer) and where INAV's source says so:

- MSP_SET_WP takes waypoint number 1 (which clears the list) or count + 1 (an append), with
  a known action; anything else (a gap, 0 or 255 while disarmed, 121, action 2) is ignored
  and still answered `>`; a payload that is not 21 bytes is answered `!`
  (fc/fc_msp.c:3082-3112, navigation/navigation.c:3983-4001). The list is valid while the
  last waypoint taken carries flag 0xA5.
- MSP_WP of a waypoint that does not exist returns an RTH record (action 4, zeros, flag
  0xA5) under the number asked, never an error; with no payload it reads number 0
  (fc/fc_msp.c:1924-1938; sbufReadU8 of nothing is 0).
- MSP_WP_GETINFO: reserved 0, max 120, valid, count (fc_msp.c:1501-1506).
- MSP_WP_MISSION_SAVE / LOAD take a 1-byte mission id (else `!`); a save of a list that is
  not valid is refused (`!`); a load takes the saved list, or empties the list and fails
  (`!`) if none valid was saved (navigation.c:4131-4193).
- MSP2_INAV_SET_WP_INDEX is answered `!`: INAV takes it only while armed flying a WP
  mission (navigation.c:3895-3907), and this model never flies.
- A command it does not know is answered `!`; a reply uses the request's framing (v1, v2,
  v2 inside v1).
"""

from __future__ import annotations

from dataclasses import dataclass

from .commands import CODE, FLAG_LAST, Waypoint, WaypointInfo
from .frame import ERROR, FROM_FC, MspFrame

ACTIONS = frozenset({1, 3, 4, 5, 6, 7, 8})   # navigation.h:520-526 (setWaypoint's list, navigation.c:3985)
API = (0, 2, 5)                              # MSP_API_VERSION as INAV 9.1.0 answered


def missing(number: int) -> Waypoint:
    """What MSP_WP returns for a waypoint that does not exist."""
    return Waypoint(number, 4, 0, 0, 0, 0, 0, 0, FLAG_LAST)


@dataclass
class ControllerStats:
    requests: int = 0
    errors: int = 0           # answered `!`
    ignored_waypoints: int = 0


class MspFlightController:
    def __init__(self, *, max_waypoints: int = 120) -> None:
        self.max_waypoints = max_waypoints
        self.waypoints: list[Waypoint] = []
        self.valid = False
        self.saved: list[Waypoint] = []
        self.nav_status = bytes(7)            # mode, state, action, number, error, i16 heading target
        self.stats = ControllerStats()
        self._handlers = {
            CODE["MSP_API_VERSION"]: lambda p: bytes(API),
            CODE["MSP_WP_GETINFO"]: lambda p: self.info().pack(),
            CODE["MSP_WP"]: self._wp,
            CODE["MSP_SET_WP"]: self._set_wp,
            CODE["MSP_NAV_STATUS"]: lambda p: self.nav_status,
            CODE["MSP_WP_MISSION_SAVE"]: self._save,
            CODE["MSP_WP_MISSION_LOAD"]: self._load,
            CODE["MSP2_INAV_SET_WP_INDEX"]: lambda p: None,   # never armed in a WP mission here
        }

    def info(self) -> WaypointInfo:
        return WaypointInfo(0, self.max_waypoints, self.valid, len(self.waypoints))

    def handle(self, frame: MspFrame) -> list[MspFrame]:
        """The reply to one request (frames from the flight controller itself are ignored)."""
        if frame.direction != "<":
            return []
        self.stats.requests += 1
        handler = self._handlers.get(frame.command)
        payload = handler(frame.payload) if handler is not None else None
        if payload is None:
            self.stats.errors += 1
            return [MspFrame(frame.command, b"", ERROR, frame.version, frame.flag)]
        return [MspFrame(frame.command, payload, FROM_FC, frame.version, frame.flag)]

    # --- commands: each returns the reply payload, or None for `!` ----------------------------
    def _wp(self, payload: bytes) -> bytes:
        number = payload[0] if payload else 0
        if 1 <= number <= len(self.waypoints):
            return self.waypoints[number - 1].pack()
        return missing(number).pack()

    def _set_wp(self, payload: bytes) -> bytes | None:
        if len(payload) != 21:
            return None
        wp = Waypoint.unpack(payload)
        if not self.takes(wp):
            self.stats.ignored_waypoints += 1
            return b""
        self.store(wp)
        return b""

    def takes(self, wp: Waypoint) -> bool:
        """Whether setWaypoint takes `wp` into the mission: number 1 or count + 1, a known action."""
        return (1 <= wp.number <= self.max_waypoints and wp.action in ACTIONS
                and wp.number in (1, len(self.waypoints) + 1))

    def store(self, wp: Waypoint) -> None:
        if wp.number == 1:
            self.waypoints = []
        self.waypoints.append(wp)
        self.valid = wp.flag == FLAG_LAST

    def _save(self, payload: bytes) -> bytes | None:
        if len(payload) != 1 or not self.valid:
            return None
        self.saved = list(self.waypoints)
        return b""

    def _load(self, payload: bytes) -> bytes | None:
        if len(payload) != 1:
            return None
        self.waypoints = list(self.saved)
        self.valid = bool(self.saved) and self.saved[-1].flag == FLAG_LAST
        if not self.valid:            # "sanity check failed - reset the list", and the load fails
            self.waypoints = []
            return None
        return b""
