"""What the thesis's mission computer reports (mission_computer.py is the machine): the
request to withdraw a takeover, a handover's start and its result, and `Action`, everything
its methods return; the mission computer keeps the first `MAX_RESULTS` results (and
emergencies)."""

from __future__ import annotations

from dataclasses import dataclass

from ..mission.actions import Send
from .emergency_procedure import EmergencyEnded, EmergencyStarted, RevokeControl
from .mission_computer_transitions import HandoverOutcome

MAX_RESULTS = 1000


@dataclass(frozen=True)
class WithdrawTakeover:
    """Ask the system manager to end a forwarded request from, or a takeover window for,
    `requester` now (an aborted handover must not complete later)."""

    requester: int
    reason: str


@dataclass(frozen=True)
class HandoverStarted:
    commander: int
    partner: int
    region: str
    at: float


@dataclass(frozen=True)
class HandoverResult:
    outcome: HandoverOutcome
    commander: int                 # the commander when the handover started
    partner: int
    owner: int                     # gcs_main when it ended
    started: float
    finished: float
    steps: tuple[tuple[int, float], ...]   # (thesis step, first seen) in order of step
    detail: str = ""

    @property
    def duration(self) -> float:
        return self.finished - self.started


@dataclass(frozen=True)
class HandoverFinished:
    result: HandoverResult


Action = (Send | WithdrawTakeover | HandoverStarted | HandoverFinished
          | EmergencyStarted | RevokeControl | EmergencyEnded)
