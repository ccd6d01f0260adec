"""The MAV_CMD facts the vehicle's accepted commands come from (issue 13): generated from
the upstream common.xml, committed, and checked against the XML where ../shared exists."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.reference_impl.mission import commands_regenerate
from mavconform.reference_impl.mission.commands import (
    COMMANDS, DESTINATION_COMMANDS, LOCATION_COMMANDS, PLAN_COMMANDS, by_name, name_of,
)
from mavconform.reference_impl.mission.constants import (
    FENCE_COMMANDS, MISSION_COMMANDS, POSITIONAL_COMMANDS, RALLY_COMMANDS, Cmd,
)


def test_the_committed_facts_match_the_upstream_xml() -> None:
    if not commands_regenerate.DEFAULT_XML.is_file():
        pytest.skip(f"upstream MAVLink XML not found at {commands_regenerate.DEFAULT_XML}")
    assert commands_regenerate.check() == "identical", (
        "commands_data.py is stale: python -m mavconform.reference_impl.mission.commands_regenerate")
    assert commands_regenerate.main(["--check"]) == 0


def test_check_mode_reports_a_stale_module(tmp_path: Path, monkeypatch, capsys) -> None:
    xml = tmp_path / "common.xml"
    xml.write_text('<mavlink><enums><enum name="MAV_CMD">'
                   '<entry value="16" name="MAV_CMD_NAV_WAYPOINT" hasLocation="true" isDestination="true">'
                   '<param index="1" label="Hold"/></entry></enum></enums></mavlink>')
    assert commands_regenerate.main(["--check", "--xml", str(xml)]) == 1
    assert "out of date" in capsys.readouterr().err
    out = tmp_path / "commands_data.py"
    monkeypatch.setattr(commands_regenerate, "PY_PATH", out)
    assert commands_regenerate.main(["--xml", str(xml)]) == 0
    assert "(16, 'NAV_WAYPOINT', True, True, False, '', ((1, 'Hold', False),))," in out.read_text()
    assert commands_regenerate.main(["--check", "--xml", str(xml)]) == 0
    assert commands_regenerate.main(["--xml", str(tmp_path / "absent.xml")]) == 2


def test_every_cmd_the_engines_name_is_an_upstream_command_of_that_name() -> None:
    for member in Cmd:
        if member is not Cmd.REQUEST_OPERATOR_CONTROL:       # development.xml, not common.xml
            assert COMMANDS[member].name == member.name, member
    assert Cmd.REQUEST_OPERATOR_CONTROL not in COMMANDS


def test_the_sets_are_facts_of_the_xml() -> None:
    assert MISSION_COMMANDS == PLAN_COMMANDS and POSITIONAL_COMMANDS == DESTINATION_COMMANDS
    assert FENCE_COMMANDS.isdisjoint(MISSION_COMMANDS) and RALLY_COMMANDS.isdisjoint(MISSION_COMMANDS)
    old_hand_list = {16, 17, 18, 19, 20, 21, 22, 31, 93, 112, 114, 115, 176, 177, 178, 179, 183, 189}
    assert old_hand_list <= MISSION_COMMANDS
    assert {195, 206, 1000, 2000} <= MISSION_COMMANDS                    # the QGC commands
    assert {95, 159, 240} & MISSION_COMMANDS == set()                    # *_LAST range markers
    assert 180 not in MISSION_COMMANDS                                   # deprecated DO_SET_PARAMETER
    assert 195 in LOCATION_COMMANDS and 195 not in POSITIONAL_COMMANDS  # an ROI is looked at, not flown to
    assert {16, 17, 18, 19, 21, 22, 31} <= POSITIONAL_COMMANDS
    assert by_name("image_start_capture").label(2) == "Interval" and by_name("MAV_CMD_DO_JUMP").mission_only
    assert by_name("NO_SUCH") is None
    assert (name_of(195), name_of(31999)) == ("MAV_CMD_DO_SET_ROI_LOCATION", "command 31999")
