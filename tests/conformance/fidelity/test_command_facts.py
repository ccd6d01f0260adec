"""command_facts.py is tools/command_facts.py's output from upstream common.xml, unchanged (run
where ../shared/mavlink-upstream exists), and PX4's mission_item_s round trip (P28) gives what
PX4 v1.16 SIH gave back."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

from mavconform.reference_impl.mission.items import MissionItem, MissionType, to_float32
from mavconform.reference_impl.mission.px4_storage import px4_mission_item, yaw_round_trip

ROOT = Path(__file__).resolve().parents[3]
UPSTREAM = ROOT.parent / "shared" / "mavlink-upstream" / "common.xml"


@pytest.mark.skipif(not UPSTREAM.is_file(), reason="upstream common.xml is not beside the project")
def test_the_committed_facts_are_upstreams() -> None:
    spec = importlib.util.spec_from_file_location("command_facts_tool", ROOT / "tools" / "command_facts.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    assert tool.OUT.read_text(encoding="utf-8") == tool.render(UPSTREAM)


def _item(frame: int, command: int, p: tuple = (0.0, 0.0, 0.0, 0.0), x: int = 473978654, y: int = 85453595) -> MissionItem:
    return MissionItem(0, frame, command, *p, x, y, 25.0, 0, 1)


def test_px4s_record_gives_back_what_the_sitl_did() -> None:
    """Values seen on PX4 v1.16.0 SIH (mavconform fidelity --matrix-scope commands, 2026-11-28)."""
    assert yaw_round_trip(to_float32(1234.5678)) == 154.56771850585938 and yaw_round_trip(-12.375) == 347.625
    wp = px4_mission_item(_item(6, 16, (12.375, 2.0, 1234.5, -12.375)))
    assert (wp.param1, wp.param2, wp.param3, wp.param4) == (12.375, 2.0, 0.0, 347.625)
    loiter = px4_mission_item(_item(6, 19, (3.0, -12.375, 50.0, float("nan"))))
    assert (loiter.param1, loiter.param2, loiter.param3, loiter.param4) == (3.0, 0.0, 50.0, 0.0)
    assert px4_mission_item(_item(6, 80)).command == 201 and px4_mission_item(_item(2, 80)).command == 201
    jump = px4_mission_item(_item(2, 177, (7.5, -1.0, 0.0, 0.0), 0, 0))
    assert (jump.param1, jump.param2) == (7.0, 65535.0)
    actuator = px4_mission_item(_item(2, 187, (0.5, 0.0, 0.0, 0.0), 2**31 - 1, 12345))
    assert (actuator.x, actuator.y, actuator.param1) == (-2**31, 12345, 0.5)
    fence = MissionItem(0, 3, 5000, 1.0, 2.0, 3.0, 4.0, 1, 2, 20.0, 0, 1, MissionType.FENCE)
    assert px4_mission_item(fence) == fence
