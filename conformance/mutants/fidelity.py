"""Mutants for the fidelity survey (conformance/fidelity/): each stores or refuses one kind of
cell otherwise than its profile says, as real autopilots have (a param rounded in a compact
record, an altitude reference dropped, a frame refused), and the survey must catch it in that
cell (tests/conformance/fidelity/). `breaks` lists the clauses the change also fails."""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer

from . import mutant, server_mutant

FENCE_CIRCLE = 5003
DO_CHANGE_SPEED = 178
TERRAIN_FRAMES = (10, 11)


class _RoundsCircleRadius(MissionServer):
    """Keeps a fence circle's radius (param1) in whole metres."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        keep = self._keep
        self._keep = lambda it: keep(replace(it, param1=float(round(it.param1))) if int(it.command) == FENCE_CIRCLE
                                     else it)


class _RoundsChangeSpeed(MissionServer):
    """Keeps DO_CHANGE_SPEED's speed (param2) in whole metres per second, as a compact record
    might, without refusing a speed it cannot keep."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        keep = self._keep
        self._keep = lambda it: keep(replace(it, param2=float(round(it.param2)))
                                     if int(it.command) == DO_CHANGE_SPEED and it.param2 == it.param2 else it)


class _DropsRelativeAltInt(MissionServer):
    """Stores a mission item in MAV_FRAME_GLOBAL_RELATIVE_ALT_INT (6) as MAV_FRAME_GLOBAL_INT (5):
    the altitude, relative to home when sent, comes back as above mean sea level."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        keep = self._keep
        self._keep = lambda it: keep(replace(it, frame=5) if it.frame == 6 and it.mission_type == 0 else it)


class _RefusesTerrainFrames(MissionServer):
    """Refuses mission items in the terrain frames (10, 11) that its profile accepts."""

    def _on_item(self, msg, src, now):
        if msg.frame in TERRAIN_FRAMES and msg.mission_type == 0:
            slot, refusal = self._slot_for(msg, src)
            if refusal is None and msg.seq == slot.expected:
                return self._reject(slot, MissionResult.UNSUPPORTED_FRAME, src)
        return super()._on_item(msg, src, now)


mutant("rounds-circle-radius", "keeps a fence circle's radius in whole metres", set(), server_mutant(_RoundsCircleRadius))
mutant("rounds-change-speed", "keeps DO_CHANGE_SPEED's speed (param2) in whole m/s", set(),
       server_mutant(_RoundsChangeSpeed))
mutant("drops-relative-alt-int", "stores a mission item in frame 6 (relative altitude, INT) as frame 5 (AMSL)",
       set(), server_mutant(_DropsRelativeAltInt))
mutant("refuses-terrain-frames", "refuses mission items in frames 10 and 11, which its profile accepts",
       set(), server_mutant(_RefusesTerrainFrames))
