"""Profile files: a user's profile builds on a builtin one; every mistake is one line
naming the file and the key."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import load_profile

from .profile_files import write_profile as _write


def test_a_user_profile_overrides_a_knob_of_its_base(tmp_path) -> None:
    path = _write(tmp_path, 'name = "fork"\nbase = "px4"\n[[knob]]\nknob = "retry_cap"\nvalue = true\n'
                            '[[knob]]\nknob = "max_retries"\nvalue = 3\n')
    fork, px4 = load_profile(path), load_profile("px4")
    assert fork.name == "fork" and fork.description == px4.description
    assert fork.behaviour.retry_cap and fork.behaviour.timings.max_retries == 3
    assert fork.behaviour.timings.protocol_timeout == 5.0 and fork.behaviour.sequential_download
    assert [s.knob for s in fork.settings][: len(px4.settings)] == [s.knob for s in px4.settings]
    assert fork.setting("retry_cap").value is True and fork.config.autopilot == 12


def test_the_alternative_of_a_disputed_knob_can_be_chosen(tmp_path) -> None:
    px4 = load_profile("px4")
    alt = px4.setting("supported_types").alternative
    assert alt.variant == "P1" and alt.value == ["mission", "fence"]
    path = _write(tmp_path, 'name = "old-px4"\nbase = "px4"\n[[knob]]\nknob = "supported_types"\n'
                            'value = ["mission", "fence"]\nvariant = "P1"\n')
    assert MissionType.RALLY not in load_profile(path).behaviour.supported_types


def test_a_base_may_be_another_file_beside_it(tmp_path) -> None:
    _write(tmp_path, 'name = "a"\nbase = "ardupilot"\n[[knob]]\nknob = "item_timeout"\nvalue = 0.5\n', "a.toml")
    path = _write(tmp_path, 'name = "b"\nbase = "a.toml"\n', "b.toml")
    b = load_profile(path)
    assert b.behaviour.timings.item_timeout == 0.5 and b.behaviour.home_at_seq0


@pytest.mark.parametrize("text, words", [
    ('name = "x"\n[[knob]]\nknob = "warp_drive"\nvalue = 1\n', ["knob[0]", "unknown knob 'warp_drive'"]),
    ('name = "x"\n[[knob]]\nknob = "retry_cap"\nvalue = "yes"\n', ["knob[0] (retry_cap)", "bad value"]),
    ('name = "x"\n[[knob]]\nknob = "item_timeout"\nvalue = -1\n', ["(item_timeout)", "seconds > 0"]),
    ('name = "x"\n[[knob]]\nknob = "retry_cap"\n', ["(retry_cap)", "'value' is missing"]),
    ('name = "x"\n[[knob]]\nknob = "retry_cap"\nvalue = true\ncolour = 1\n', ["unknown key 'colour'"]),
    ('name = "x"\nflavour = 1\n', ["unknown key 'flavour'"]),
    ('description = "no name"\n', ["'name'"]),
    ('name = "x"\nbase = "nowhere.toml"\n', ["base = 'nowhere.toml'", "no such profile"]),
    ('name = "x"\n[[knob]]\nknob = "retry_cap"\nvalue = false\n', ["retry_cap=False needs timings.protocol_timeout"]),
    ('name = = "x"\n', ["not valid TOML"]),
])
def test_mistakes_are_one_line_naming_file_and_key(tmp_path, text: str, words: list[str]) -> None:
    path = _write(tmp_path, text)
    with pytest.raises(UsageError) as err:
        load_profile(path)
    message = str(err.value)
    assert "\n" not in message and path in message
    for w in words:
        assert w in message, message


def test_a_base_cycle_is_reported_not_followed_forever(tmp_path) -> None:
    _write(tmp_path, 'name = "a"\nbase = "b.toml"\n', "a.toml")
    path = _write(tmp_path, 'name = "b"\nbase = "a.toml"\n', "b.toml")
    with pytest.raises(UsageError, match="cycle"):
        load_profile(path)


def test_an_unknown_name_lists_the_builtins() -> None:
    with pytest.raises(UsageError, match="builtin: spec, px4, px4-fixedwing, px4-vtol, ardupilot, ardupilot-plane, "
                                         "ardupilot-rover"):
        load_profile("betaflight")


def test_stored_items_is_identity_for_spec_and_the_compact_record_for_ardupilot() -> None:
    items = [MissionItem(0, 6, 16, param1=2.7, param2=3.0, param4=90.0, x=1, y=2, z=10.129),
             MissionItem(1, 3, 16, param1=float("nan"), z=-1.5)]
    assert load_profile("spec").stored_items(items, MissionType.MISSION) == tuple(items)
    a, b = load_profile("ardupilot").stored_items(items, MissionType.MISSION)
    assert (a.frame, a.param1, a.param2, a.param4, a.x, a.y) == (3, 2.0, 0.0, 0.0, 1, 2)
    assert abs(a.z - 10.12) < 1e-5 and b.param1 == 0.0 and abs(b.z + 1.5) < 1e-6
    rally = load_profile("ardupilot").stored_items([MissionItem(0, 3, 5100, param1=1.0, z=20.7)], MissionType.RALLY)
    assert (rally[0].z, rally[0].param1, rally[0].mission_type) == (20.0, 0.0, MissionType.RALLY)


def test_a_profile_vehicle_takes_config_overrides() -> None:
    node = load_profile("ardupilot").vehicle(system=7)
    assert node.config.system == 7 and node.server.behaviour.home_at_seq0 and node.config.autopilot == 3
