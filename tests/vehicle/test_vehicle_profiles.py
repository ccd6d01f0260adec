"""The per-vehicle-type builtin profiles and the vehicle-model knobs: every setting sourced,
every mistake one line naming the file and the key, ArduPlane's command list and stored form
on the wire (virtual time)."""

from __future__ import annotations

import re

import pytest

from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.flight_rules import ModeKind
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, KNOBS, load_profile
from mavconform.reference_impl.profiles.knobs import FLIGHT

from ..profiles.profile_files import write_profile
from .pilot import BARE_WAYPOINTS, Pilot

VEHICLE_PROFILES = ("px4-fixedwing", "px4-vtol", "ardupilot-plane", "ardupilot-rover")
VARIANT = re.compile(r"^(HB|[APLI]\d+'?)$")   # I: INAV's rows
SOURCE_LINE = re.compile(r"\S+\.(cpp|h|c|parm|toml|xml)|rc\.\w+|\w+\.h\b|init\.d")


def test_the_vehicle_type_profiles_are_builtin_targets():
    assert set(VEHICLE_PROFILES) < set(BUILTIN_PROFILES)
    for name in VEHICLE_PROFILES:
        assert parse_target(f"builtin:{name}").name == name


@pytest.mark.parametrize("name", [n for n in BUILTIN_PROFILES if n != "spec"])
def test_every_vehicle_model_setting_has_its_row_source_and_reason(name):
    for s in load_profile(name).settings:
        assert VARIANT.match(s.variant) and s.why, s
        if s.knob == "vehicle_type" or KNOBS[s.knob].where == FLIGHT or s.knob in ("params", "cruise_speed"):
            assert SOURCE_LINE.search(s.source), (s.knob, s.source)


def test_the_plane_stores_the_copters_commands_but_the_spline_waypoint():
    copter = load_profile("ardupilot").setting("mission_commands").value
    plane = load_profile("ardupilot-plane").setting("mission_commands").value
    assert [c for c in copter if c != "NAV_SPLINE_WAYPOINT"] == plane and "NAV_SPLINE_WAYPOINT" in copter
    assert load_profile("ardupilot-rover").setting("mission_commands").value == copter


def _waypoint(seq: int, p1: float, p2: float, p3: float, p4: float, command: int = Cmd.NAV_WAYPOINT) -> MissionItem:
    return MissionItem(seq, 3, int(command), param1=p1, param2=p2, param3=p3, param4=p4,
                       x=473990000 + 1000 * seq, y=85450000, z=30.0)


def test_the_plane_refuses_a_spline_waypoint_and_keeps_radius_and_pass_by_not_the_hold():
    plane = Pilot("ardupilot-plane")
    refused = plane.session.upload(MissionType.MISSION, [_waypoint(0, 0, 0, 0, 0, Cmd.NAV_SPLINE_WAYPOINT)])
    assert not refused.ok and refused.nack == MissionResult.UNSUPPORTED
    copter = Pilot("ardupilot")
    assert copter.session.upload(MissionType.MISSION, [_waypoint(0, 0, 0, 0, 0, Cmd.NAV_SPLINE_WAYPOINT)]).ok
    sent = [_waypoint(0, 7.0, 30.6, 300.0, 45.0), _waypoint(1, 2.0, 0.0, 12.9, float("nan"))]
    for pilot, kept in ((plane, [(0.0, 30.0, 255.0, 0.0), (0.0, 0.0, 12.0, 0.0)]),
                        (copter, [(7.0, 0.0, 0.0, 0.0), (2.0, 0.0, 0.0, 0.0)])):
        pilot.upload(sent)
        back = pilot.session.download(MissionType.MISSION)
        assert back.ok and [(it.param1, it.param2, it.param3, it.param4) for it in back.items] == kept


def test_the_vehicle_model_knobs_are_documented_and_land_in_the_flight_rules():
    flight = {k for k, knob in KNOBS.items() if knob.where == FLIGHT}
    assert {"modes", "set_mode_params", "boot_mode", "arming", "mission_start", "landing_required",
            "statustexts", "disarm_after_landing"} <= flight
    for name in flight | {"vehicle_type", "params", "cruise_speed", "item_reached_one_slot"}:
        assert len(KNOBS[name].doc) > 20, name


def _profile(tmp_path, knobs: str, base: str = "px4") -> str:
    return write_profile(tmp_path, f'name = "mine"\nbase = "{base}"\n{knobs}')


@pytest.mark.parametrize(("knobs", "words"), [
    ('[[knob]]\nknob = "vehicle_type"\nvalue = "JET"\n', ["(vehicle_type)", "no MAV_TYPE"]),
    ('[[knob]]\nknob = "modes"\nvalue = [{ name = "A", number = 1 }]\n', ["(modes)", "name, number and does"]),
    ('[[knob]]\nknob = "modes"\nvalue = [{ name = "A", number = 1, does = "fly" }]\n', ["(modes)", "does must be"]),
    ('[[knob]]\nknob = "boot_mode"\nvalue = "WARP"\n', ["boot_mode: 'WARP' is not in the mode table"]),
    ('[[knob]]\nknob = "no_arming_modes"\nvalue = ["AUTO"]\n', ["no_arming_modes: 'AUTO' is not in the mode table"]),
    ('[[knob]]\nknob = "mission_start"\nvalue = "go"\n', ["(mission_start)", "'flies'"]),
    ('[[knob]]\nknob = "command_refusal"\nvalue = "ACCEPTED"\n', ["(command_refusal)", "refusing MAV_RESULT"]),
    ('[[knob]]\nknob = "disarm_after_landing"\nvalue = -1\n', ["(disarm_after_landing)", "seconds >= 0"]),
    ('[[knob]]\nknob = "statustexts"\nvalue = { warp = "x" }\n', ["(statustexts)", "unknown event 'warp'"]),
    ('[[knob]]\nknob = "params"\nvalue = { A_VERY_LONG_PARAMETER_NAME = 1 }\n', ["(params)", "1 to 16 bytes"]),
    ('[[knob]]\nknob = "params"\nvalue = { X = { value = 1, type = "INT128" } }\n', ["(params)", "MAV_PARAM_TYPE"]),
    ('[[knob]]\nknob = "custom_mode_idle"\nvalue = 5\n', ["custom_mode_idle / custom_mode_mission", "boot_mode"]),
])
def test_vehicle_model_mistakes_are_one_line_naming_file_and_key(tmp_path, knobs, words):
    path = _profile(tmp_path, knobs)
    with pytest.raises(UsageError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message and path in message
    for w in words:
        assert w in message, message


def test_a_user_profile_flies_a_vehicle_of_its_own(tmp_path):
    path = _profile(tmp_path, '[[knob]]\nknob = "vehicle_type"\nvalue = "HEXAROTOR"\n'
                              '[[knob]]\nknob = "no_arming_modes"\nvalue = ["AUTO.MISSION"]\n'
                              '[[knob]]\nknob = "cruise_speed"\nvalue = 7.5\n')
    mine = load_profile(path)
    assert (mine.config.vehicle_type, mine.config.speed) == (13, 7.5)
    assert mine.config.flight_rules.mode_of(ModeKind.MISSION).name == "AUTO.MISSION"
    p = Pilot(mine.config)
    assert p.set_mode(4, 4) == R.ACCEPTED and p.arm() == R.TEMPORARILY_REJECTED


def test_custom_mode_idle_and_mission_still_name_the_mode_of_a_vehicle_without_a_mode_table(tmp_path):
    path = write_profile(tmp_path, 'name = "mine"\n[[knob]]\nknob = "custom_mode_idle"\nvalue = 7\n'
                                   '[[knob]]\nknob = "custom_mode_mission"\nvalue = 9\n')
    p = Pilot(load_profile(path).config)
    assert p.mode() == 7 and p.set_mode(9) == R.UNSUPPORTED
    p.upload(BARE_WAYPOINTS)
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED and p.mode() == 9 and p.armed()
