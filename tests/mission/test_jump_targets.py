"""A DO_JUMP lands on the same waypoint on every vehicle (virtual time).

A plan names a jump's target (param1) by its position in the plan. A vehicle that keeps its
home at seq 0 (ArduPilot, A1) counts one higher, so the reference GCS adds 1 on upload and
takes it off on download, as QGroundControl's PlanManager does the other way round
(writeMissionItems / _handleMissionItem, whose numbering starts at its home). PX4 jumps to
the 0-based index in its mission (navigator mission_base.cpp do_jump_mission_index): no shift.
"""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.reference_impl.mission.adaptations import HOME_AT_SEQ0, shift_jumps
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile

from ..rigs import vehicle_and_gcs

JUMP_TO, REPEAT = 1, 1


def _plan() -> list[MissionItem]:
    """A, B, DO_JUMP to B once, C: flown A B (jump) B (jump spent) C."""
    wp = lambda seq, north: MissionItem(seq, 3, int(Cmd.NAV_WAYPOINT), x=473977419 + north,  # noqa: E731
                                        y=85455938, z=20.0)
    return [wp(0, 0), wp(1, 300), MissionItem(2, 2, int(Cmd.DO_JUMP), param1=JUMP_TO, param2=REPEAT),
            wp(3, 600)]


def _collapsed(seqs: list[int]) -> list[int]:
    return [s for i, s in enumerate(seqs) if i == 0 or seqs[i - 1] != s]


# (inav: it ignores the _INT mission messages, which the reference GCS does not fall back from
# yet, and stores no DO_JUMP: its mission commands are NAV_WAYPOINT and RTL)
@pytest.mark.parametrize("name", [n for n in BUILTIN_PROFILES if not load_profile(n).int_messages_ignored])
def test_the_jump_lands_on_the_plans_target_when_flown(name: str) -> None:
    profile = load_profile(name)
    home = 1 if profile.behaviour.home_at_seq0 else 0
    # every MISSION_CURRENT sent at once: the one-slot profiles would fold the jump's instant
    # currents (B reached, the jump done 0.1 s later) into one send (item_reached_one_slot)
    behaviour = dataclasses.replace(profile.behaviour, item_reached_one_slot=False)
    rig = vehicle_and_gcs(dataclasses.replace(profile.config, autostart=True, behaviour=behaviour), seed=5)
    plan = _plan()
    result = rig.session.upload(MissionType.MISSION, plan)
    assert result.ok, result.summary()
    assert rig.vehicle.store.items(MissionType.MISSION)[2 + home].param1 == JUMP_TO + home
    rig.net.run_for(60.0)
    currents = [msg.seq - home for msg in rig.gcs.received
                if msg.get_type() == "MISSION_CURRENT" and msg.total == len(plan)]
    # reaching the jump makes C current for an instant, then the jump's target
    assert _collapsed(currents) == [0, 1, 2, 3, JUMP_TO, 2, 3], name
    back = rig.session.download(MissionType.MISSION)
    assert back.ok and back.items[2].param1 == JUMP_TO                # the plan's numbering again
    assert (HOME_AT_SEQ0.id in back.adaptations) == bool(home)


def test_shift_jumps_moves_only_finite_jump_targets() -> None:
    items = [MissionItem(0, 2, int(Cmd.DO_JUMP), param1=3.0, param2=2.0),
             MissionItem(1, 2, int(Cmd.DO_JUMP), param1=float("nan")),
             MissionItem(2, 3, int(Cmd.NAV_WAYPOINT), param1=3.0)]
    up = shift_jumps(items, 1)
    assert (up[0].param1, up[0].param2, up[2]) == (4.0, 2.0, items[2]) and up[1].param1 != up[1].param1
    assert shift_jumps(up, -1)[0] == items[0]
    assert "DO_JUMP" in HOME_AT_SEQ0.description and "PlanManager" in HOME_AT_SEQ0.source
