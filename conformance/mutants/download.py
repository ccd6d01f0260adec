"""Mutants that break the download clauses (MIS.DN.*)."""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import SlotState

from . import mutant, server_mutant

COUNT_CAP = 5


class _CountCapped(MissionServer):
    def _on_request_list(self, msg, src, now):
        out = super()._on_request_list(msg, src, now)
        for send in out:
            if send.msg.get_type() == "MISSION_COUNT":
                send.msg.count = min(send.msg.count, COUNT_CAP)
        return out


class _DropsParams(MissionServer):
    def _on_request(self, msg, src, now):
        out = super()._on_request(msg, src, now)
        for send in out:
            if send.msg.get_type() == m.ITEM_INT:
                send.msg.param2 = send.msg.param3 = send.msg.param4 = 0.0
        return out


class _NoFloatDownload(MissionServer):
    def _on_request(self, msg, src, now):
        out = super()._on_request(msg, src, now)
        return [Send(m.item_message(self.store.items(self._plan_type(s.msg.mission_type))[s.msg.seq],
                                    s.to, as_int=True), s.to)
                if s.msg.get_type() == m.ITEM_FLOAT else s for s in out]


class _SilentBeyondList(MissionServer):
    def _on_request(self, msg, src, now):
        t = self._plan_type(msg.mission_type)
        if t is not None and self.state(t) is SlotState.SENDING and self.partner(t) == src \
                and msg.seq >= self.store.count(t):
            return []
        return super()._on_request(msg, src, now)


class _IgnoresRepeatedRequest(MissionServer):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._served: dict = {}

    def _on_request_list(self, msg, src, now):
        self._served.pop(msg.mission_type, None)
        return super()._on_request_list(msg, src, now)

    def _on_request(self, msg, src, now):
        if self._served.get(msg.mission_type) == msg.seq:
            return []   # "already sent that one"
        out = super()._on_request(msg, src, now)
        if any(s.msg.get_type() in (m.ITEM_INT, m.ITEM_FLOAT) for s in out):
            self._served[msg.mission_type] = msg.seq
        return out


class _IgnoresAckIn(MissionServer):
    ignored: frozenset[int] = frozenset()

    def _on_ack(self, msg, src, now):
        t = self._plan_type(msg.mission_type)
        if t is not None and self.state(t) is SlotState.SENDING and msg.type in self.ignored:
            return []
        return super()._on_ack(msg, src, now)


class _IgnoresFinalAck(_IgnoresAckIn):
    ignored = frozenset({MissionResult.ACCEPTED})


class _IgnoresErrorAck(_IgnoresAckIn):
    ignored = frozenset(r for r in MissionResult
                        if r not in (MissionResult.ACCEPTED, MissionResult.OPERATION_CANCELLED))


mutant("count-capped", f"reports at most {COUNT_CAP} items in MISSION_COUNT, whatever it stores",
       {"MIS.DN.01"}, server_mutant(_CountCapped))
mutant("int-download-drops-params", "serves MISSION_ITEM_INT with params 2-4 zeroed",
       {"MIS.DN.02"}, server_mutant(_DropsParams))
mutant("no-float-download", "answers MISSION_REQUEST with MISSION_ITEM_INT instead of MISSION_ITEM",
       {"MIS.DN.03"}, server_mutant(_NoFloatDownload))
mutant("silent-beyond-list", "ignores a download request beyond the list instead of an error ACK",
       {"MIS.DN.05"}, server_mutant(_SilentBeyondList))
mutant("ignores-repeated-request", "does not answer a request for the item it has just sent",
       {"MIS.DN.06"}, server_mutant(_IgnoresRepeatedRequest))
# A download kept open also serves a request the GCS sends after it ended (MIS.IDL.01).
mutant("ignores-download-final-ack", "keeps a download open after the GCS's final MISSION_ACK ACCEPTED",
       {"MIS.DN.07", "MIS.IDL.01"}, server_mutant(_IgnoresFinalAck))
mutant("ignores-download-error-ack", "keeps a download open after an error MISSION_ACK other than "
       "OPERATION_CANCELLED", {"MIS.DN.08"}, server_mutant(_IgnoresErrorAck))


class _NeverFlagsCurrent(MissionServer):
    """Serves every downloaded item with current=0, whichever item is current."""

    def _download_item(self, t, seq):
        item = super()._download_item(t, seq)
        return replace(item, current=0) if item.current else item


mutant("never-flags-current", "serves every downloaded item with current=0, the current one too",
       {"MIS.DN.09"}, server_mutant(_NeverFlagsCurrent))
