"""One handover's six steps on the mission computer (mission_computer.py gives them and the
bound): `_Attempt`, the handover under way, and the mixin of `MissionComputer` that starts it,
sends the invitation and the connect notice, records each step as the phase table allows,
and finishes it with its result. The region check that starts a handover and the inputs
that move it stay in mission_computer.py."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..mission.actions import Send
from ..state_table import next_state
from ..wire.dialect import mavlink as _d
from . import control_messages as cm
from .mission_computer_config import MissionComputerConfig
from .mission_computer_reports import (MAX_RESULTS, Action, HandoverFinished, HandoverResult, HandoverStarted,
                                       WithdrawTakeover)
from .mission_computer_transitions import (COMMITTED, PHASE_STEP, PHASE_TRANSITIONS, HandoverOutcome, HandoverPhase,
                                           McEvent, PhaseEvent)

if TYPE_CHECKING:
    from .mission_computer import _Watch


@dataclass
class _Attempt:
    commander: int
    partner: int
    watch: _Watch
    started: float
    commit_by: float
    end_by: float
    phase: HandoverPhase = HandoverPhase.INVITING
    steps: dict[int, float] = field(default_factory=dict)
    resend_at: float | None = None
    resends_left: int = 0
    sent: int = 0                   # invitations / notices sent, for `confirmation`
    released_at: float | None = None   # the commander released before the grant (steps 3 and 6)
    notice_sent: bool = False

    @property
    def committed(self) -> bool:
        return self.phase in COMMITTED


class HandoverSequence:
    """The steps; `MissionComputer` supplies the attributes below and `_move`, `_record_move`,
    `_maybe_start` and `_end_mission`."""

    config: MissionComputerConfig
    commander: int
    attempt: _Attempt | None
    results: list[HandoverResult]
    _ending: bool

    # --- the sequence ---------------------------------------------------------------------
    def _start(self, w: _Watch, partner: int, now: float) -> list[Action]:
        cfg = self.config
        self._move(McEvent.HANDOVER_DUE)
        a = self.attempt = _Attempt(self.commander, partner, w, now, now + cfg.commit_timeout, now + cfg.bound)
        a.steps[1] = now
        a.resends_left = cfg.resends
        a.resend_at = now + cfg.resend_period if cfg.resends else None
        text = cm.statustext(_d.MAV_SEVERITY_INFO, f"Handover {a.commander}->{partner} started")
        return [HandoverStarted(a.commander, partner, w.name, now), self._notice(a, now), Send(text)]

    def _notice(self, a: _Attempt, now: float) -> Send:
        """Step 1's invitation before the commit, step 4's connect notice after it: the
        operator-control command, to the partner, naming the partner (param4). Param 3 is
        the time left (clamped to the XML's 3..60 s): the partner's request timeout."""
        left = (a.end_by if a.committed else a.commit_by) - now
        timeout = min(max(left, cm.TIMEOUT_MIN), cm.TIMEOUT_MAX)
        msg = cm.request_command((a.partner, 0), cm.ACTION_REQUEST, False, timeout, a.partner,
                                 confirmation=min(a.sent, 255))
        a.sent += 1
        return Send(msg, (a.partner, 0))

    def _commit(self, now: float) -> list[Action]:
        a = self.attempt
        self._step(PhaseEvent.GRANTED, now)
        if a.released_at is not None:
            self._step(PhaseEvent.COMMANDER_DISCONNECTED, a.released_at)
        a.sent, a.notice_sent = 0, True
        a.resends_left = self.config.resends
        a.resend_at = now + self.config.resend_period if self.config.resends else None
        return [self._notice(a, now)]

    def _step(self, event: PhaseEvent, now: float) -> None:
        a = self.attempt
        old = a.phase
        a.phase = next_state(PHASE_TRANSITIONS, old, event, "handover sequence")
        if a.phase is not old:
            self._record_move(old, event, a.phase)
        step = {PhaseEvent.PARTNER_CONFIRMED: 5, PhaseEvent.COMMANDER_DISCONNECTED: 6}.get(event, PHASE_STEP[a.phase])
        if a.phase is not old or event in (PhaseEvent.PARTNER_CONFIRMED, PhaseEvent.COMMANDER_DISCONNECTED):
            a.steps.setdefault(step, now)

    def _finish_if_done(self, now: float) -> list[Action]:
        a = self.attempt
        if a is not None and a.phase is HandoverPhase.DONE:
            return self._finish(HandoverOutcome.COMPLETED, now)
        return []

    def _finish(self, outcome: HandoverOutcome, now: float, detail: str = "", *,
                event: McEvent | None = None) -> list[Action]:
        """End the handover under way with `outcome`; the mission computer moves by `event`
        (default: the outcome's own, back to on_mission)."""
        a = self.attempt
        assert a is not None
        self.attempt = None
        self._move(event or {HandoverOutcome.COMPLETED: McEvent.COMPLETED,
                             HandoverOutcome.UNCONFIRMED: McEvent.UNCONFIRMED,
                             HandoverOutcome.ABORTED: McEvent.ABORTED}[outcome])
        result = HandoverResult(outcome, a.commander, a.partner, self.commander, a.started, now,
                                tuple(sorted(a.steps.items())), detail)
        if len(self.results) < MAX_RESULTS:
            self.results.append(result)
        out: list[Action] = []
        if outcome is HandoverOutcome.ABORTED:
            out.append(WithdrawTakeover(a.partner, detail))
        severity = _d.MAV_SEVERITY_INFO if outcome is HandoverOutcome.COMPLETED else _d.MAV_SEVERITY_WARNING
        out += [HandoverFinished(result),
                Send(cm.statustext(severity, f"Handover {a.commander}->{a.partner} {outcome.value}"))]
        if event is not None:
            return out
        if self._ending:
            self._end_mission()
        else:
            out += self._maybe_start(now)
        return out
