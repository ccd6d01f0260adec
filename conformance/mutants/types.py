"""Mutants that break the plan-type clauses (MIS.TYP.*)."""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import SlotState

from . import mutant, server_mutant


class _MissionUploadClearsRally(MissionServer):
    def _commit(self, t, items, src, now):
        out = super()._commit(t, items, src, now)
        if t is MissionType.MISSION and items:
            self.store.clear(MissionType.RALLY)   # one storage area shared badly
        return out


class _RequestsTypedMission(MissionServer):
    def _request_msg(self, slot):
        return m.request_message(slot.expected, MissionType.MISSION, slot.partner,
                                 as_int=self.behaviour.request_int)


class _DownloadItemsTypedMission(MissionServer):
    def _on_request(self, msg, src, now):
        out = super()._on_request(msg, src, now)
        return [Send(m.item_message(replace(m.item_from_message(a.msg), mission_type=MissionType.MISSION),
                                    a.to, as_int=a.msg._type == m.ITEM_INT), a.to)
                if a.msg._type in (m.ITEM_INT, m.ITEM_FLOAT) else a for a in out]


class _UnknownTypeAsMission(MissionServer):
    def _plan_type(self, raw):
        found = super()._plan_type(raw)
        return MissionType.MISSION if found is None and raw != MissionType.ALL else found


class _ItemsIgnoreMissionType(MissionServer):
    def _on_item(self, msg, src, now):
        t = self._plan_type(msg.mission_type)
        if t is None or self._slots[t].state is SlotState.IDLE:
            for slot in self._slot_list:
                if slot.state is SlotState.RECEIVING and slot.partner == src:
                    msg.mission_type = int(slot.mission_type)   # any item joins the running upload
                    break
        return super()._on_item(msg, src, now)


mutant("mission-upload-clears-rally", "an accepted mission upload wipes the stored rally plan",
       {"MIS.TYP.01"}, server_mutant(_MissionUploadClearsRally))
mutant("requests-typed-mission", "requests upload items with mission_type MISSION whatever the transfer's type",
       {"MIS.TYP.02"}, server_mutant(_RequestsTypedMission))
mutant("download-items-typed-mission", "sends downloaded items with mission_type MISSION whatever the plan's type",
       {"MIS.TYP.03"}, server_mutant(_DownloadItemsTypedMission))
mutant("unknown-type-as-mission", "treats an unknown mission_type as the mission plan instead of refusing it",
       {"MIS.TYP.04"}, server_mutant(_UnknownTypeAsMission))
mutant("items-ignore-mission-type", "takes an item of any plan type into the upload that is running",
       {"MIS.TYP.05"}, server_mutant(_ItemsIgnoreMissionType))
