"""The `nan_params` knob (A23): which params 1-4 of which mission commands may be NaN, checked
before anything else, as ArduPilot's AP_Mission::sanity_check_params does; +-inf is refused
in any. The `location_alt_max` knob (A24): ArduPilot's cap on a location's altitude. The spec
and PX4 vehicles take NaN anywhere ("use the default") and are unchanged."""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.commands import LOCATION_COMMANDS, by_name
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.validation import ItemRule, first_defect
from mavconform.reference_impl.profiles import load_profile

from ..rigs import vehicle_and_gcs
from .profile_files import write_profile as _write

NAN, INF = float("nan"), float("inf")
PARAM = {1: MissionResult.INVALID_PARAM1, 2: MissionResult.INVALID_PARAM2,
         3: MissionResult.INVALID_PARAM3, 4: MissionResult.INVALID_PARAM4}
# AP_Mission.cpp sanity_check_params (ArduPilot 531699d652, L1013-1060): its nan_mask per command.
ARDUPILOT_MASK = {"NAV_WAYPOINT": {4}, "NAV_LOITER_UNLIM": {4}, "NAV_LAND": {4}, "NAV_TAKEOFF": {4},
                  "NAV_ARC_WAYPOINT": {2, 3, 4}, "NAV_VTOL_TAKEOFF": {4}, "NAV_VTOL_LAND": {3, 4}}
# Commands no NaN may reach: QGC's survey and camera commands, other NAV ones, an unknown one.
NO_NAN = ("DO_GIMBAL_MANAGER_PITCHYAW", "DO_SET_ROI_LOCATION", "IMAGE_START_CAPTURE", "DO_CHANGE_SPEED",
          "NAV_LOITER_TIME", "NAV_LOITER_TURNS", "NAV_SPLINE_WAYPOINT", "NAV_RETURN_TO_LAUNCH",
          "DO_SET_CAM_TRIGG_INTERVAL", 31999)


def _rules(profile: str) -> tuple[ItemRule, ...]:
    return load_profile(profile).behaviour.item_rules


def _value(command: str | int) -> int:
    return by_name(command).value if isinstance(command, str) else command


def _item(command: str | int, **fields) -> MissionItem:
    """An item of the command, in a relative global frame at a real spot if it has a location,
    else in MAV_FRAME_MISSION."""
    value = _value(command)
    at = dict(frame=3, x=473977419, y=85455938, z=30.0) if value in LOCATION_COMMANDS else dict(frame=2)
    return MissionItem(0, command=value, **(at | fields))


def _code(item: MissionItem, rules: tuple[ItemRule, ...]) -> MissionResult | None:
    defect = first_defect(item, rules)
    return None if defect is None else defect.code


# --- what ArduCopter SITL 531699d6 answered (2026-11-24) ------------------------------------

def _uploaded(profile: str, middle: MissionItem) -> MissionResult | None:
    """The NACK a profiled vehicle gives waypoint, `middle`, waypoint (None: accepted),
    uploaded by the reference GCS in virtual time."""
    rig = vehicle_and_gcs(load_profile(profile).config, seed=5)
    wp = lambda seq, north: MissionItem(seq, 3, 16, x=473977419 + north, y=85455938, z=30.0)  # noqa: E731
    result = rig.session.upload(MissionType.MISSION, [wp(0, 0), dataclasses.replace(middle, seq=1), wp(2, 1000)])
    assert result.ok or result.nack is not None, result.summary()
    return None if result.ok else MissionResult(result.nack)


GIMBAL_NAN = MissionItem(0, 2, 1000, param1=-45.0, param3=NAN, param4=NAN)   # a .plan's nulls, read
GIMBAL_ZERO = dataclasses.replace(GIMBAL_NAN, param3=0.0, param4=0.0)


def test_ardupilot_refuses_the_gimbal_item_with_nan_rates_as_sitl_did() -> None:
    assert _uploaded("ardupilot", GIMBAL_NAN) == MissionResult.INVALID_PARAM3
    assert _uploaded("ardupilot", dataclasses.replace(GIMBAL_NAN, param4=0.0)) == MissionResult.INVALID_PARAM3
    assert _uploaded("ardupilot", GIMBAL_ZERO) is None


@pytest.mark.parametrize("profile", ["spec", "px4"])
def test_spec_and_px4_take_the_gimbal_item_with_nan_rates(profile: str) -> None:
    assert _uploaded(profile, GIMBAL_NAN) is None and _uploaded(profile, GIMBAL_ZERO) is None


def test_the_knob_holds_the_mask_with_its_source() -> None:
    setting = load_profile("ardupilot").setting("nan_params")
    assert setting.variant == "A23" and "sanity_check_params" in setting.source
    assert "531699d652" in setting.source and setting.seen_on
    assert {k: set(v) for k, v in setting.value.items()} == ARDUPILOT_MASK


# --- the mask, param by param ----------------------------------------------------------------

MASK_CASES = [(command, n) for command in (*ARDUPILOT_MASK, *NO_NAN) for n in (1, 2, 3, 4)]


@pytest.mark.parametrize("command, n", MASK_CASES)
def test_ardupilot_takes_nan_only_where_its_mask_allows(command: str | int, n: int) -> None:
    rules = _rules("ardupilot")
    name = f"param{n}"
    plain = _code(_item(command), rules)          # what the item draws with its params at 0
    allowed = n in ARDUPILOT_MASK.get(command, set())
    assert _code(_item(command, **{name: NAN}), rules) == (plain if allowed else PARAM[n])
    for inf in (INF, -INF):
        assert _code(_item(command, **{name: inf}), rules) == PARAM[n]


@pytest.mark.parametrize("profile", ["spec", "px4"])
@pytest.mark.parametrize("command, n", MASK_CASES)
def test_spec_and_px4_take_nan_anywhere_and_refuse_inf_after_the_command(profile: str, command: str | int,
                                                                          n: int) -> None:
    rules = _rules(profile)
    name = f"param{n}"
    plain = _code(_item(command), rules)
    assert _code(_item(command, **{name: NAN}), rules) == plain
    wanted = plain if plain in (MissionResult.UNSUPPORTED, MissionResult.UNSUPPORTED_FRAME) else PARAM[n]
    assert _code(_item(command, **{name: INF}), rules) == wanted


def test_the_first_bad_param_wins_and_params_go_before_command_and_frame() -> None:
    """mavlink_int_to_mission_cmd calls sanity_check_params first (L1073): params 1-4 in order,
    then the command's own case (UNSUPPORTED in its default), location, frame (L1519)."""
    rules = _rules("ardupilot")
    assert _code(_item("DO_CHANGE_SPEED", param2=INF, param3=NAN), rules) == MissionResult.INVALID_PARAM2
    assert _code(_item("DO_CHANGE_SPEED", param1=NAN, param2=INF), rules) == MissionResult.INVALID_PARAM1
    assert _code(_item("NAV_WAYPOINT", param4=NAN, param3=INF), rules) == MissionResult.INVALID_PARAM3
    assert _code(_item(31999), rules) == MissionResult.UNSUPPORTED
    assert _code(_item(31999, param1=NAN), rules) == MissionResult.INVALID_PARAM1
    assert _code(_item("NAV_LOITER_TURNS", frame=1), rules) == MissionResult.UNSUPPORTED_FRAME
    assert _code(_item("NAV_LOITER_TURNS", frame=1, param2=NAN), rules) == MissionResult.INVALID_PARAM2
    assert _code(_item("NAV_WAYPOINT", param1=NAN), rules) == MissionResult.INVALID_PARAM1
    spec = _rules("spec")     # the spec vehicle: command first, NaN is "use the default"
    assert _code(_item(31999, param1=NAN), spec) == MissionResult.UNSUPPORTED
    assert _code(_item(31999, param1=INF), spec) == MissionResult.UNSUPPORTED
    assert _code(_item("NAV_WAYPOINT", param1=NAN), spec) is None


def test_fence_and_rally_items_keep_the_spec_rules() -> None:
    """sanity_check_params is AP_Mission's: fence and rally items go through other code."""
    rules = _rules("ardupilot")
    fence = MissionItem(0, 3, 5003, param1=50.0, param2=NAN, x=1, y=1, mission_type=MissionType.FENCE)
    rally = MissionItem(0, 3, 5100, param1=NAN, x=1, y=1, z=30.0, mission_type=MissionType.RALLY)
    assert _code(fence, rules) is None and _code(rally, rules) is None
    assert _code(dataclasses.replace(rally, param1=INF), rules) == MissionResult.INVALID_PARAM1


# --- the location's altitude (A24) ----------------------------------------------------------

@pytest.mark.parametrize("command", ["NAV_WAYPOINT", "DO_SET_ROI_LOCATION", "NAV_LOITER_TURNS"])
def test_ardupilot_caps_the_altitude_of_a_location(command: str) -> None:
    rules = _rules("ardupilot")
    for z in (82_999.0, -82_999.0, 0.0):
        assert _code(_item(command, z=z), rules) is None, z
    for z in (83_000.0, -83_000.0, 1e9, NAN, INF, -INF):
        assert _code(_item(command, z=z), rules) == MissionResult.INVALID_PARAM7, z
    assert _code(_item("DO_CHANGE_SPEED", z=1e9), rules) is None          # no location: z unread
    setting = load_profile("ardupilot").setting("location_alt_max")
    assert setting.variant == "A24" and "LOCATION_ALT_MAX_M" in setting.source


def test_spec_needs_a_finite_destination_altitude_only() -> None:
    rules = _rules("spec")
    assert _code(_item("NAV_WAYPOINT", z=1e9), rules) is None
    assert _code(_item("NAV_WAYPOINT", z=NAN), rules) == MissionResult.INVALID_PARAM7
    assert _code(_item("DO_SET_ROI_LOCATION", z=NAN), rules) is None   # an ROI is no destination


def test_px4_checks_no_altitude() -> None:
    """P28: PX4 v1.16's parser copies z as sent (mavlink_mission.cpp L1419); its SIH stored a
    NAV_VTOL_LAND with a NaN altitude (the fidelity survey's cell 85 p7:nan)."""
    rules = _rules("px4")
    assert _code(_item("NAV_WAYPOINT", z=1e9), rules) is None
    assert _code(_item("NAV_WAYPOINT", z=NAN), rules) is None


# --- profile files --------------------------------------------------------------------------


def test_a_user_profile_writes_its_own_mask(tmp_path) -> None:
    path = _write(tmp_path, 'name = "strict"\nbase = "spec"\n[[knob]]\nknob = "nan_params"\n'
                            'value = { MAV_CMD_NAV_LOITER_TIME = [4], "1000" = [3, 4] }\n')
    rules = load_profile(path).behaviour.item_rules
    assert _code(_item("NAV_LOITER_TIME", param4=NAN), rules) is None
    assert _code(_item("NAV_WAYPOINT", param4=NAN), rules) == MissionResult.INVALID_PARAM4
    assert _code(GIMBAL_NAN, rules) is None
    path = _write(tmp_path, 'name = "none"\nbase = "ardupilot"\n[[knob]]\nknob = "nan_params"\nvalue = {}\n')
    rules = load_profile(path).behaviour.item_rules
    assert _code(_item("NAV_WAYPOINT", param4=NAN), rules) == MissionResult.INVALID_PARAM4


@pytest.mark.parametrize("knob, value, words", [
    ("nan_params", "[4]", "expected a table of MAV_CMD names"),
    ("nan_params", "{ NAV_WARP = [4] }", "'NAV_WARP' is no MAV_CMD"),
    ("nan_params", "{ NAV_WAYPOINT = [5] }", "NAV_WAYPOINT: expected a whole number in 1..4"),
    ("nan_params", "{ NAV_WAYPOINT = [] }", "NAV_WAYPOINT: expected a non-empty list of params 1-4"),
    ("nan_params", "{ NAV_WAYPOINT = [4, 4] }", "4 is listed twice"),
    ("nan_params", '{ NAV_WAYPOINT = [4], "16" = [4] }', "command 16 is listed twice"),
    ("location_alt_max", "0", "metres > 0"),
    ("location_alt_max", '"high"', "metres > 0"),
])
def test_bad_values_are_one_line_naming_the_knob(tmp_path, knob: str, value: str, words: str) -> None:
    path = _write(tmp_path, f'name = "x"\n[[knob]]\nknob = "{knob}"\nvalue = {value}\n')
    with pytest.raises(UsageError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message and f"knob[0] ({knob})" in message and words in message, message
