"""Mutants that break the plan-id clauses (MIS.OID.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.store import MissionStore

from . import mutant, server_mutant

CONSTANT_ID = 0x00C0FFEE


class _DownloadIdDiffers(MissionServer):
    def _on_request_list(self, msg, src, now):
        out = super()._on_request_list(msg, src, now)
        for action in out:
            if action.msg._type == "MISSION_COUNT" and action.msg.opaque_id:
                action.msg.opaque_id ^= 0x1   # not the id the upload was accepted with
        return out


class _ConstantIdStore(MissionStore):
    def commit(self, mission_type, items):
        plan = tuple(items)
        super().commit(mission_type, plan)
        self._ids[mission_type] = CONSTANT_ID if plan else 0
        return self._ids[mission_type]


class _ConstantPlanId(MissionServer):
    def __init__(self, system, component, behaviour=None, store=None, **kwargs):
        super().__init__(system, component, behaviour, store or _ConstantIdStore(), **kwargs)


mutant("download-id-differs", "reports an opaque_id on download other than the one its upload ACK gave",
       {"MIS.OID.01"}, server_mutant(_DownloadIdDiffers))
mutant("constant-plan-id", "gives every stored plan the same opaque_id",
       {"MIS.OID.02"}, server_mutant(_ConstantPlanId))
