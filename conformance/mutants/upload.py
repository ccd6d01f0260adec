"""Mutants that break the upload clauses (MIS.UP.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.timing import Timings

from . import knob_mutant, mutant, server_mutant


class _NeverGivesUp(MissionServer):
    def _on_timeout(self, slot, now):
        if slot.state.name == "RECEIVING":
            slot.retries = 0   # the retry count never grows: it requests forever
        return super()._on_timeout(slot, now)


mutant("no-retry", "never re-requests an item that did not arrive; gives up at once",
       {"MIS.UP.06"}, knob_mutant(timings=Timings(max_retries=0)))
mutant("slow-retry", "re-requests items every 1000 ms instead of about 250 ms",
       {"MIS.UP.07"}, knob_mutant(timings=Timings(item_timeout=1.0)))
mutant("too-many-retries", "resends a request 8 times before giving up",
       {"MIS.UP.09"}, knob_mutant(timings=Timings(max_retries=8)))
mutant("never-gives-up", "keeps re-requesting a silent upload's item forever",
       {"MIS.UP.08", "MIS.UP.09"}, server_mutant(_NeverGivesUp))


class _RequestsFromOne(MissionServer):
    def _request_msg(self, slot):
        if slot.expected == 0:   # asks for item 1 where item 0 is due
            return m.request_message(1, slot.mission_type, slot.partner, as_int=self.behaviour.request_int)
        return super()._request_msg(slot)


class _SkipsAnItem(MissionServer):
    def _request_msg(self, slot):
        if slot.expected == 1 and slot.count >= 4:  # in longer plans, asks for item 2 where item 1 is due
            return m.request_message(2, slot.mission_type, slot.partner, as_int=self.behaviour.request_int)
        return super()._request_msg(slot)


class _NoFinalAck(MissionServer):
    def _commit(self, t, items, src, now):
        out = super()._commit(t, items, src, now)
        return [a for a in out if a.msg._type != "MISSION_ACK"]


class _AcksButKeepsOld(MissionServer):
    def _commit(self, t, items, src, now):
        if items:
            items = list(self.store.items(t))  # reports success, stores nothing new
        return super()._commit(t, items, src, now)


class _NonAtomic(MissionServer):
    """Writes each item into the stored plan as it arrives (ArduPilot-like, VARIANTS A2)."""
    def _on_item(self, msg, src, now):
        slot, _ = self._slot_for(msg, src)
        before = len(slot.received) if slot is not None else 0
        out = super()._on_item(msg, src, now)
        if slot is not None and slot.state.name == "RECEIVING" and len(slot.received) > before:
            old = list(self.store.items(slot.mission_type))
            self.store.commit(slot.mission_type, slot.received + old[len(slot.received):])
        return out


class _TakesOutOfOrderItems(MissionServer):
    def _on_item(self, msg, src, now):
        slot, _ = self._slot_for(msg, src)
        if slot is not None and slot.state.name == "RECEIVING" and msg.seq > slot.expected:
            slot.expected = msg.seq   # takes the item it got, as if it were the one it asked for
        return super()._on_item(msg, src, now)


class _OutOfOrderIsFatal(MissionServer):
    def _out_of_sequence(self, slot, seq, now):
        return self._reject(slot, MissionResult.INVALID_SEQUENCE, slot.partner)


class _IgnoresGcsErrorAck(MissionServer):
    def _on_ack(self, msg, src, now):
        slot = self._slots.get(self._plan_type(msg.mission_type))
        if slot is not None and slot.state.name == "RECEIVING":
            return []
        return super()._on_ack(msg, src, now)


class _ClearsOnRefusedCount(MissionServer):
    def _on_count(self, msg, src, now):
        out = super()._on_count(msg, src, now)
        t = self._plan_type(msg.mission_type)
        if t is not None and any(a.msg._type == "MISSION_ACK" and a.msg.type == MissionResult.NO_SPACE for a in out):
            self.store.clear(t)
        return out


class _IntOnly(MissionServer):
    def _on_item(self, msg, src, now):
        if msg._type == "MISSION_ITEM":
            slot, refusal = self._slot_for(msg, src)
            if refusal is None and slot.state.name == "RECEIVING":
                return self._reject(slot, MissionResult.UNSUPPORTED, src)
        return super()._on_item(msg, src, now)


class _CountZeroKeepsPlan(MissionServer):
    def _commit(self, t, items, src, now):
        if not items:
            items = list(self.store.items(t))
        return super()._commit(t, items, src, now)


mutant("requests-from-1", "answers MISSION_COUNT with a request for item 1, not item 0",
       {"MIS.UP.01", "MIS.UP.02"}, server_mutant(_RequestsFromOne))
mutant("skips-an-item", "in plans of 4 or more items, requests item 2 after item 0, never item 1",
       {"MIS.UP.02"}, server_mutant(_SkipsAnItem))
mutant("no-final-ack", "stores the plan after the last item but sends no MISSION_ACK",
       {"MIS.UP.03"}, server_mutant(_NoFinalAck))
mutant("acks-but-keeps-old", "answers ACCEPTED after the last item but keeps the old plan",
       {"MIS.UP.04"}, server_mutant(_AcksButKeepsOld))
mutant("non-atomic-upload", "writes each item into the stored plan as it arrives",
       {"MIS.UP.05", "MIS.UP.12", "MIS.UP.17", "MIS.CAN.02"}, server_mutant(_NonAtomic))
mutant("takes-out-of-order-items", "stores an out-of-sequence item instead of re-requesting",
       {"MIS.UP.10", "MIS.UP.11"}, server_mutant(_TakesOutOfOrderItems))
mutant("out-of-order-is-fatal", "ends the upload with INVALID_SEQUENCE on an out-of-sequence item",
       {"MIS.UP.10", "MIS.UP.11"}, server_mutant(_OutOfOrderIsFatal))
mutant("ignores-gcs-error-ack", "goes on requesting items after the GCS's error MISSION_ACK",
       {"MIS.UP.12", "MIS.CAN.01"}, server_mutant(_IgnoresGcsErrorAck))
mutant("clears-on-refused-count", "refuses a too-large count with NO_SPACE but clears the stored plan",
       {"MIS.UP.13"}, server_mutant(_ClearsOnRefusedCount))
mutant("int-only", "rejects MISSION_ITEM (float) items with UNSUPPORTED",
       {"MIS.UP.14"}, server_mutant(_IntOnly))
mutant("float-requests", "requests items with MISSION_REQUEST (float), not MISSION_REQUEST_INT",
       {"MIS.UP.15"}, knob_mutant(request_int=False))
mutant("count-zero-keeps-plan", "answers MISSION_COUNT 0 with ACCEPTED but keeps the plan",
       {"MIS.UP.16"}, server_mutant(_CountZeroKeepsPlan))
