"""Mutants that break the set-current clauses (MIS.CUR.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import Cmd, CommandResult
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.server import MissionServer

from . import knob_mutant, mutant, server_mutant


def _valid(server: MissionServer, seq: int) -> bool:
    return 0 <= seq < server.store.count(MissionType.MISSION)


class _IgnoresSetCurrent(MissionServer):
    def _on_set_current(self, msg, src, now):
        return super()._on_set_current(msg, src, now) if not _valid(self, msg.seq) else []


class _SilentSetCurrentFailure(MissionServer):
    def _on_set_current(self, msg, src, now):
        return super()._on_set_current(msg, src, now) if _valid(self, msg.seq) else []


class _InvalidSetCurrentClamps(MissionServer):
    def _on_set_current(self, msg, src, now):
        out = super()._on_set_current(msg, src, now)
        count = self.store.count(MissionType.MISSION)
        if not _valid(self, msg.seq) and count:
            out += self.progress.set_current(count - 1, now)   # "the nearest valid item"
        return out


class _SetCurrentUnicast(MissionServer):
    def _on_set_current(self, msg, src, now):
        return [Send(s.msg, s.to if s.to is not None else src)
                for s in super()._on_set_current(msg, src, now)]


class _NoSetCurrentCommand(MissionServer):
    def command_set_current(self, seq_param, source, now):
        return [Send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, CommandResult.UNSUPPORTED,
                                           source), source)]


mutant("ignores-set-current", "does nothing on a valid MISSION_SET_CURRENT",
       {"MIS.CUR.01", "MIS.CUR.04"}, server_mutant(_IgnoresSetCurrent))
mutant("silent-set-current-failure", "sends no STATUSTEXT when MISSION_SET_CURRENT fails",
       {"MIS.CUR.02"}, server_mutant(_SilentSetCurrentFailure))
mutant("invalid-set-current-clamps", "a set-current beyond the plan moves to the last item",
       {"MIS.CUR.03"}, server_mutant(_InvalidSetCurrentClamps))
mutant("set-current-unicast", "sends the MISSION_CURRENT answering a set-current only to the requester",
       {"MIS.CUR.04"}, server_mutant(_SetCurrentUnicast))
mutant("no-set-current-command", "answers MAV_CMD_DO_SET_MISSION_CURRENT UNSUPPORTED",
       {"MIS.CUR.05"}, server_mutant(_NoSetCurrentCommand))
mutant("slow-mission-current-stream", "streams MISSION_CURRENT every 3 s instead of every second",
       {"MIS.CUR.06"}, knob_mutant(current_period=3.0))
