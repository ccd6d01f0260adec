"""The `mission_commands` knob (issue 13): which mission commands a profiled vehicle stores,
by name or number, with the source of the list; the spec vehicle takes every mission command
of the upstream XML."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.commands import LOCATION_COMMANDS, PLAN_COMMANDS, by_name
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.validation import first_defect
from mavconform.reference_impl.profiles import load_profile

# What QGroundControl puts in a survey or an inspection mission besides waypoints.
QGC_COMMANDS = ("DO_SET_ROI_LOCATION", "DO_SET_ROI_NONE", "DO_SET_CAM_TRIGG_DIST",
                "DO_GIMBAL_MANAGER_PITCHYAW", "IMAGE_START_CAPTURE", "IMAGE_STOP_CAPTURE",
                "VIDEO_START_CAPTURE", "VIDEO_STOP_CAPTURE", "DO_CHANGE_SPEED")


def _item(name_or_value, frame: int | None = None) -> MissionItem:
    """An item of the command, in a global frame if it has a location, else MAV_FRAME_MISSION."""
    value = by_name(name_or_value).value if isinstance(name_or_value, str) else name_or_value
    if frame is None:
        frame = 3 if value in LOCATION_COMMANDS else 2
    return MissionItem(0, frame, value, x=473977419, y=85455938, z=30.0)


def _accepts(profile: str, name_or_value) -> bool:
    return first_defect(_item(name_or_value), load_profile(profile).behaviour.item_rules) is None


@pytest.mark.parametrize("profile", ["spec", "px4", "ardupilot"])
@pytest.mark.parametrize("name", QGC_COMMANDS)
def test_every_builtin_vehicle_stores_what_qgc_puts_in_a_mission(profile: str, name: str) -> None:
    assert _accepts(profile, name)


def test_each_profile_narrows_the_set_as_its_autopilot_does() -> None:
    assert not _accepts("px4", "NAV_LOITER_TURNS") and not _accepts("px4", "DO_SET_SERVO")
    assert _accepts("ardupilot", "NAV_LOITER_TURNS") and _accepts("ardupilot", 42703)  # NAV_ATTITUDE_TIME
    assert not _accepts("ardupilot", "DO_SET_CAM_TRIGG_INTERVAL")
    assert _accepts("spec", "DO_SET_CAM_TRIGG_INTERVAL") and not _accepts("spec", 42703)
    for name in ("spec", "px4", "ardupilot"):
        assert not _accepts(name, 31999) and not _accepts(name, "NAV_RALLY_POINT")


def test_the_narrowed_sets_cite_their_source_and_stay_mission_commands() -> None:
    for name, where in (("px4", "parse_mavlink_mission_item"), ("ardupilot", "mavlink_int_to_mission_cmd")):
        setting = load_profile(name).setting("mission_commands")
        assert where in setting.source and setting.why
        named = {by_name(v).value for v in setting.value if isinstance(v, str)}
        assert named <= PLAN_COMMANDS, sorted(named - PLAN_COMMANDS)


def _write(tmp_path, text: str) -> str:
    path = tmp_path / "mine.toml"
    path.write_text(text)
    return str(path)


def test_a_user_profile_narrows_or_reopens_the_set(tmp_path) -> None:
    path = _write(tmp_path, 'name = "survey-only"\nbase = "px4"\n[[knob]]\nknob = "mission_commands"\n'
                            'value = ["NAV_WAYPOINT", "MAV_CMD_NAV_TAKEOFF", 2000]\n')
    rules = load_profile(path).behaviour.item_rules
    assert first_defect(_item("NAV_TAKEOFF", 3), rules) is None and first_defect(_item(2000), rules) is None
    assert first_defect(_item("DO_CHANGE_SPEED"), rules).code == 3          # MAV_MISSION_UNSUPPORTED
    # accept_unknown_commands in a file built on ardupilot replaces the base's mission_commands
    path = _write(tmp_path, 'name = "anything"\nbase = "ardupilot"\n[[knob]]\nknob = "accept_unknown_commands"\n'
                            'value = true\n')
    profile = load_profile(path)
    assert profile.setting("mission_commands") is None
    assert first_defect(_item(31999), profile.behaviour.item_rules) is None
    fence = MissionItem(0, 0, 16, x=1, y=1, mission_type=MissionType.FENCE)
    assert first_defect(fence, profile.behaviour.item_rules) is not None


@pytest.mark.parametrize("value, words", [
    ('["NAV_WARP"]', ["knob[0] (mission_commands)", "'NAV_WARP' is no MAV_CMD of the upstream common.xml"]),
    ("[]", ["expected a non-empty list"]),
    ('"NAV_WAYPOINT"', ["expected a non-empty list"]),
    ("[70000]", ["whole number in 0..65535"]),
    ('["NAV_WAYPOINT", 16]', ["'NAV_WAYPOINT' is listed twice"]),
])
def test_bad_lists_are_one_line_naming_the_knob(tmp_path, value: str, words: list[str]) -> None:
    path = _write(tmp_path, f'name = "x"\n[[knob]]\nknob = "mission_commands"\nvalue = {value}\n')
    with pytest.raises(UsageError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message and path in message and all(w in message for w in words), message


def test_two_knobs_for_the_same_rules_in_one_file_are_refused(tmp_path) -> None:
    path = _write(tmp_path, 'name = "x"\n[[knob]]\nknob = "mission_commands"\nvalue = [16]\n'
                            '[[knob]]\nknob = "accept_unknown_commands"\nvalue = true\n')
    with pytest.raises(UsageError, match=r"knob\[1\] \(accept_unknown_commands\): sets what knob "
                                         r"'mission_commands' sets too"):
        load_profile(path)
