"""What the autopilot does with mode, arming and flight commands (sans-IO, time injected).

The vehicle node hands it MAV_CMD_DO_SET_MODE, MAV_CMD_COMPONENT_ARM_DISARM,
MAV_CMD_MISSION_START, MAV_CMD_NAV_TAKEOFF / NAV_VTOL_TAKEOFF, MAV_CMD_NAV_RETURN_TO_LAUNCH,
MAV_CMD_NAV_LAND / NAV_VTOL_LAND and the home-position requests; it answers each with its
COMMAND_ACK (and the STATUSTEXT the profile gives the autopilot's words for) and makes the
flight model (flight.py) do what the mode says, by the profile's `FlightRules`
(flight_rules.py). It also acts by itself: it disarms after landing and after idling armed on
the ground, changes mode at the end of the mission, and resets the mission on a disarm.

The state is the current mode and whether the vehicle is armed. The flight moves only when it
may: armed (or on a vehicle that needs no arming), in a mode that flies. A vehicle without a
mode table (the spec vehicle) answers DO_SET_MODE, arming, take-off, return and landing
MAV_RESULT_UNSUPPORTED, flies on MISSION_START and reports itself armed while it flies, so
every builtin vehicle can be asked whether it is still armed.
"""

from __future__ import annotations

import math
from typing import Any

from . import vehicle_info
from .flight import LAND_COMMANDS, TAKEOFF_COMMANDS, FlightSim, Position
from .flight_rules import FlightRules, Mode, ModeKind
from .mission import messages as m
from .mission.actions import Peer, Send
from .mission.constants import Cmd
from .mission.constants import CommandResult as R
from .mission.items import MissionType
from .wire.dialect import mavlink as _d

FORCE = 21196.0            # COMPONENT_ARM_DISARM param2: arm or disarm whatever the checks say (common.xml)
NAV_LAST = 95              # MAV_CMD_NAV_LAST: commands below it are navigation commands
FLAG_ARMED = _d.MAV_MODE_FLAG_SAFETY_ARMED
FLAG_CUSTOM = _d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
FLAG_AUTO = _d.MAV_MODE_FLAG_AUTO_ENABLED
MISSION = MissionType.MISSION
STATUSTEXT_LEN = 50        # bytes of STATUSTEXT.text


class Autopilot:
    """`legacy_modes`: HEARTBEAT.custom_mode (idle, flying the mission) for a vehicle without a
    mode table (the custom_mode_idle / custom_mode_mission knobs); `events`: the list its
    mode changes, arming and disarming are logged to (the vehicle's)."""

    def __init__(self, rules: FlightRules, flight: FlightSim, *, legacy_modes: tuple[int, int] = (0, 0),
                 events: list[str] | None = None) -> None:
        self.rules = rules
        self.flight = flight
        self.legacy_modes = legacy_modes
        self.mode: Mode | None = rules.mode_named(rules.boot_mode) if rules.modes else None
        self._armed = False
        self._landed_seen = flight.landed_at
        self._complete_seen = False
        self._disarm_at: float | None = None        # after a landing (disarm_after_landing)
        self._idle_disarm_at: float | None = None   # armed on the ground, not flying (disarm_idle_after)
        self.events: list[str] = [] if events is None else events   # what it did, for the vehicle's log
        self._text_id = 0                           # the last long STATUSTEXT's id

    @property
    def armed(self) -> bool:
        """Armed as the HEARTBEAT says: a vehicle that needs no arming is armed while it flies."""
        return self._armed if self.rules.arming else self.flight.flying

    @property
    def progress(self):
        return self.flight.progress

    # --- the HEARTBEAT -------------------------------------------------------------------------
    def heartbeat_fields(self) -> tuple[int, int, int]:
        """(base_mode, custom_mode, system_status): the mode's number, the armed flag, AUTO
        while the flight moves by itself, ACTIVE while armed."""
        flying, armed = self.flight.flying, self.armed
        if self.mode is not None:
            custom = self.mode.number
        else:
            custom = self.legacy_modes[1] if flying else self.legacy_modes[0]
        base = FLAG_CUSTOM | (FLAG_AUTO if flying else 0) | (FLAG_ARMED if armed else 0)
        return base, custom, _d.MAV_STATE_ACTIVE if armed else _d.MAV_STATE_STANDBY

    # --- commands ------------------------------------------------------------------------------
    def command(self, msg: Any, source: Peer, now: float) -> list[Send] | None:
        """The COMMAND_ACK (and what follows it) for a command this module handles; None for any other."""
        handler = _HANDLERS.get(msg.command)
        if handler is None:
            return None
        result, after = handler(self, msg, source, now)
        return [Send(m.command_ack_message(msg.command, result, source), source), *after]

    def _set_mode(self, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        rules = self.rules
        if not rules.modes:
            return R.UNSUPPORTED, []
        if not _whole(msg.param1) & FLAG_CUSTOM:   # ArduPilot _set_mode_common; PX4's base-mode form is not modelled
            return R.DENIED, []
        if rules.set_mode_params == "px4":          # uint8 casts, as Commander.cpp does
            number = (_whole(msg.param2) & 0xFF) << 16 | (_whole(msg.param3) & 0xFF) << 24
        else:
            number = _whole(msg.param2, -1)
        mode = rules.mode_numbered(number)
        if mode is None:
            return rules.refusal, []
        return self._change_mode(mode, now)

    def _change_mode(self, mode: Mode, now: float) -> tuple[int, list[Send]]:
        """Enter `mode` if it lets itself be entered now."""
        if mode is self.mode:
            return R.ACCEPTED, []
        if mode.kind is ModeKind.MISSION and self._armed:   # disarmed, any mode may be entered
            if not self.flight.store.count(MISSION) or self._plan_unflyable():
                return self.rules.refusal, []
            if self.rules.takeoff_first and not self.flight.airborne(now) and not self._takeoff_next():
                return self.rules.refusal, self._text("missing-takeoff")
        return R.ACCEPTED, self._enter(mode, now)

    def _arm_disarm(self, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        if not self.rules.arming:
            return R.UNSUPPORTED, []
        forced = msg.param2 == FORCE
        if msg.param1 == 1:
            if self._armed:
                return R.ACCEPTED, []
            refused = None if forced else self._arming_refused(now)
            if refused is not None:
                return self.rules.refusal, self._text(refused)
            return R.ACCEPTED, self._arm(now)
        if msg.param1 == 0:
            if not self._armed:
                return R.ACCEPTED, []
            if self.flight.airborne(now) and not forced:
                return self.rules.refusal, self._text("disarm-refused")
            return R.ACCEPTED, self._disarm(now, "disarmed by command")
        return R.UNSUPPORTED, []

    def _mission_start(self, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        rules, flight = self.rules, self.flight
        how = rules.mission_start
        if how == "flies":
            if rules.arming and not self._armed:
                return rules.refusal, []
            started = flight.start(now)
            if started:
                self._complete_seen = False
            return (R.ACCEPTED if started else R.FAILED), started
        mission = rules.mode_of(ModeKind.MISSION)
        assert mission is not None   # FlightRules checks it
        if how == "mission-mode":
            if msg.param1 != 0 or msg.param2 != 0:   # first/last item not supported
                return R.DENIED, []
            if self.mode is mission:
                return R.ACCEPTED, self._fly_if_armed(now)
            return self._change_mode(mission, now)
        # mission-mode-and-arm
        count = flight.store.count(MISSION)
        if not count or self._plan_unflyable():
            return R.DENIED, self._text("mission-start-refused")
        if not (math.isfinite(msg.param1) and -1 <= msg.param1 < count):
            return R.DENIED, []
        result, out = self._change_mode(mission, now)
        if result != R.ACCEPTED:
            return result, out
        if not self._armed:
            refused = self._arming_refused(now)
            if refused is not None:
                return rules.refusal, out + self._text(refused)
            out += self._arm(now)
        return R.ACCEPTED, out

    def _takeoff(self, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        rules, how = self.rules, self.rules.takeoff_command
        named = _param7(msg)
        altitude = named if math.isfinite(named) and named > 0 else rules.takeoff_altitude
        if how == "unsupported":
            return R.UNSUPPORTED, []
        if how == "refused":
            return rules.refusal, []
        if how == "takeoff-mode":
            mode = rules.mode_of(ModeKind.TAKEOFF)
            assert mode is not None
            result, out = self._change_mode(mode, now)
            if result == R.ACCEPTED and self._may_fly():
                self.flight.climb(altitude, now)
            return result, out
        # guided-climb: armed, on the ground, in a guided mode, to an altitude it names (ArduCopter takeoff.cpp)
        if (self.mode is None or self.mode.kind is not ModeKind.GUIDED or not self._may_fly()
                or self.flight.airborne(now) or not (math.isfinite(named) and named > 0)):
            return rules.refusal, []
        self.flight.climb(named, now)
        return R.ACCEPTED, []

    def _home(self, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        if msg.command == Cmd.REQUEST_MESSAGE and _whole(msg.param1, -1) != _d.MAVLINK_MSG_ID_HOME_POSITION:
            return R.UNSUPPORTED, []
        home = self.flight.home
        return R.ACCEPTED, [Send(vehicle_info.home_position_message(home.lat, home.lon, home.alt, now), source)]

    # --- by itself -----------------------------------------------------------------------------
    def start_now(self, now: float) -> list[Send]:
        """Fly the stored mission at once, as a GCS would have it fly (VehicleConfig.autostart):
        the mission mode, armed."""
        mission = self.rules.mode_of(ModeKind.MISSION)
        if mission is None:
            return self.flight.start(now)
        if not self.flight.store.count(MISSION):
            return []
        self._armed = self._armed or self.rules.arming
        return self._enter(mission, now) if self.mode is not mission else self._fly_if_armed(now)

    def plan_changed(self, now: float) -> list[Send]:
        """A new mission was stored: say so if it cannot be flown (PX4's feasibility check)."""
        self._complete_seen = False
        if self.flight.store.count(MISSION) and self._plan_unflyable():
            return self._text("plan-refused")
        return []

    def next_deadline(self) -> float | None:
        a, b = self._disarm_at, self._idle_disarm_at   # asked after every frame: no list
        if a is None:
            return b
        return a if b is None or a <= b else b

    def poll(self, now: float) -> list[Send]:
        """What the autopilot does by itself, after the flight model moved on to `now`."""
        out: list[Send] = []
        flight, rules = self.flight, self.rules
        if flight.landed_at != self._landed_seen:
            self._landed_seen = flight.landed_at
            if self._armed and rules.disarm_after_landing is not None and flight.landed_at is not None:
                self._disarm_at = flight.landed_at + rules.disarm_after_landing
        if self.progress.complete and not self._complete_seen:
            self._complete_seen = True
            out += self._mission_ended(now)
        if self._disarm_at is not None and (not self._armed or flight.airborne(now)):
            self._disarm_at = None                   # taken off again, or disarmed meanwhile
        if self._disarm_at is not None and now >= self._disarm_at:
            self._disarm_at = None
            out += self._disarm(now, "disarmed by itself after landing") + self._text("auto-disarmed")
        self._watch_idle(now)
        if self._idle_disarm_at is not None and now >= self._idle_disarm_at:
            self._idle_disarm_at = None
            out += self._disarm(now, "disarmed by itself: armed on the ground") + self._text("idle-disarmed")
        return out

    # --- internals -----------------------------------------------------------------------------
    def _may_fly(self) -> bool:
        return self._armed or not self.rules.arming

    def _enter(self, mode: Mode, now: float) -> list[Send]:
        """The vehicle is in `mode` now: make the flight do what the mode does."""
        if mode is not self.mode:
            self.events.append(f"mode {mode.name}")
        self.mode = mode
        kind, flight = mode.kind, self.flight
        moves_by_itself = kind in (ModeKind.MISSION, ModeKind.TAKEOFF)
        if not self._may_fly() or not (flight.flying or flight.airborne(now) or moves_by_itself):
            return []        # on the ground and not flying: a mode change moves nothing
        if kind is ModeKind.MISSION:
            return self._fly_if_armed(now)
        if kind is ModeKind.RTL:
            home = flight.home
            flight.divert(Position(home.lat, home.lon, home.alt), now, land=self.rules.rtl_lands and not flight.ground)
        elif kind is ModeKind.LAND:
            here = flight.where(now)
            flight.divert(here, now, land=not flight.ground)
        elif kind is ModeKind.TAKEOFF:
            flight.climb(self.rules.takeoff_altitude, now)
        else:          # manual, guided, hold: no pilot, so it stays where it is
            flight.hold(now)
        return []

    def _fly_if_armed(self, now: float) -> list[Send]:
        """In the mission mode: fly the mission if the vehicle may; a mission that was done
        starts again from its first item (AP_Mission::resume of a complete mission)."""
        if not self._may_fly() or self.progress.running:
            return []
        out: list[Send] = []
        if self.progress.complete:
            self.progress.complete = False
            out = self.progress.set_current(self.progress.first_seq, now)
        self._complete_seen = False
        return out + self.flight.start(now)

    def _arming_refused(self, now: float) -> str | None:
        """Why arming is refused now (a TEXT_EVENTS key), None if it is not."""
        rules, mode = self.rules, self.mode
        if mode is not None and mode.name in rules.no_arming_modes:
            return "arm-refused-mode"
        if rules.land_start_blocks_arming and any(
                it.command == Cmd.DO_LAND_START for it in self.flight.store.items(MISSION)):
            return "arm-refused-plan"
        if mode is not None and mode.kind is ModeKind.MISSION and self._plan_unflyable():
            return "arm-refused-plan"
        return None

    def _arm(self, now: float) -> list[Send]:
        """Armed: in a mode that flies by itself (the mission, a take-off), the flight starts."""
        self._armed = True
        self.events.append("armed")
        if self.mode is not None and self.mode.kind in (ModeKind.MISSION, ModeKind.TAKEOFF):
            return self._enter(self.mode, now)
        return []

    def _disarm(self, now: float, why: str) -> list[Send]:
        self._armed = False
        self._disarm_at = self._idle_disarm_at = None
        self.events.append(why)
        self.flight.stop(now)
        reset = self.rules.disarm_resets_mission
        in_mission = self.mode is not None and self.mode.kind is ModeKind.MISSION
        resets = reset == "always" or (reset == "outside-mission-mode" and not in_mission)
        if resets and self.flight.store.count(MISSION):
            self._complete_seen = False
            self.progress.complete = False
            return self.progress.set_current(self.progress.first_seq, now)
        return []

    def _mission_ended(self, now: float) -> list[Send]:
        """The last item is done, or the mission landed; in the air, the end-of-mission mode."""
        if not self.flight.ground and not self.flight.airborne(now):
            return self._text("mission-landed")
        out = self._text("mission-complete")
        end = self.rules.mode_named(self.rules.mission_end_mode) if self.rules.mission_end_mode else None
        if end is not None and self.mode is not None and self.mode.kind is ModeKind.MISSION:
            out += self._enter(end, now)
        return out

    def _watch_idle(self, now: float) -> None:
        """Armed on the ground and not moving: disarm after disarm_idle_after."""
        after = self.rules.disarm_idle_after
        idle = (after is not None and self._armed and not self.flight.flying and not self.flight.airborne(now)
                and self._disarm_at is None)
        if not idle:
            self._idle_disarm_at = None
        elif self._idle_disarm_at is None:
            self._idle_disarm_at = now + after

    def _plan_unflyable(self) -> bool:
        """A landing is required and the stored mission has none."""
        return self.rules.landing_required and not any(
            it.command in LAND_COMMANDS for it in self.flight.store.items(MISSION))

    def _takeoff_next(self) -> bool:
        """The next navigation item from the current one on is a take-off (AP_Mission::starts_with_takeoff_cmd)."""
        items = self.flight.store.items(MISSION)
        start = max(self.progress.seq, self.progress.first_seq)
        nav = next((it for it in items[start:] if it.command < NAV_LAST), None)
        return nav is not None and nav.command in TAKEOFF_COMMANDS

    def _text(self, event: str) -> list[Send]:
        """The profile's STATUSTEXT for `event` (a refusal is CRITICAL, as both autopilots send
        theirs; news is INFO)."""
        text = self.rules.text(event)
        if not text:
            return []
        mode = self.mode.name if self.mode is not None else ""
        news = event.endswith("-disarmed") or (event.startswith("mission-") and not event.endswith("-refused"))
        severity = _d.MAV_SEVERITY_INFO if news else _d.MAV_SEVERITY_CRITICAL
        return self._statustext(severity, text.replace("{mode}", mode))

    def _statustext(self, severity: int, text: str) -> list[Send]:
        """One STATUSTEXT, or a text longer than its 50 bytes in chunks (upstream: the same
        nonzero id, chunk_seq from 0; a NUL in the text ends the sequence)."""
        data = text.encode()
        if len(data) <= STATUSTEXT_LEN:
            return [Send(_d.MAVLink_statustext_message(severity, data, 0, 0))]
        self._text_id = self._text_id % 0xFFFF + 1
        chunks = [data[i:i + STATUSTEXT_LEN] for i in range(0, len(data), STATUSTEXT_LEN)]
        if len(chunks[-1]) == STATUSTEXT_LEN:
            chunks.append(b"")            # so the last chunk has its NUL
        return [Send(_d.MAVLink_statustext_message(severity, c, self._text_id, i)) for i, c in enumerate(chunks)]


def _whole(value: float, otherwise: int = 0) -> int:
    """A float param as the integer it carries (truncated), `otherwise` for NaN or infinity."""
    return int(value) if math.isfinite(value) else otherwise


def _param7(msg: Any) -> float:
    """Param 7 of a COMMAND_LONG, or the z of a COMMAND_INT (where it travels)."""
    return msg.param7 if hasattr(msg, "param7") else msg.z


def _mode_command(kind: ModeKind) -> Any:
    """A command that is a mode change (RTL, LAND): UNSUPPORTED without such a mode."""
    def handle(self: Autopilot, msg: Any, source: Peer, now: float) -> tuple[int, list[Send]]:
        mode = self.rules.mode_of(kind)
        return (R.UNSUPPORTED, []) if mode is None else self._change_mode(mode, now)
    return handle


_HANDLERS = {
    Cmd.DO_SET_MODE: Autopilot._set_mode,
    Cmd.COMPONENT_ARM_DISARM: Autopilot._arm_disarm,
    Cmd.MISSION_START: Autopilot._mission_start,
    Cmd.NAV_TAKEOFF: Autopilot._takeoff,
    Cmd.NAV_VTOL_TAKEOFF: Autopilot._takeoff,
    Cmd.NAV_RETURN_TO_LAUNCH: _mode_command(ModeKind.RTL),
    Cmd.NAV_LAND: _mode_command(ModeKind.LAND),
    Cmd.NAV_VTOL_LAND: _mode_command(ModeKind.LAND),
    Cmd.REQUEST_MESSAGE: Autopilot._home,
    Cmd.GET_HOME_POSITION: Autopilot._home,
}
