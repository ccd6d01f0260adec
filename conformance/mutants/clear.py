"""Mutants that break the clear clauses (MIS.CLR.*, and MIS.DN.04 through a clear)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType
from mavconform.reference_impl.mission.server import MissionServer

from . import mutant, server_mutant

REPEAT_WINDOW = 3.0   # s


class _ClearWithoutAck(MissionServer):
    def _on_clear_all(self, msg, src, now):
        return [s for s in super()._on_clear_all(msg, src, now) if s.msg.get_type() != "MISSION_ACK"]


class _ClearKeepsPlan(MissionServer):
    def _on_clear_all(self, msg, src, now):
        return [Send(m.ack_message(MissionResult.ACCEPTED, msg.mission_type, src), src)]


class _ClearWipesEveryType(MissionServer):
    def _on_clear_all(self, msg, src, now):
        out = super()._on_clear_all(msg, src, now)
        if any(s.msg.get_type() == "MISSION_ACK" and s.msg.type == MissionResult.ACCEPTED for s in out):
            for t in PLAN_TYPES:
                if self.state(t).name == "IDLE":
                    self.store.clear(t)
        return out


class _ClearAllTypeMissionOnly(MissionServer):
    def _on_clear_all(self, msg, src, now):
        if msg.mission_type != MissionType.ALL:
            return super()._on_clear_all(msg, src, now)
        msg.mission_type = int(MissionType.MISSION)
        out = super()._on_clear_all(msg, src, now)
        for s in out:
            if s.msg.get_type() == "MISSION_ACK":
                s.msg.mission_type = int(MissionType.ALL)
        return out


class _IgnoresRepeatedClear(MissionServer):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._last: dict = {}

    def _on_clear_all(self, msg, src, now):
        key = (src, msg.mission_type)
        t = self._plan_type(msg.mission_type)
        if t is not None and self.store.count(t) == 0 \
                and now - self._last.get(key, -REPEAT_WINDOW) < REPEAT_WINDOW:
            return []   # "that clear is done already"
        self._last[key] = now
        return super()._on_clear_all(msg, src, now)


mutant("clear-without-ack", "clears the plan but never answers MISSION_CLEAR_ALL",
       {"MIS.CLR.01", "MIS.CLR.05"}, server_mutant(_ClearWithoutAck))
mutant("clear-keeps-plan", "answers MISSION_CLEAR_ALL ACCEPTED but clears nothing",
       {"MIS.CLR.02", "MIS.CLR.04", "MIS.DN.04"}, server_mutant(_ClearKeepsPlan))
mutant("clear-wipes-every-type", "clearing one plan type clears the fence and rally plans too",
       {"MIS.CLR.03"}, server_mutant(_ClearWipesEveryType))
mutant("clear-all-type-mission-only", "accepts a clear of MAV_MISSION_TYPE_ALL but clears only the mission",
       {"MIS.CLR.04"}, server_mutant(_ClearAllTypeMissionOnly))
mutant("ignores-repeated-clear", f"ignores a MISSION_CLEAR_ALL repeated within {REPEAT_WINDOW:g} s (nothing left to clear)",
       {"MIS.CLR.05"}, server_mutant(_IgnoresRepeatedClear))
