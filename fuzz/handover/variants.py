"""Deliberately broken vehicles, one per safety property, and a flight that shows each break.

The properties prove they can fail (DESIGN.md: "the suite must prove it can fail"): each
variant breaks one rule the way a real implementation could, and `WITNESSES` names a flight
on which the property it breaks fails, while the reference vehicle passes the same flight.
"""

from __future__ import annotations

import math
from typing import Any

from mavconform.reference_impl.handover.control_manager import ControlManager
from mavconform.reference_impl.handover.mission_computer import MissionComputer
from mavconform.reference_impl.handover.mission_computer_transitions import HandoverOutcome, McState
from mavconform.reference_impl.wire.dialect import mavlink as _d

from .world import Behaviour, FlightCase, vehicle_with

__all__ = ["VARIANTS", "WITNESSES"]


class OptimisticAckManager(ControlManager):
    """P1: answers a request it refuses and forwards with ACCEPTED instead of FAILED, so the
    requester believes it commands while the owner still does (a manager that ACKs receipt,
    not the outcome)."""

    def _ack(self, to: Any, result: int) -> Any:
        return super()._ack(to, _d.MAV_RESULT_ACCEPTED if result == _d.MAV_RESULT_FAILED else result)


class NeverAbortingComputer(MissionComputer):
    """P2: a handover that cannot complete is never given up (no deadline, no region exit)."""

    def _finish(self, outcome: HandoverOutcome, now: float, detail: str = "", *, event: Any = None) -> list:
        if outcome is HandoverOutcome.ABORTED and event is None:
            self.attempt.commit_by = math.inf
            return []
        return super()._finish(outcome, now, detail, event=event)


class OwnerLossBlindComputer(MissionComputer):
    """P3: the commander's loss is not an emergency: the vehicle flies on with nobody in control."""

    def owner_lost(self, lost: Any, now: float) -> list:
        return []


class ObeysAnyoneManager(ControlManager):
    """P4: the control filter lets every GCS's commands and mission writes through."""

    def screen(self, frame: Any) -> None:
        return None


class RetryingComputer(MissionComputer):
    """P5: an aborted handover is started again at once, in the same region entry."""

    def _finish(self, outcome: HandoverOutcome, now: float, detail: str = "", *, event: Any = None) -> list:
        a = self.attempt
        out = super()._finish(outcome, now, detail, event=event)
        if outcome is HandoverOutcome.ABORTED and a is not None and self.state is McState.ON_MISSION:
            a.watch.used = False
            out += self._maybe_start(now)
        return out


VARIANTS = {
    "optimistic-ack": (vehicle_with(manager=OptimisticAckManager), "P1"),
    "never-aborts": (vehicle_with(mission_computer=NeverAbortingComputer), "P2"),
    "owner-loss-blind": (vehicle_with(mission_computer=OwnerLossBlindComputer), "P3"),
    "obeys-anyone": (vehicle_with(manager=ObeysAnyoneManager), "P4"),
    "retries-in-region": (vehicle_with(mission_computer=RetryingComputer), "P5"),
}

_REFUSING_A = (("A", Behaviour("refuses")),)
WITNESSES = {
    # every handover: B's request is refused and forwarded; this manager says ACCEPTED
    "optimistic-ack": FlightCase(seed=1),
    # A never allows: the handover can only end by aborting
    "never-aborts": FlightCase(seed=2, behaviours=_REFUSING_A, max_duration=300.0),
    # A falls silent for 20 s a minute after take-off, before the handover region
    "owner-loss-blind": FlightCase(seed=3, behaviours=(("A", Behaviour(silent=((60.0, 80.0),))),),
                                   max_duration=150.0),
    # B, not in control, sets the current item, starts the mission and uploads
    "obeys-anyone": FlightCase(seed=4, behaviours=(("B", Behaviour(meddle=((20.0, "set_current_cmd", 3),
                                                                          (30.0, "set_current_msg", 4),
                                                                          (40.0, "upload", 0)))),),
                               max_duration=60.0),
    # A never allows, the region takes 55 s to cross: an abort at 11.25 s, then a retry
    "retries-in-region": FlightCase(seed=5, behaviours=_REFUSING_A, max_duration=200.0),
}
