"""The thesis's mission computer on the vehicle, as a sans-IO state machine (seed 003, ch. 4).

Two rules, after h11's `_state.py`:
- Every change of `state` and of a handover's phase goes through `_move` / `_step`, which
  consult `MC_TABLE` / `PHASE_TRANSITIONS`; a move the tables lack is a bug here.
- No I/O, no clock, no flight model: positions come in with their times (`observe`), frames
  and the system manager's `ControlChanged` events with `now`; out go `Send` actions, a
  `WithdrawTakeover` request for the manager, and `HandoverStarted` / `HandoverFinished`.

Theory of operation. The mission computer knows the parent GCS and every GCS's coverage
(circle, polygon, or the waypoints it owns). From MISSION_STARTED (on_load -> on_mission) it
checks the latest position every `check_period` (the thesis's 50 ms). Each handover region
has a `Latch` (hysteresis.py: margin and dwell): for the geographic methods one per pair of
GCSs, the intersection of their coverages; for the waypoint method one per GCS, "the leg the
vehicle flies is this GCS's" (the last waypoint reached within the acceptance radius). When a
region is entered and the commander (the manager's `gcs_main`) is one of its pair, or is not
the leg's owner, the handover toward the other GCS starts (on_handover), exactly once per
entry. The six steps run over MAVLink operator control (docs/handover.md):

1. the vehicle invites the partner: MAV_CMD_REQUEST_OPERATOR_CONTROL to it, param4 its own id;
2. the partner requests control; the manager refuses it and forwards it to the commander;
3. the commander allows takeover (CONTROL_STATUS: takeover allowed) or releases;
4. the partner's request is granted (CONTROL_STATUS: gcs_main = partner): the commit;
   the vehicle sends the partner the connect notice (the same command, now to the owner);
5. the partner's COMMAND_ACK of the notice: it hears the vehicle as the owner;
6. the old commander's release (param1 0), sent when it sees it lost control.

Bound. A handover ends within `bound` seconds of its start: not committed by
`start + bound - closing_timeout`, it is aborted and the vehicle withdraws the forwarded request
or open takeover window (`WithdrawTakeover`), so the old commander keeps control; committed,
it ends COMPLETED when 5 and 6 are seen, else UNCONFIRMED at `start + bound` (control is not
taken back: the partner was told it holds control, the commander that it does not).
Leaving the region before the commit aborts too. After an abort at the deadline the vehicle
refuses the partner's requests for control until it leaves the region (`screen`): the
commander's allow can still arrive late, and would otherwise hand control over after all.

Emergency (`config.emergency`, emergency_procedure.py; off by default). The system manager's
owner loss (`owner_lost`) or `outside_grace_s` outside every coverage, while flying, moves
on_mission / on_handover to on_emergency: a handover under way ends (ABORTED before the commit,
UNCONFIRMED after), the refuge is chosen with the battery the flight has left, and out go
`EmergencyStarted` (the vehicle diverts), a STATUSTEXT naming trigger and refuge, and
`RevokeControl` (CONTROL_STATUS with no owner). While on_emergency no region is watched and
`screen` refuses every GCS's state-changing message except a control request from a known GCS
covering the vehicle; its grant (`control_changed`) is TAKEN_BACK (on_mission, every region
seen afresh, as at the start of a flight); landing at the refuge (`stop`) is LANDED (on_load).

Its load is in mission_computer_config.py, what it reports in mission_computer_reports.py, and
a handover's steps in mission_computer_sequence.py.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any, Iterable, Sequence

from ..mission.actions import Send
from ..mission.constants import POSITIONAL_COMMANDS
from ..mission.items import GLOBAL_FRAMES, MissionItem
from ..state_table import next_state
from ..wire.dialect import mavlink as _d
from ..wire.frame import Frame
from . import control_messages as cm
from .control_results import ControlChanged, OwnerLost, Refusal
from .emergency_procedure import (BatteryReading, EmergencyConfig, EmergencyEnded, EmergencyStarted, OutsideWatch,
                                  RevokeControl, announcement, commander_lost, ended_text, refuge_for)
from .emergency_procedure import screen as emergency_screen
from .emergency import Trigger
from .geo import GeoPoint
from .hysteresis import Edge, Latch, Presence, Sense, sense_of, sense_when
from .mission_computer_config import THESIS_CHECK_PERIOD, MissionComputerConfig, critical_path_budget
from .mission_computer_reports import (MAX_RESULTS, Action, HandoverFinished, HandoverResult, HandoverStarted,
                                       WithdrawTakeover)
from .mission_computer_sequence import HandoverSequence, _Attempt
from .mission_computer_transitions import MC_TABLE, HandoverOutcome, McEvent, McState, PhaseEvent
from .regions import Intersection, OwnedWaypoints, RegionMethod
from .waypoints import waypoint_reached

__all__ = ["EmergencyConfig", "EmergencyEnded", "EmergencyStarted", "HandoverFinished", "HandoverResult",
           "HandoverStarted", "MissionComputer", "MissionComputerConfig", "RevokeControl", "THESIS_CHECK_PERIOD",
           "WithdrawTakeover", "critical_path_budget", "mission_waypoints"]


def mission_waypoints(items: Iterable[MissionItem]) -> tuple[tuple[int, GeoPoint], ...]:
    """The mission's positional items as (seq, point), for the waypoint method's reach check."""
    return tuple((it.seq, GeoPoint.from_e7(it.x, it.y)) for it in items
                 if it.command in POSITIONAL_COMMANDS and it.frame in GLOBAL_FRAMES)


# --- internals ---------------------------------------------------------------------------------
@dataclass
class _Watch:
    """One handover region: a pair of GCSs (geographic) or one GCS's legs (waypoints)."""

    gcs: tuple[int, ...]
    region: Any                     # the Intersection (geographic) or None (waypoints)
    latch: Latch | None = None      # made at the first check after the start
    used: bool = False              # this entry already started a handover
    barred: int = 0                 # the partner of this entry's handover that was not granted in time

    @property
    def name(self) -> str:
        return "+".join(map(str, self.gcs)) if len(self.gcs) > 1 else f"legs of {self.gcs[0]}"

    def partner_for(self, commander: int) -> int | None:
        if not commander:
            return None
        if len(self.gcs) == 1:
            return self.gcs[0] if self.gcs[0] != commander else None
        if commander in self.gcs:
            return next(g for g in self.gcs if g != commander)
        return None


class MissionComputer(HandoverSequence):
    """Vehicle-side handover: `observe` positions, `handle` frames, `control_changed` events,
    `poll` timers; send and apply what they return."""

    def __init__(self, system: int, component: int, config: MissionComputerConfig, *,
                 record_history: bool = False) -> None:
        self.system = system
        self.component = component
        self.config = config
        self.state = McState.ON_LOAD
        self.commander = 0                      # gcs_main, as the manager last said
        self.attempt: _Attempt | None = None
        self.results: list[HandoverResult] = []
        self.recent: deque[tuple[Any, Any, Any]] = deque(maxlen=256)
        self.history: list[tuple[Any, Any, Any]] = []
        self._record = record_history
        self._position: tuple[GeoPoint, float] | None = None
        self._next_check: float | None = None
        self._watches: list[_Watch] = []
        self._ending = False
        self._waypoints: tuple[tuple[int, GeoPoint], ...] = ()
        self._next_wp = 0
        self.leg_owner: int | None = None
        self._seq_owner = {seq: g for g, cov in config.coverages if isinstance(cov, OwnedWaypoints)
                           for seq in cov.seqs}
        # the emergency procedure
        self.emergency: EmergencyStarted | None = None     # the one under way
        self.emergencies: list[EmergencyStarted] = []       # every one so far (the first MAX_RESULTS)
        self._battery: BatteryReading | None = None
        self._launch: GeoPoint | None = None
        self._outside = OutsideWatch()

    # --- inputs ---------------------------------------------------------------------------
    def start(self, now: float, waypoints: Sequence[tuple[int, GeoPoint]] = ()) -> list[Action]:
        """The flight started (on_load -> on_mission). `waypoints`: the mission's positional
        items in order, for the waypoint method (`mission_waypoints`)."""
        if self.state is not McState.ON_LOAD:
            return []
        self._move(McEvent.MISSION_STARTED)
        self._waypoints, self._next_wp, self.leg_owner = tuple(waypoints), 0, None
        self._watches = self._make_watches()
        self._next_check = now
        self._ending = False
        self._launch = self._position[0] if self._position is not None else None
        self._outside = OutsideWatch()
        return []

    def stop(self, now: float) -> list[Action]:
        """The flight ended. A handover under way runs to its end first; an emergency ends
        here: the vehicle landed at its refuge."""
        if self.state is McState.ON_HANDOVER:
            self._ending = True
        elif self.state is McState.ON_MISSION:
            self._end_mission()
        elif self.state is McState.ON_EMERGENCY:
            self._move(McEvent.LANDED)
            self._next_check, self._watches = None, []
            return self._end_emergency(0, now, "landed at the refuge")
        return []

    def observe(self, point: GeoPoint, at: float, battery: BatteryReading | None = None) -> None:
        """The vehicle's position at time `at` (older than the last one: dropped), with the
        battery left then and its model (None: no battery modelled)."""
        if self._position is None or at >= self._position[1]:
            self._position = (point, at)
            self._battery = battery

    def owner_lost(self, lost: OwnerLost, now: float) -> list[Action]:
        """The system manager dropped the silent owner: the commander-lost trigger, while flying."""
        e = self.config.emergency
        if e is None or not e.commander_lost or not self._flying:
            return []
        trigger = commander_lost(lost, e.policy)
        if trigger is None:
            return []
        self.commander = 0           # the manager has dropped it (its ControlChanged follows)
        return self._emergency(trigger, now, lost.sysid)

    def screen(self, frame: Frame) -> Refusal | None:
        """What the vehicle refuses before the system manager sees it: during the emergency,
        every GCS's state-changing message, and a request for control from a GCS not entitled
        to take it back (emergency_procedure.screen); otherwise a request for control from the
        partner of a handover aborted for want of a grant, until the vehicle has left that
        region (no late message hands it over: the commander's allow may still arrive after
        the abort, from a slow operator or a request that was itself late). None otherwise."""
        if self.state is McState.ON_EMERGENCY:
            return emergency_screen(frame, self.system, self.component, self.may_take_back)
        msg, src = frame.msg, frame.source
        if (not cm.is_request_control(msg) or msg.param1 != cm.ACTION_REQUEST or src[0] == self.commander
                or not cm.addressed_to(msg, self.system, self.component)):
            return None
        w = next((w for w in self._watches if w.barred == src[0] and w.used), None)
        if w is None:
            return None
        ack = cm.command_ack(msg.command, _d.MAV_RESULT_TEMPORARILY_REJECTED, src)
        return Refusal(f"GCS {src[0]}'s handover in region {w.name} was aborted: not before the vehicle leaves it",
                       (Send(ack, src),))

    def may_take_back(self, sysid: int) -> bool:
        """Whether GCS `sysid` may take control during the emergency: takeback is on, the GCS
        has coverage in the mission, and (geographic methods) that coverage holds the vehicle."""
        e = self.config.emergency
        if e is None or not e.takeback or sysid not in self.config.gcs_ids:
            return False
        if self.config.method is RegionMethod.WAYPOINTS:
            return True
        return self._position is not None and self.config.coverage(sysid).contains(self._position[0])

    def control_changed(self, change: ControlChanged, now: float) -> list[Action]:
        """The system manager changed gcs_main or the takeover flag (its CONTROL_STATUS)."""
        previous, self.commander = self.commander, change.owner
        if self.state is McState.ON_EMERGENCY:
            return self._taken_back(now) if change.owner else []
        a = self.attempt
        if a is None:
            if change.owner != previous:
                self._move(McEvent.CONTROL_MOVED)
            return []
        owner = change.owner
        if a.committed:
            if owner != a.partner:
                return self._finish(HandoverOutcome.UNCONFIRMED, now,
                                    f"control moved on to GCS {owner} before steps 5-6 were seen")
            return []
        if owner == a.partner:
            return self._commit(now)
        if owner == 0:
            a.released_at = now if a.released_at is None else a.released_at
            self._step(PhaseEvent.COMMANDER_RELEASED, now)
        elif owner == a.commander:
            if change.takeover_allowed:
                self._step(PhaseEvent.COMMANDER_ALLOWED, now)
        else:
            return self._finish(HandoverOutcome.ABORTED, now, f"control went to GCS {owner}, not the partner")
        return []

    def handle(self, frame: Frame, now: float) -> list[Action]:
        """Frames the system manager has seen: the partner's request and ACKs, the old
        commander's release. Anything else is not the mission computer's business."""
        a = self.attempt
        msg = frame.msg
        if a is None or not cm.addressed_to(msg, self.system, self.component):
            return []
        sender = frame.source[0]
        if msg._type == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL and sender == a.partner:
            if not a.committed:
                a.resend_at = None           # the invitation arrived
            elif a.notice_sent:
                a.resend_at = None
                self._step(PhaseEvent.PARTNER_CONFIRMED, now)
        elif cm.is_request_control(msg):
            if sender == a.partner and msg.param1 == cm.ACTION_REQUEST and not a.committed:
                a.resend_at = None
                if self.commander not in (0, a.partner):
                    self._step(PhaseEvent.PARTNER_REQUESTED, now)
            elif sender == a.commander and msg.param1 == cm.ACTION_RELEASE and a.committed:
                self._step(PhaseEvent.COMMANDER_DISCONNECTED, now)
        return self._finish_if_done(now)

    def poll(self, now: float) -> list[Action]:
        out: list[Action] = []
        a = self.attempt
        if a is not None:
            if not a.committed and now >= a.commit_by:
                a.watch.barred = a.partner
                out += self._finish(HandoverOutcome.ABORTED, now,
                                    f"control not granted to GCS {a.partner} within {self.config.commit_timeout:g} s")
            elif a.committed and now >= a.end_by:
                missing = [s for s in (5, 6) if s not in a.steps]
                out += self._finish(HandoverOutcome.UNCONFIRMED, now,
                                    f"step(s) {', '.join(map(str, missing))} not seen within {self.config.bound:g} s")
            elif a.resend_at is not None and now >= a.resend_at:
                a.resends_left -= 1
                a.resend_at = now + self.config.resend_period if a.resends_left > 0 else None
                out.append(self._notice(a, now))
        if self._next_check is not None and now >= self._next_check:
            self._next_check = now + self.config.check_period
            out += self._check(now)
        return out

    @property
    def _flying(self) -> bool:
        """In the air with a mission (not landed, not waiting for a handover to end after it)."""
        return self.state in (McState.ON_MISSION, McState.ON_HANDOVER) and not self._ending

    def next_deadline(self) -> float | None:
        times = [self._next_check]
        a = self.attempt
        if a is not None:
            times += [a.resend_at, a.end_by if a.committed else a.commit_by]
        present = [t for t in times if t is not None]
        return min(present) if present else None

    # --- the region check -----------------------------------------------------------------
    def _make_watches(self) -> list[_Watch]:
        cfg = self.config
        if cfg.method is RegionMethod.WAYPOINTS:
            return [_Watch((g,), None) for g in cfg.gcs_ids]
        ids = cfg.gcs_ids
        return [_Watch((x, y), Intersection((cfg.coverage(x), cfg.coverage(y))))
                for i, x in enumerate(ids) for y in ids[i + 1:]]

    def _sense(self, w: _Watch, point: GeoPoint) -> Sense:
        if w.region is None:
            return sense_when(self.leg_owner == w.gcs[0])
        return sense_of(w.region, point, self.config.margin_m)

    def _check(self, now: float) -> list[Action]:
        """The 50 ms task: where is the vehicle, which region did it enter or leave."""
        if self._position is None:
            return []
        point, at = self._position
        if self._waypoints:
            self._reach(point)
        out: list[Action] = []
        e = self.config.emergency
        if e is not None and e.outside and self.config.method is not RegionMethod.WAYPOINTS and self._flying:
            self._outside.observe((c for _, c in self.config.coverages), point, at)
            trigger = self._outside.due(now, e.policy)
            if trigger is not None:
                return self._emergency(trigger, now, self.commander)
        for w in self._watches:
            sense = self._sense(w, point)
            if w.latch is None:
                # a region the flight starts in was not entered: no handover for it
                inside = sense is not Sense.OUTSIDE
                w.latch = Latch(self.config.dwell, initial=Presence.IN if inside else Presence.OUT,
                                on_move=self._latch_moved)
                w.used = inside
                continue
            if w.latch.observe(sense, at) is Edge.EXITED:
                w.used, w.barred = False, 0
                a = self.attempt
                if a is not None and a.watch is w and not a.committed:
                    out += self._finish(HandoverOutcome.ABORTED, now, f"left region {w.name} before the grant")
        if self.state is McState.ON_MISSION:
            out += self._maybe_start(now)
        return out

    def _reach(self, point: GeoPoint) -> None:
        """The thesis's second method: the next waypoint is reached within the acceptance
        radius; the leg that starts there is its owner's."""
        wps, radius = self._waypoints, self.config.acceptance_radius_m
        while self._next_wp < len(wps) and waypoint_reached(point, wps[self._next_wp][1], radius):
            self.leg_owner = self._seq_owner.get(wps[self._next_wp][0])
            self._next_wp += 1

    def _maybe_start(self, now: float) -> list[Action]:
        for w in self._watches:
            if w.used or w.latch is None or w.latch.state is not Presence.IN:
                continue
            partner = w.partner_for(self.commander)
            if partner is not None:
                w.used = True
                return self._start(w, partner, now)
        return []

    # --- the emergency procedure ------------------------------------------------------------
    def _emergency(self, trigger: Trigger, now: float, commander: int) -> list[Action]:
        """A trigger fired while flying: end any handover, choose the refuge, announce, divert,
        drop control."""
        e = self.config.emergency
        assert e is not None and self._position is not None
        out: list[Action] = []
        why = f"emergency: {trigger.kind.value}"
        if self.attempt is not None:
            outcome = HandoverOutcome.UNCONFIRMED if self.attempt.committed else HandoverOutcome.ABORTED
            out += self._finish(outcome, now, why, event=McEvent.EMERGENCY)
        else:
            self._move(McEvent.EMERGENCY)
        point = self._position[0]
        home = e.home or self._launch or point
        refuge = refuge_for(point, home, e.rally, self._battery)
        started = EmergencyStarted(trigger, refuge, commander, point,
                                   None if self._battery is None else self._battery[0].remaining_wh, now)
        self.emergency = started
        if len(self.emergencies) < MAX_RESULTS:
            self.emergencies.append(started)
        self._next_check = None                  # no region is watched during the emergency
        return out + [started, announcement(trigger, refuge, commander),
                      RevokeControl(f"{why}: {trigger.reason}; {refuge.reason}")]

    def _taken_back(self, now: float) -> list[Action]:
        """A known GCS covering the vehicle was granted control: back to on_mission, every
        region seen afresh (one the vehicle is in now was not entered), the refuge flight on."""
        self._move(McEvent.TAKEN_BACK)
        for w in self._watches:
            w.latch, w.used, w.barred = None, False, 0
        self._outside = OutsideWatch()
        self._next_check = now
        return self._end_emergency(self.commander, now, f"GCS {self.commander} took control back")

    def _end_emergency(self, owner: int, now: float, how: str) -> list[Action]:
        self.emergency = None
        ended = EmergencyEnded(owner, now, how)
        return [ended, ended_text(ended)]

    def _end_mission(self) -> None:
        self._move(McEvent.MISSION_ENDED)
        self._ending = False
        self._next_check = None
        self._watches = []

    # --- bookkeeping ----------------------------------------------------------------------
    def _move(self, event: McEvent) -> None:
        old = self.state
        self.state = next_state(MC_TABLE, old, event, "mission computer")
        self._record_move(old, event, self.state)

    def _latch_moved(self, old: Presence, event: Any, new: Presence) -> None:
        if new is not old:
            self._record_move(old, event, new)

    def _record_move(self, old: Any, event: Any, new: Any) -> None:
        self.recent.append((old, event, new))
        if self._record:
            self.history.append((old, event, new))
