"""The `mission_commands` knob (issue 13): which mission commands a profiled vehicle stores,
by name or number (or per set of frames, as PX4 does), with the source of the list; the spec
vehicle takes every mission command of the upstream XML. The `location_frames` knob: which
frames an item with a location may use (ArduPilot: MAV_FRAME_MISSION too). Regression tests
for what real PX4 and ArduPilot SITLs answered."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.commands import LOCATION_COMMANDS, PLAN_COMMANDS, by_name
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.validation import first_defect
from mavconform.reference_impl.profiles import load_profile

from ..rigs import vehicle_and_gcs
from .profile_files import write_profile as _write

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


# --- what real targets answered (2026-11-24): `mavconform gcs upload` of a 3-item mission,
# NAV_WAYPOINT frame 3, the command under test, NAV_WAYPOINT frame 3; the command in frame 3
# (MAV_FRAME_GLOBAL_RELATIVE_ALT, with a position) or frame 2 (MAV_FRAME_MISSION, x=y=z=0) ---
OK, U = None, MissionResult.UNSUPPORTED
COMMANDS_TRIED = (16, 18, 115, 176, 183, 195, 206, 1000, 2000, 31999)
# command -> its answers (frame 3, frame 2); PX4 v1.16.0 SITL (SIH), ArduCopter SITL 531699d6
SEEN_ON_PX4 = {16: (OK, "not tried"), 18: (U, U), 115: (U, U), 176: (U, U), 183: (U, U),
               195: (OK, U), 206: (U, OK), 1000: (U, OK), 2000: (U, OK), 31999: (U, U)}
SEEN_ON_ARDUPILOT = {c: (OK, OK) for c in COMMANDS_TRIED} | {176: (U, U), 31999: (U, U)}
# ... and four more cases of AP_Mission's switch, tried in frame 3 only (param1 0 and 1 alike)
SEEN_ON_ARDUPILOT |= {c: (OK, "not tried") for c in (36, 188, 600, 601)}
SEEN = [(profile, command, frame, answers[i])
        for profile, table in (("px4", SEEN_ON_PX4), ("ardupilot", SEEN_ON_ARDUPILOT))
        for command, answers in table.items() for i, frame in enumerate((3, 2))
        if answers[i] != "not tried"]


def _uploaded(profile: str, command: int, frame: int) -> MissionResult | None:
    """The NACK the profiled vehicle gives the 3-item mission (None: accepted), over the
    reference GCS as `mavconform gcs upload` drives it (virtual time)."""
    rig = vehicle_and_gcs(load_profile(profile).config, seed=3)
    wp = lambda seq, north: MissionItem(seq, 3, 16, x=473977419 + north, y=85455938, z=30.0)  # noqa: E731
    middle = (MissionItem(1, 3, command, x=473977919, y=85455938, z=30.0) if frame == 3
              else MissionItem(1, 2, command))
    result = rig.session.upload(MissionType.MISSION, [wp(0, 0), middle, wp(2, 1000)])
    assert result.ok or result.nack is not None, result.summary()
    return None if result.ok else MissionResult(result.nack)


@pytest.mark.parametrize("profile, command, frame, seen", SEEN)
def test_builtin_vehicles_answer_as_the_real_targets_did(profile: str, command: int, frame: int,
                                                         seen: MissionResult | None) -> None:
    assert _uploaded(profile, command, frame) == seen


def test_px4_picks_the_command_list_by_frame_and_refuses_other_frames() -> None:
    """parse_mavlink_mission_item: global frames take the positional list, MAV_FRAME_MISSION
    the other one; a terrain or local frame is refused before the command is looked at."""
    rules = load_profile("px4").behaviour.item_rules
    setting = load_profile("px4").setting("mission_commands")
    assert "v1.16.0" in setting.source and "parse_mavlink_mission_item" in setting.source
    assert [sorted(t["frames"]) for t in setting.value] == [
        ["GLOBAL", "GLOBAL_INT", "GLOBAL_RELATIVE_ALT", "GLOBAL_RELATIVE_ALT_INT"], ["MISSION"]]
    for frame in (0, 5, 6):
        assert first_defect(_item("NAV_TAKEOFF", frame), rules) is None
    assert first_defect(_item("DO_JUMP", 2), rules) is None
    assert first_defect(_item("DO_JUMP", 3), rules).code == U
    for frame in (10, 11, 1, 7):     # terrain and local frames
        assert first_defect(_item(31999, frame), rules).code == MissionResult.UNSUPPORTED_FRAME
    assert first_defect(_item("NAV_WAYPOINT", 2), rules).code == U      # wrong list, not wrong frame


def test_ardupilot_checks_the_frame_of_a_location_only() -> None:
    """AP_Mission::mavlink_int_to_mission_cmd: a command with a location takes MAV_FRAME_MISSION
    or a global frame (terrain too), nothing else; the frame of any other command is not read."""
    rules = load_profile("ardupilot").behaviour.item_rules
    setting = load_profile("ardupilot").setting("location_frames")
    assert "mavlink_int_to_mission_cmd" in setting.source and "531699d6" in setting.source
    for frame in (0, 2, 3, 5, 6, 10, 11):
        assert first_defect(_item("NAV_LOITER_TURNS", frame), rules) is None, frame
    for frame in (1, 7, 8):
        assert first_defect(_item("NAV_LOITER_TURNS", frame), rules).code == MissionResult.UNSUPPORTED_FRAME
        assert first_defect(_item("DO_CHANGE_SPEED", frame), rules) is None
    fence = MissionItem(0, 2, 5003, param1=50.0, mission_type=MissionType.FENCE)   # fence: spec rules
    assert first_defect(fence, rules).code == MissionResult.UNSUPPORTED_FRAME
    spec = load_profile("spec").behaviour.item_rules
    assert first_defect(_item("NAV_LOITER_TURNS", 2), spec).code == MissionResult.UNSUPPORTED_FRAME


def test_a_user_profile_writes_a_frame_table_and_location_frames(tmp_path) -> None:
    path = _write(tmp_path, 'name = "t"\n[[knob]]\nknob = "location_frames"\nvalue = ["MAV_FRAME_MISSION", 3]\n'
                            '[[knob]]\nknob = "mission_commands"\n'
                            '[[knob.value]]\nframes = ["GLOBAL_RELATIVE_ALT"]\ncommands = ["NAV_WAYPOINT"]\n'
                            '[[knob.value]]\nframes = [2]\ncommands = ["DO_JUMP", "NAV_WAYPOINT"]\n')
    rules = load_profile(path).behaviour.item_rules
    assert first_defect(_item("NAV_WAYPOINT", 3), rules) is None
    assert first_defect(_item("NAV_WAYPOINT", 2), rules) is None          # location_frames has 2
    assert first_defect(_item("DO_JUMP", 3), rules).code == U
    assert first_defect(_item("NAV_WAYPOINT", 0), rules).code == MissionResult.UNSUPPORTED_FRAME


@pytest.mark.parametrize("value, words", [
    ('[{frames = ["MISSION"], commands = ["DO_JUMP"]}, {frames = [2], commands = [16]}]',
     ["list 1: frame 2 is in an earlier list too"]),
    ('[{frames = ["NOWHERE"], commands = [16]}]', ["list 0: 'NOWHERE' is no MAV_FRAME"]),
    ('[{frames = [], commands = [16]}]', ["list 0: expected a non-empty list of MAV_FRAME"]),
    ('[{frames = [3], commands = [16, "NAV_WAYPOINT"]}]', ["list 0: 16 is listed twice"]),
    ('[{frames = [3]}]', ["list 0: expected the keys frames and commands"]),
])
def test_bad_frame_tables_are_one_line_naming_the_knob(tmp_path, value: str, words: list[str]) -> None:
    path = _write(tmp_path, f'name = "x"\n[[knob]]\nknob = "mission_commands"\nvalue = {value}\n')
    with pytest.raises(UsageError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message and "knob[0] (mission_commands)" in message, message
    assert all(w in message for w in words), message


def test_bad_location_frames_are_refused(tmp_path) -> None:
    for value, words in (('["MISSION", 2]', "listed twice"), ("[300]", "0..255"), ('"MISSION"', "non-empty list")):
        path = _write(tmp_path, f'name = "x"\n[[knob]]\nknob = "location_frames"\nvalue = {value}\n')
        with pytest.raises(UsageError, match=words):
            load_profile(path)
