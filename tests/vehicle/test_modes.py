"""Every builtin vehicle's HEARTBEAT (type, autopilot, boot mode, not armed) and its flight modes
set by MAV_CMD_DO_SET_MODE in its autopilot's encoding (virtual time)."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile
from mavconform.reference_impl.wire.dialect import mavlink as d

from .pilot import ARMED, BARE_WAYPOINTS, Pilot


def px4(main: int, sub: int = 0) -> int:
    return main << 16 | sub << 24


PX4_AUTO, PX4_LOITER, PX4_MISSION = 4, 3, 4        # px4_custom_mode.h
# profile -> (HEARTBEAT.type, autopilot, custom_mode after boot)
IDENTITY = {
    "spec": (d.MAV_TYPE_QUADROTOR, d.MAV_AUTOPILOT_GENERIC_MISSION_FULL, 0),
    "px4": (d.MAV_TYPE_QUADROTOR, d.MAV_AUTOPILOT_PX4, px4(PX4_AUTO, PX4_LOITER)),
    "px4-fixedwing": (d.MAV_TYPE_FIXED_WING, d.MAV_AUTOPILOT_PX4, px4(PX4_AUTO, PX4_LOITER)),
    "px4-vtol": (d.MAV_TYPE_VTOL_FIXEDROTOR, d.MAV_AUTOPILOT_PX4, px4(PX4_AUTO, PX4_LOITER)),
    "ardupilot": (d.MAV_TYPE_QUADROTOR, d.MAV_AUTOPILOT_ARDUPILOTMEGA, 0),          # STABILIZE
    "ardupilot-plane": (d.MAV_TYPE_FIXED_WING, d.MAV_AUTOPILOT_ARDUPILOTMEGA, 0),   # MANUAL
    "ardupilot-rover": (d.MAV_TYPE_GROUND_ROVER, d.MAV_AUTOPILOT_ARDUPILOTMEGA, 0),  # MANUAL
    "inav": (d.MAV_TYPE_QUADROTOR, d.MAV_AUTOPILOT_GENERIC, 0),   # custom_mode not modelled (inav.toml)
}


def test_every_builtin_profile_is_listed_here():
    assert set(IDENTITY) == set(BUILTIN_PROFILES)


@pytest.mark.parametrize("name", sorted(IDENTITY))
def test_the_heartbeat_says_what_the_vehicle_is_and_that_it_is_not_armed(name):
    beat = Pilot(name).beat()
    assert (beat.type, beat.autopilot, beat.custom_mode) == IDENTITY[name]
    assert beat.base_mode == d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and beat.system_status == d.MAV_STATE_STANDBY


def test_ardupilot_takes_the_mode_number_in_param2():
    p = Pilot("ardupilot")
    assert p.set_mode(4) == R.ACCEPTED and p.mode() == 4             # GUIDED
    assert p.set_mode(8) == R.FAILED and p.mode() == 4               # no mode 8 on a copter
    assert p.command(Cmd.DO_SET_MODE, 0, 3) == R.DENIED               # without CUSTOM_MODE_ENABLED
    assert p.set_mode(4) == R.ACCEPTED and not p.armed()


def test_copter_guided_is_acro_on_a_plane():
    """The trap of issue 23: the same DO_SET_MODE means another mode on another vehicle."""
    plane = Pilot("ardupilot-plane")
    assert plane.set_mode(4) == R.ACCEPTED and plane.mode() == 4
    assert plane.vehicle.autopilot.mode.name == "ACRO"
    assert plane.set_mode(15) == R.ACCEPTED and plane.vehicle.autopilot.mode.name == "GUIDED"


@pytest.mark.parametrize("name", ["px4", "px4-fixedwing", "px4-vtol"])
def test_px4_takes_main_and_sub_mode_in_params_2_and_3(name):
    p = Pilot(name)
    assert p.set_mode(PX4_AUTO, PX4_MISSION) == R.ACCEPTED and p.mode() == 0x04040000
    assert p.set_mode(PX4_AUTO, 9) == R.TEMPORARILY_REJECTED and p.mode() == 0x04040000   # no such sub mode here
    assert p.set_mode(3) == R.ACCEPTED and p.mode() == px4(3)                                # POSCTL


def test_the_spec_vehicle_has_no_modes_arming_or_flight_commands_and_is_armed_while_it_flies():
    p = Pilot("spec")
    for command, params in ((Cmd.DO_SET_MODE, (1, 4)), (Cmd.COMPONENT_ARM_DISARM, (1,)),
                            (Cmd.NAV_RETURN_TO_LAUNCH, ()), (Cmd.NAV_LAND, ()), (Cmd.NAV_TAKEOFF, (0,) * 6 + (10,))):
        assert p.command(command, *params) == R.UNSUPPORTED, command
    p.upload(BARE_WAYPOINTS)
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    beat = p.beat()
    assert beat.base_mode & ARMED and beat.system_status == d.MAV_STATE_ACTIVE and beat.custom_mode == 0
    assert p.run_until(lambda: 1 in p.reached(), timeout=60)
    assert not p.armed()                        # the mission is over: it no longer flies


ODD = [float("nan"), float("inf"), float("-inf"), 1e30, -1.0, 0.0, 1.0, 21196.0]
HANDLED = [Cmd.DO_SET_MODE, Cmd.COMPONENT_ARM_DISARM, Cmd.MISSION_START, Cmd.NAV_TAKEOFF, Cmd.NAV_VTOL_TAKEOFF,
           Cmd.NAV_RETURN_TO_LAUNCH, Cmd.NAV_LAND, Cmd.NAV_VTOL_LAND, Cmd.REQUEST_MESSAGE, Cmd.GET_HOME_POSITION]


# (inav: COMMAND_LONG is ignored, as INAV 9.1 has no handler for it: tests/profiles/test_inav_profile.py)
@pytest.mark.parametrize("name", [n for n in sorted(IDENTITY)
                                  if "COMMAND_LONG" not in load_profile(n).config.ignored_messages])
def test_any_params_as_command_long_or_command_int_get_one_answer(name):
    """Fuzzers and careless GCSs send NaN, infinities and huge values: every command the
    autopilot handles is answered, once, whatever its params, in either command message."""
    p = Pilot(name)
    p.upload(BARE_WAYPOINTS)
    for command in HANDLED:
        for value in ODD:
            assert p.command(command, value, value, value, 0, 0, 0, value) in set(R), (command, value)
            start = len(p.gcs.received)
            p.gcs.send(d.MAVLink_command_int_message(1, 1, 3, command, 0, 0, value, value, value, 0, 0, 0, value))
            p.run(0.2)
            acks = [x for x in p.gcs.received[start:] if x.get_type() == "COMMAND_ACK" and x.command == command]
            assert len(acks) == 1, (command, value)
