"""Mutants that break the idle and cancellation clauses (MIS.IDL.01, MIS.CAN.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import SlotState

from . import mutant, server_mutant

ACCEPTED, CANCELLED = MissionResult.ACCEPTED, MissionResult.OPERATION_CANCELLED


def _gcs_cancel(server, msg, src, state):
    """The slot a MISSION_ACK OPERATION_CANCELLED from its partner would end, if it is in `state`."""
    t = server._plan_type(msg.mission_type)
    if t is None or msg.type != CANCELLED:
        return None
    slot = server._slots[t]
    return slot if slot.state is state and slot.partner == src else None


class _AcceptsStrayItem(MissionServer):
    def _stray_item(self, msg, t, src, now):
        self.stats.stray += 1
        return [Send(m.ack_message(ACCEPTED, t, src), src)]


class _UploadIgnoresCancel(MissionServer):
    def _on_ack(self, msg, src, now):
        if _gcs_cancel(self, msg, src, SlotState.RECEIVING) is not None:
            return []   # keeps requesting until its retries run out
        return super()._on_ack(msg, src, now)


class _CommitsOnCancel(MissionServer):
    def _on_ack(self, msg, src, now):
        slot = _gcs_cancel(self, msg, src, SlotState.RECEIVING)
        kept = list(slot.received) if slot is not None else []
        out = super()._on_ack(msg, src, now)
        if kept:
            self.store.commit(slot.mission_type, kept)   # keeps the items that did arrive
        return out


class _DownloadIgnoresCancel(MissionServer):
    """Once it has sent an item, a download stays open (for its partner only) until it
    times out, whatever OPERATION_CANCELLED says."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._served = set()

    def _on_request_list(self, msg, src, now):
        self._served.discard(msg.mission_type)
        return super()._on_request_list(msg, src, now)

    def _on_request(self, msg, src, now):
        out = super()._on_request(msg, src, now)
        if any(a.msg._type in (m.ITEM_INT, m.ITEM_FLOAT) for a in out):
            self._served.add(msg.mission_type)
        return out

    def _on_ack(self, msg, src, now):
        if _gcs_cancel(self, msg, src, SlotState.SENDING) is not None and msg.mission_type in self._served:
            return []
        return super()._on_ack(msg, src, now)


class _ResumesCancelledUpload(MissionServer):
    """Remembers a cancelled upload's items; a new MISSION_COUNT of the same size from the
    same GCS, next thing it sends about that plan type, resumes where the old one stopped."""

    _stash = None

    def handle(self, frame, now):
        stash = self._stash
        if stash is not None and frame.msg._type not in ("MISSION_COUNT", "MISSION_ACK") \
                and getattr(frame.msg, "mission_type", None) == stash[0]:
            self._stash = None
        return super().handle(frame, now)

    def _on_ack(self, msg, src, now):
        slot = _gcs_cancel(self, msg, src, SlotState.RECEIVING)
        if slot is not None and slot.received:
            self._stash = (int(slot.mission_type), src, slot.count, list(slot.received))
        return super()._on_ack(msg, src, now)

    def _on_count(self, msg, src, now):
        stash, self._stash = self._stash, None
        out = super()._on_count(msg, src, now)
        if stash is not None and stash[:3] == (msg.mission_type, src, msg.count):
            slot = self._slots[self._plan_type(msg.mission_type)]
            if slot.state is SlotState.RECEIVING:
                slot.received, slot.expected = stash[3], len(stash[3])
                return [Send(self._request_msg(slot), slot.partner)]
        return out


mutant("accepts-stray-item", "answers an item that arrives outside any upload with MISSION_ACK ACCEPTED",
       {"MIS.IDL.01"}, server_mutant(_AcceptsStrayItem))
mutant("upload-ignores-cancel", "ignores MISSION_ACK OPERATION_CANCELLED from the GCS during an upload",
       {"MIS.CAN.01"}, server_mutant(_UploadIgnoresCancel))
mutant("commits-on-cancel", "on OPERATION_CANCELLED from the GCS, stores the upload's items that did arrive",
       {"MIS.CAN.02"}, server_mutant(_CommitsOnCancel))
mutant("download-ignores-cancel", "ignores OPERATION_CANCELLED from the GCS once a download has sent an item",
       {"MIS.CAN.03"}, server_mutant(_DownloadIgnoresCancel))
mutant("resumes-cancelled-upload", "a new upload after a cancelled one resumes at the item where it stopped",
       {"MIS.CAN.04"}, server_mutant(_ResumesCancelledUpload))
