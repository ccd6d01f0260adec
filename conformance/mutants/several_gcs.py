"""Mutants that break the several-GCS and addressing clauses (MIS.GCS.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import SlotEvent, SlotState

from . import mutant, server_mutant


class _RefusesBusyWithError(MissionServer):
    def _deny(self, t, src):
        self.stats.denied += 1
        return [Send(m.ack_message(MissionResult.ERROR, t, src), src)]


class _DenialAbortsTransfer(MissionServer):
    def _deny(self, t, src):
        out = super()._deny(t, src)
        slot = self._slots[t]
        partner = slot.partner
        self._abort(slot, SlotEvent.CANCEL)   # the running transfer is dropped as well
        return out + [Send(m.ack_message(MissionResult.OPERATION_CANCELLED, t, partner), partner)]


class _IgnoresTargetSystem(MissionServer):
    def _addressed_to_us(self, msg):
        return getattr(msg, "target_component", 0) in (0, self.component)


mutant("busy-refusal-not-denied", "refuses another GCS during a transfer with MAV_MISSION_ERROR, not DENIED",
       {"MIS.GCS.01"}, server_mutant(_RefusesBusyWithError))
mutant("denial-aborts-transfer", "when it denies another GCS, also cancels the transfer that is running",
       {"MIS.GCS.02"}, server_mutant(_DenialAbortsTransfer))
mutant("ignores-target-system", "acts on mission messages addressed to any system",
       {"MIS.GCS.03"}, server_mutant(_IgnoresTargetSystem))


class _AnyAckEndsDownload(MissionServer):
    """Takes a MISSION_ACK from any GCS as the end of the running download."""

    def _on_ack(self, msg, src, now):
        t = self._plan_type(msg.mission_type)
        if t is not None and self.state(t) is SlotState.SENDING and self.partner(t) != src:
            src = self.partner(t)   # as if the downloading GCS had sent it
        return super()._on_ack(msg, src, now)


mutant("any-ack-ends-download", "ends a running download on a MISSION_ACK from any GCS, not only the "
       "one downloading", {"MIS.GCS.04"}, server_mutant(_AnyAckEndsDownload))
