"""Take-off, return and landing by command or mode (virtual time): a copter climbs by
MAV_CMD_NAV_TAKEOFF in GUIDED, PX4 by switching to AUTO.TAKEOFF; RTL flies home and lands
there (a PX4 fixed-wing loiters), LAND lands where the vehicle is; after landing the vehicle
disarms by itself where its autopilot does."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R

from .pilot import Pilot, plan

COPTER_GUIDED, COPTER_RTL, COPTER_LAND = 4, 6, 9


def takeoff(p: Pilot, altitude: float) -> int:
    return p.command(Cmd.NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, altitude)


def test_a_copter_takes_off_by_command_only_in_guided_armed_on_the_ground():
    p = Pilot("ardupilot")
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED
    assert takeoff(p, 10) == R.FAILED                              # disarmed
    assert p.arm() == R.ACCEPTED and takeoff(p, 0) == R.FAILED      # no altitude: it cannot go down
    assert p.set_mode(0) == R.ACCEPTED and takeoff(p, 10) == R.FAILED          # STABILIZE
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and takeoff(p, 10) == R.ACCEPTED
    p.run(2.0)
    assert 3.0 < p.altitude() < 7.0                                # 2.5 m/s
    p.run(10.0)
    assert p.altitude() == pytest.approx(10.0) and p.armed()        # holding up there
    assert takeoff(p, 20) == R.FAILED                               # not again in the air


def test_a_copter_sent_home_lands_there_and_disarms():
    p = Pilot("ardupilot")
    p.upload(plan((Cmd.NAV_TAKEOFF, None, 20.0), (Cmd.NAV_WAYPOINT, 300.0, 20.0)))
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    p.run(20.0)
    assert p.north() > 50
    assert p.command(Cmd.NAV_RETURN_TO_LAUNCH) == R.ACCEPTED and p.mode() == COPTER_RTL
    assert p.run_until(lambda: not p.armed(), timeout=120)
    assert p.north() < 1.0 and p.altitude() == 0.0


def test_land_lands_where_the_vehicle_is():
    p = Pilot("ardupilot")
    p.upload(plan((Cmd.NAV_TAKEOFF, None, 20.0), (Cmd.NAV_WAYPOINT, 300.0, 20.0)))
    assert p.set_mode(COPTER_GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    p.run(20.0)
    here = p.north()
    assert p.command(Cmd.NAV_LAND) == R.ACCEPTED and p.mode() == COPTER_LAND
    p.run(9.0)
    assert p.altitude() > 0.0 and p.armed()                         # 20 m at 2 m/s
    p.run(3.0)
    assert p.altitude() == 0.0 and not p.armed() and p.north() == pytest.approx(here, abs=0.5)


def test_px4_takes_off_by_switching_to_auto_takeoff_and_returns_home_to_land():
    p = Pilot("px4")
    assert takeoff(p, 15) == R.ACCEPTED and p.mode() == 0x02040000   # AUTO.TAKEOFF, disarmed: nothing yet
    p.run(2.0)
    assert p.altitude() == 0.0
    assert p.arm() == R.ACCEPTED
    p.run(10.0)
    assert p.altitude() == pytest.approx(2.5)                        # MIS_TAKEOFF_ALT: the mode's own altitude
    assert takeoff(p, 15) == R.ACCEPTED
    p.run(10.0)
    assert p.altitude() == pytest.approx(15.0)
    assert p.command(Cmd.NAV_RETURN_TO_LAUNCH) == R.ACCEPTED and p.mode() == 0x05040000
    assert p.run_until(lambda: not p.armed(), timeout=60)
    p.run(0.1)
    assert p.altitude() == 0.0 and "Disarmed by landing" in p.texts()


def test_a_px4_fixed_wing_sent_home_loiters_there_armed():
    p = Pilot("px4-fixedwing")
    p.upload(plan((Cmd.NAV_TAKEOFF, None, 25.0), (Cmd.NAV_WAYPOINT, 500.0, 25.0), (Cmd.NAV_LAND, 900.0, 0.0)))
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    p.run(30.0)
    assert p.command(Cmd.NAV_RETURN_TO_LAUNCH) == R.ACCEPTED
    p.run(120.0)
    assert p.north() < 1.0 and p.altitude() == pytest.approx(25.0) and p.armed()   # RTL_LAND_DELAY -1
    assert p.command(Cmd.NAV_LAND) == R.ACCEPTED
    assert p.run_until(lambda: not p.armed(), timeout=60) and p.altitude() == 0.0


def test_a_vehicle_without_a_land_mode_does_not_take_the_land_command():
    plane = Pilot("ardupilot-plane")                                 # QLAND needs a quadplane
    assert plane.command(Cmd.NAV_LAND) == R.UNSUPPORTED
    assert Pilot("ardupilot-rover").command(Cmd.NAV_LAND) == R.UNSUPPORTED
