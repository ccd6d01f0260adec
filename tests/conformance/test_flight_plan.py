"""The plan the progress clauses fly: realistic for each vehicle class, laid out from home,
sized from the vehicle's radii, flyable where the autopilots say (PX4 fixed-wing needs a
landing and a glide slope under FW_LND_ANG; a rover never climbs)."""

from __future__ import annotations

import math

import pytest

from mavconform.conformance.harness.flight_plan import (CAM_TRIGG_DIST, METRES_PER_DEGREE, VTOL_LAND,
                                                        VTOL_TAKEOFF, Home, layout, radius)
from mavconform.conformance.harness.flight_styles import STYLES, generic_style, style_for
from mavconform.reference_impl.mission.constants import POSITIONAL_COMMANDS, Cmd
from mavconform.reference_impl.vehicle_class import VehicleClass

HOME = Home(-353632610, 1491652299, 584.0)
FLOWN = (VehicleClass.MULTICOPTER, VehicleClass.FIXED_WING, VehicleClass.VTOL, VehicleClass.GROUND)
LANDINGS = {Cmd.NAV_LAND, VTOL_LAND}
TAKEOFFS = {Cmd.NAV_TAKEOFF, VTOL_TAKEOFF}


def _metres(a, b) -> float:
    east = METRES_PER_DEGREE * math.cos(math.radians(HOME.lat / 1e7))
    return math.hypot((a.x - b.x) / 1e7 * METRES_PER_DEGREE, (a.y - b.y) / 1e7 * east)


@pytest.mark.parametrize("vehicle", FLOWN)
def test_every_plan_is_realistic_a_do_command_right_after_two_waypoints(vehicle):
    plan = layout(vehicle, HOME, radius(vehicle, None, None), home_slot=False)
    items = plan.items
    assert [it.seq for it in items] == list(range(len(items))) == plan.flown
    assert plan.navigation == [it.seq for it in items if it.command in POSITIONAL_COMMANDS]
    after_waypoint = [it for prev, it in zip(items, items[1:])
                      if it.command in (Cmd.DO_CHANGE_SPEED, CAM_TRIGG_DIST) and prev.command == Cmd.NAV_WAYPOINT]
    assert len(after_waypoint) == 2
    assert any(it.command == Cmd.NAV_LOITER_TIME and it.param1 > 0 for it in items)
    assert plan.last == items[-1].seq and plan.window_s > plan.path_m / 10


@pytest.mark.parametrize("vehicle", [VehicleClass.MULTICOPTER, VehicleClass.FIXED_WING, VehicleClass.VTOL])
def test_an_aircraft_takes_off_first_and_lands_at_home_last(vehicle):
    plan = layout(vehicle, HOME, 50.0, home_slot=False)
    assert plan.items[0].command in TAKEOFFS and plan.items[0].z > 0
    assert plan.items[-1].command in LANDINGS and plan.items[-1].z == 0
    assert (plan.items[-1].x, plan.items[-1].y) == (HOME.lat, HOME.lon)


def test_a_ground_vehicle_never_climbs_and_needs_no_landing():
    plan = layout(VehicleClass.GROUND, HOME, 3.0, home_slot=False)
    assert all(it.z == 0 for it in plan.items)
    assert not {it.command for it in plan.items} & (LANDINGS | TAKEOFFS)
    assert plan.approach is None


def test_a_fixed_wing_lands_straight_in_below_px4s_glide_slope():
    """PX4's FeasibilityChecker::checkFixedWindLandApproach refuses a landing whose approach
    from the waypoint before it is steeper than FW_LND_ANG (5 degrees by default)."""
    plan = layout(VehicleClass.FIXED_WING, HOME, radius(VehicleClass.FIXED_WING, 50.0, 80.0), home_slot=False)
    approach, land = plan.items[plan.approach], plan.items[-1]
    assert approach.command == Cmd.NAV_WAYPOINT and land.command == Cmd.NAV_LAND
    assert approach.z / _metres(approach, land) < math.tan(math.radians(5.0))
    assert plan.items[0].param1 > 0   # a take-off pitch


def test_the_legs_are_sized_from_the_radii_the_vehicle_reports():
    small = layout(VehicleClass.FIXED_WING, HOME, radius(VehicleClass.FIXED_WING, 10.0, None), home_slot=False)
    large = layout(VehicleClass.FIXED_WING, HOME, radius(VehicleClass.FIXED_WING, 30.0, 90.0), home_slot=False)
    assert small.radius_m == 50.0 and large.radius_m == 90.0 and large.path_m > small.path_m
    legs = [_metres(a, b) for a, b in zip(large.items, large.items[1:])
            if a.command in POSITIONAL_COMMANDS and b.command in POSITIONAL_COMMANDS]
    assert min(legs) >= 2 * 90.0 * 0.99
    assert radius(VehicleClass.MULTICOPTER, 2.0, None) == 8.0 and radius(VehicleClass.MULTICOPTER, 30.0, None) == 60.0
    assert radius(VehicleClass.FIXED_WING, 500.0, 500.0) == 100.0   # bounded: a flight of minutes


def test_a_target_that_keeps_home_in_slot_0_gets_a_placeholder_first():
    plan = layout(VehicleClass.MULTICOPTER, HOME, 8.0, home_slot=True)
    assert (plan.items[0].seq, plan.items[0].x, plan.items[0].y) == (0, HOME.lat, HOME.lon)
    assert plan.flown[0] == 1 and plan.items[1].command == Cmd.NAV_TAKEOFF
    assert [it.seq for it in plan.items] == list(range(len(plan.items)))


def test_every_autopilot_and_class_has_a_style_whose_modes_are_its_own():
    ardupilot, px4 = 3, 12
    assert style_for(ardupilot, VehicleClass.MULTICOPTER).arm_in.custom_mode == 4          # GUIDED
    assert style_for(ardupilot, VehicleClass.FIXED_WING).arm_in.custom_mode == 10          # AUTO, not ACRO (4)
    assert style_for(ardupilot, VehicleClass.GROUND).arm_in.custom_mode == 10
    assert style_for(ardupilot, VehicleClass.GROUND).stop.custom_mode == 4                 # HOLD
    assert style_for(px4, VehicleClass.FIXED_WING).arm_in.custom_mode == 0x04040000        # AUTO.MISSION
    assert style_for(px4, VehicleClass.FIXED_WING).arm_in.params == (1.0, 4.0, 4.0)
    assert style_for(7, VehicleClass.MULTICOPTER) == generic_style(VehicleClass.MULTICOPTER)
    assert style_for(3, VehicleClass.OTHER) is None
    for (_, vehicle), style in STYLES.items():
        assert style.vehicle is vehicle and style.source
        assert style.arm_in is not None and style.arm_in.source
