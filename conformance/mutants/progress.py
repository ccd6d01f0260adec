"""Mutants that break the progress clauses (MIS.PRG.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission.progress import MissionProgress
from mavconform.reference_impl.mission.server import MissionServer

from . import mutant, server_mutant


class _NoItemReached(MissionProgress):
    def reached(self, seq, now, **kw):
        return [s for s in super().reached(seq, now, **kw) if s.msg.get_type() != "MISSION_ITEM_REACHED"]


class _SilentCurrentInFlight(MissionProgress):
    """Announces the start and the end of the flight, nothing between (no stream either)."""

    def reached(self, seq, now, **kw):
        out = super().reached(seq, now, **kw)
        return [s for s in out if s.msg.get_type() != "MISSION_CURRENT"] if self.running else out

    def poll(self, now):
        out = super().poll(now)
        return [] if self.running else out


def _with_progress(progress_cls: type[MissionProgress]) -> type[MissionServer]:
    class Server(MissionServer):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.progress = progress_cls(self.store, self.behaviour.current_period)
    return Server


mutant("no-item-reached", "never sends MISSION_ITEM_REACHED",
       {"MIS.PRG.01"}, server_mutant(_with_progress(_NoItemReached)))
mutant("silent-current-in-flight", "sends no MISSION_CURRENT while flying the mission",
       {"MIS.PRG.02"}, server_mutant(_with_progress(_SilentCurrentInFlight)))
