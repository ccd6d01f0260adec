"""ArduPlane's stored form of a waypoint (storage form "compact15-plane"): the acceptance radius
(param2) and pass-by distance (param3) kept as whole metres 0..255, the hold time (param1) and
yaw (param4) dropped; Copter's compact15 keeps the hold time instead."""

from __future__ import annotations

import math

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.store import STORAGE_FORMS

PLANE, COPTER = STORAGE_FORMS["compact15-plane"], STORAGE_FORMS["compact15"]


def waypoint(p1: float, p2: float, p3: float, p4: float) -> MissionItem:
    return MissionItem(1, 6, int(Cmd.NAV_WAYPOINT), param1=p1, param2=p2, param3=p3, param4=p4,
                       x=473977420, y=85455940, z=12.345)


@pytest.mark.parametrize(("p2", "p3", "kept"), [
    (30.0, 0.0, (30.0, 0.0)), (12.9, 7.6, (12.0, 7.0)), (300.0, 255.5, (255.0, 255.0)),
    (-4.0, math.nan, (0.0, 0.0)), (math.inf, -math.inf, (255.0, 0.0)),
])
def test_a_plane_keeps_radius_and_pass_by_truncated_and_clamped_and_drops_hold_and_yaw(p2, p3, kept):
    stored = PLANE(waypoint(7.0, p2, p3, 45.0))
    assert (stored.param1, stored.param2, stored.param3, stored.param4) == (0.0, *kept, 0.0)
    assert (stored.frame, stored.z) == (3, COPTER(waypoint(7.0, p2, p3, 45.0)).z)   # the rest as compact15


def test_a_copter_keeps_the_hold_and_drops_the_rest():
    stored = COPTER(waypoint(7.9, 30.0, 5.0, 45.0))
    assert (stored.param1, stored.param2, stored.param3, stored.param4) == (7.0, 0.0, 0.0, 0.0)


def test_other_commands_and_plan_types_are_stored_as_compact15():
    loiter = MissionItem(2, 3, int(Cmd.NAV_LOITER_TIME), param1=20.0, param2=1.0, param3=60.0, x=1, y=2, z=30.0)
    rally = MissionItem(0, 3, int(Cmd.NAV_RALLY_POINT), x=1, y=2, z=30.7, mission_type=MissionType.RALLY)
    fence_wp = MissionItem(0, 3, int(Cmd.NAV_WAYPOINT), param1=5.0, param2=9.0, x=1, y=2,
                           mission_type=MissionType.FENCE)
    for it in (loiter, rally, fence_wp):
        assert PLANE(it) == COPTER(it)
