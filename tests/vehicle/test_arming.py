"""Arming and disarming as each autopilot allows it, and what starts the mission (virtual time):
ArduCopter arms in GUIDED and starts with MISSION_START, never arms in AUTO; ArduPlane and
ArduRover arm in AUTO, which starts the mission; PX4 arms on MISSION_START or in AUTO.MISSION;
a fixed-wing or VTOL PX4 flies no plan without a landing; ArduPlane no plan with DO_LAND_START."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R

from .pilot import BARE_WAYPOINTS, TAKEOFF_WP_LAND, Pilot, item, plan

COPTER_AUTO, COPTER_GUIDED, COPTER_RTL = 3, 4, 6
AP_AUTO = 10                     # ArduPlane and ArduRover
PX4_AUTO, PX4_MISSION, PX4_RTL = 4, 4, 5


# --- ArduCopter --------------------------------------------------------------------------------
def test_a_copter_refuses_to_arm_in_auto_and_arms_in_guided():
    p = Pilot("ardupilot")
    p.upload(TAKEOFF_WP_LAND)
    assert p.set_mode(COPTER_AUTO) == R.ACCEPTED          # disarmed, any mode may be entered
    assert p.arm() == R.FAILED and not p.armed()
    assert p.texts()[-1] == "Arm: AUTO mode not armable"
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED and p.armed()
    assert p.arm() == R.ACCEPTED                           # already armed
    assert p.disarm() == R.ACCEPTED and not p.armed()      # on the ground


def test_a_copter_starts_its_mission_in_guided_armed_and_lands_disarms_and_resets_by_itself():
    p = Pilot("ardupilot")
    p.upload(TAKEOFF_WP_LAND)
    assert p.command(Cmd.MISSION_START, 1, 0) == R.DENIED   # first/last item not supported
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED and p.mode() == COPTER_AUTO
    p.run(4.0)
    assert 5.0 < p.altitude() < 15.0 and p.north() < 1.0    # the take-off item: straight up
    assert p.disarm() == R.FAILED and p.armed()              # not in the air
    assert p.run_until(lambda: 4 in p.reached(), timeout=120)   # home at seq 0: the landing is seq 4
    assert p.altitude() == 0.0 and p.armed()
    p.run(1.5)                                               # the land detector's second
    assert not p.armed() and p.mode() == COPTER_AUTO
    assert p.currents()[-1] == 1                             # the disarm reset the mission to item 1


def test_a_copter_armed_on_the_ground_wants_a_take_off_first_and_disarms_when_left_idle():
    p = Pilot("ardupilot")
    p.upload(BARE_WAYPOINTS)
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.FAILED and p.mode() == COPTER_GUIDED
    assert p.texts()[-1] == "Auto: Missing Takeoff Cmd"
    p.run(9.0)
    assert p.armed()
    p.run(2.0)                                               # DISARM_DELAY: 10 s armed on the ground
    assert not p.armed()


def test_mission_start_on_a_disarmed_copter_sets_auto_and_nothing_flies():
    p = Pilot("ardupilot")
    p.upload(TAKEOFF_WP_LAND)
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED and p.mode() == COPTER_AUTO
    p.run(5.0)
    assert p.altitude() == 0.0 and not p.armed() and p.reached() == []
    assert p.arm() == R.FAILED                               # and AUTO cannot be armed in


def test_a_forced_disarm_in_the_air_drops_the_copter():
    p = Pilot("ardupilot")
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 10) == R.ACCEPTED
    p.run(5.0)
    assert p.airborne() and p.disarm() == R.FAILED
    assert p.disarm(force=True) == R.ACCEPTED and not p.armed() and p.altitude() == 0.0


# --- ArduPlane ---------------------------------------------------------------------------------
def test_a_plane_arms_in_auto_which_starts_the_mission_and_disarms_20_s_after_landing():
    p = Pilot("ardupilot-plane")
    p.upload(TAKEOFF_WP_LAND)
    assert p.set_mode(AP_AUTO) == R.ACCEPTED and p.mode() == AP_AUTO and not p.armed()
    assert p.arm() == R.ACCEPTED
    p.run(4.0)
    assert p.altitude() > 5.0                                # climbing: the take-off item
    assert p.run_until(lambda: 4 in p.reached(), timeout=120)
    p.run(19.0)
    assert p.armed()                                         # LAND_DISARMDELAY: 20 s
    p.run(2.0)
    assert not p.armed() and "Auto disarmed" in p.texts()


def test_a_plane_with_do_land_start_in_its_mission_refuses_to_arm():
    p = Pilot("ardupilot-plane")
    p.upload(TAKEOFF_WP_LAND[:3] + [item(3, Cmd.DO_LAND_START, None)] + [item(4, Cmd.NAV_LAND, 300, 0)])
    assert p.set_mode(AP_AUTO) == R.ACCEPTED
    assert p.arm() == R.FAILED and not p.armed()
    assert p.texts()[-1] == "Arm: DO_LAND_START set and RTL_AUTOLAND disabled"
    assert p.arm(force=True) == R.ACCEPTED                   # forced: no checks


def test_a_plane_whose_mission_ends_in_the_air_goes_home_and_loiters_there_armed():
    p = Pilot("ardupilot-plane")
    p.upload(plan((Cmd.NAV_TAKEOFF, None, 30.0), (Cmd.NAV_WAYPOINT, 600.0, 30.0)))
    assert p.set_mode(AP_AUTO) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.run_until(lambda: 2 in p.reached(), timeout=120)
    p.run(1.0)
    assert p.mode() == 11 and "Mission complete, changing mode to RTL" in p.texts()
    p.run(60.0)
    assert p.north() < 1.0 and p.altitude() == pytest.approx(30.0) and p.armed()   # RTL_AUTOLAND 0


def test_a_plane_takes_no_take_off_command():
    p = Pilot("ardupilot-plane")
    assert p.set_mode(15) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 30) == R.FAILED and not p.airborne()


# --- ArduRover ---------------------------------------------------------------------------------
def test_a_rover_arms_in_auto_drives_its_mission_on_the_ground_and_stays_armed():
    p = Pilot("ardupilot-rover")
    p.upload(TAKEOFF_WP_LAND)
    assert p.set_mode(11) == R.ACCEPTED and p.arm() == R.FAILED      # RTL: not armable
    assert p.texts()[-1] == "Arm: Mode not armable"
    assert p.set_mode(AP_AUTO) == R.ACCEPTED and p.arm() == R.ACCEPTED
    heights = []
    assert p.run_until(lambda: heights.append(p.altitude()) or 4 in p.reached(), timeout=200)
    assert max(heights) == 0.0 and p.north() == pytest.approx(200, abs=1)
    p.run(30.0)
    assert p.armed() and "Mission Complete" in p.texts() and p.mode() == AP_AUTO
    assert p.disarm() == R.ACCEPTED and not p.armed()


def test_a_rover_in_hold_stops_where_it_is():
    p = Pilot("ardupilot-rover")
    p.upload(plan((Cmd.NAV_WAYPOINT, 300.0, 0.0)))
    assert p.set_mode(AP_AUTO) == R.ACCEPTED and p.arm() == R.ACCEPTED
    p.run(20.0)
    assert p.set_mode(4) == R.ACCEPTED                       # HOLD
    here = p.north()
    p.run(20.0)
    assert 20 < here < 300 and p.north() == pytest.approx(here) and p.armed()


# --- PX4 ---------------------------------------------------------------------------------------
def test_px4_mission_start_arms_and_flies_and_lands_then_disarms_2_s_later():
    p = Pilot("px4")
    p.upload(TAKEOFF_WP_LAND)
    assert p.command(Cmd.MISSION_START, 4, 0) == R.DENIED        # first item outside the plan
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    assert p.mode() == 0x04040000 and p.armed()
    assert p.run_until(lambda: 3 in p.reached(), timeout=200)
    p.run(1.5)
    assert p.armed()
    p.run(1.0)
    assert not p.armed() and "Mission finished, landed" in p.texts()


def test_px4_arming_in_auto_mission_flies_and_auto_rtl_cannot_be_armed_in():
    p = Pilot("px4")
    p.upload(BARE_WAYPOINTS)                                 # a quad needs no landing
    assert p.set_mode(PX4_AUTO, PX4_RTL) == R.ACCEPTED and p.arm() == R.TEMPORARILY_REJECTED
    assert p.texts()[-1] == "Arming denied: Resolve system health failures first"
    assert p.set_mode(PX4_AUTO, PX4_MISSION) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.run_until(lambda: 1 in p.reached(), timeout=100)
    p.run(1.0)
    assert p.armed() and p.airborne() and p.mode() == 0x04040000 and "Mission finished, loitering" in p.texts()
    assert p.disarm() == R.TEMPORARILY_REJECTED and p.texts()[-1] == "Disarming denied: not landed"


def test_mission_start_on_px4_without_a_mission_is_denied():
    p = Pilot("px4")
    assert p.command(Cmd.MISSION_START, 0, 0) == R.DENIED and not p.armed()
    assert p.texts()[-1] == "Mission start denied! No valid mission"


@pytest.mark.parametrize("name", ["px4-fixedwing", "px4-vtol"])
def test_a_px4_fixed_wing_or_vtol_flies_no_mission_without_a_landing(name):
    p = Pilot(name)
    p.upload(BARE_WAYPOINTS)
    assert p.texts()[-1] == "Mission rejected: Landing waypoint/pattern required."   # 52 bytes: two chunks
    assert p.command(Cmd.MISSION_START, 0, 0) == R.DENIED
    assert p.set_mode(PX4_AUTO, PX4_MISSION) == R.ACCEPTED                  # disarmed: any mode
    assert p.arm() == R.TEMPORARILY_REJECTED and not p.armed()
    p.upload(TAKEOFF_WP_LAND)
    assert p.arm() == R.ACCEPTED
    assert p.run_until(lambda: 3 in p.reached(), timeout=200)
    p.run(2.5)
    assert not p.armed() and p.altitude() == 0.0


def test_a_px4_quad_armed_on_the_ground_disarms_after_10_s_a_fixed_wing_does_not():
    quad, plane = Pilot("px4"), Pilot("px4-fixedwing")
    for p in (quad, plane):
        assert p.set_mode(3) == R.ACCEPTED and p.arm() == R.ACCEPTED     # POSCTL
        p.run(11.0)
    assert not quad.armed() and "Disarmed by auto preflight disarming" in quad.texts()
    assert plane.armed()
