"""reference_impl.mission.ardupilot_commands against a real ArduCopter SITL survey.

Where MAVCONFORM_AP_SURVEY names the run.json of an `mavconform fidelity --matrix-scope commands`
(or all) run against ArduCopter master 531699d652 SITL, every command-matrix cell (the cells
with a `probe`) must be reproduced exactly: the refusal for refused cells, every field of the
downloaded item for the others (726 of 726 on 2026-11-28). CI has no SITL, so the regression
tests below repeat a handful of those cells as literals.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import pytest

from mavconform.reference_impl.mission.ardupilot_commands import refusal, round_trip
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem

RUN = Path(os.environ.get("MAVCONFORM_AP_SURVEY", "/nonexistent/run.json"))
FIELDS = ("frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z", "autocontinue")
NAN = float("nan")
LAT, LON = 473978654, 85453595  # the survey's probe position


def _num(value: object) -> object:
    return NAN if value == "NaN" else value


def _item(fields: dict, seq: int = 1) -> MissionItem:
    """An item at seq 1: the survey uploads a home placeholder at 0, then the probe."""
    return MissionItem(seq=seq, **{k: _num(fields[k]) for k in FIELDS})


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def _differences(item: MissionItem, expected: dict) -> list[str]:
    got = round_trip(item)
    return [f"{k}: model {getattr(got, k)!r} vs SITL {_num(expected[k])!r}"
            for k in FIELDS if not _same(getattr(got, k), _num(expected[k]))]


def _cells() -> list[dict]:
    if not RUN.exists():
        return []
    cells = json.loads(RUN.read_text())["fidelity"]["cells"]
    return [c for c in cells if "probe" in c]


def _unlike(cell: dict) -> str | None:
    item = _item(cell["sent"][0])
    result = refusal(item)
    name = f"{cell['command']} {cell['probe']}"
    if cell["back"] is None:
        want = cell["class"].split(":", 1)[1]
        return None if result is not None and result.name == want else f"{name}: model {result}, SITL {want}"
    if result is not None:
        return f"{name}: model refuses with {result.name}, SITL stored it"
    return "; ".join(f"{name}: {d}" for d in _differences(item, cell["back"][0])) or None


@pytest.mark.skipif(not RUN.exists(), reason="set MAVCONFORM_AP_SURVEY to an ArduCopter survey's run.json")
def test_every_sitl_cell_is_as_the_model_says() -> None:
    cells = _cells()
    assert len(cells) > 600
    assert [u for u in map(_unlike, cells) if u] == []


def _wp(command: int, frame: int = 6, p: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
        x: int = LAT, y: int = LON, z: float = 25.0) -> MissionItem:
    return MissionItem(seq=1, frame=frame, command=command, param1=p[0], param2=p[1],
                       param3=p[2], param4=p[3], x=x, y=y, z=z)


def _do(command: int, p: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
        x: int = 0, y: int = 0, z: float = 0.0) -> MissionItem:
    return _wp(command, frame=2, p=p, x=x, y=y, z=z)


def _back(item: MissionItem) -> tuple:
    b = round_trip(item)
    return (b.frame, b.param1, b.param2, b.param3, b.param4, b.x, b.y, b.z, b.autocontinue)


def test_do_set_servo_negative_channel_and_pwm_wrap() -> None:
    # 183 p1:below / p2:below: uint8 channel, uint16 pwm; frame 2 comes back as 0
    assert _back(_do(183, (-1.0, 0.0, 0.0, 0.0))) == (0, 255.0, 0.0, 0.0, 0.0, 0, 0, 0.0, 1)
    assert _back(_do(183, (0.0, -1.0, 0.0, 0.0))) == (0, 0.0, 65535.0, 0.0, 0.0, 0, 0, 0.0, 1)
    assert _back(_do(183, (0.0, 0.0, 1.0, 1.0), x=1, y=1, z=1.0))[1:] == (0.0,) * 4 + (0, 0, 0.0, 1)


def test_nav_loiter_turns_packing() -> None:
    # 18 p1:below: MIN(255, -1.0) -> uint16 65535, whose high byte also becomes the radius
    assert _back(_wp(18, p=(-1.0, 0.0, 0.0, 0.0)))[:5] == (3, 255.0, 0.0, 255.0, 0.0)
    # 18 p3:value: radius > 255 stored /10 in 8 bits; p4:value: xtrack flag
    assert _back(_wp(18, p=(0.0, 0.0, 1234.5677490234375, 0.0)))[3] == 1230.0
    assert _back(_wp(18, p=(0.0, 0.0, 0.0, 1234.5677490234375)))[4] == 1.0
    assert _back(_wp(18, p=(12.375, 0.0, -12.375, 0.0)))[1:4] == (12.0, 0.0, -12.0)
    assert refusal(_wp(18, p=(0.0, 0.0, 0.0, NAN))) is MissionResult.INVALID_PARAM4


def test_do_change_speed_and_condition_yaw() -> None:
    assert _back(_do(178, (0.0, -2.0, -2.0, 0.0))) == (0, 0.0, -2.0, -2.0, 0.0, 0, 0, 0.0, 1)
    assert _back(_do(178, (0.0, 0.0, 0.0, 1.0), x=1)) == (0, 0.0, 0.0, 0.0, 0.0, 0, 0, 0.0, 1)
    # 115 p4: uint8 relative_angle (1234 -> 210, -12 -> 244)
    assert _back(_do(115, (0.0, 0.0, -1.0, 1234.5677490234375)))[3:5] == (-1.0, 210.0)
    assert _back(_do(115, (0.0, 0.0, -1.0, -12.375)))[4] == 244.0


def test_location_items_frames_and_altitude() -> None:
    # frame 6 -> 3, altitude kept in cm (12.375 m -> 1237 cm -> 12.37f)
    assert _back(_wp(16, z=12.375)) == (3, 0.0, 0.0, 0.0, 0.0, LAT, LON, 12.369999885559082, 1)
    # 30 in frame 2 (MISSION) is stored absolute and comes back in frame 0
    assert _back(_do(30, z=1234.5677490234375))[0::7] == (0, 1234.5599365234375)
    assert round_trip(_do(20)).frame == 0
    # 21 NAV_LAND: uint16 p1, param4 is the yaw direction flag (+1 unless negative)
    assert _back(_wp(21, p=(-12.375, 0.0, 0.0, NAN)))[1:5] == (65524.0, 0.0, 0.0, 1.0)
    # 94 NAV_PAYLOAD_PLACE: max descent in uint16 cm
    assert _back(_wp(94, p=(-1.0, 0.0, 0.0, 0.0)))[1] == 654.3599853515625


def test_refusals() -> None:
    assert refusal(_do(177)) is MissionResult.ERROR           # DO_JUMP to 0
    assert refusal(_do(177, (1.0, 0.0, 0.0, 0.0))) is None    # DO_JUMP to itself
    assert refusal(_do(177, (2.0, 0.0, 0.0, 0.0))) is MissionResult.ERROR
    assert refusal(_do(177, (2.0, 0.0, 0.0, 0.0)), mission_count=3) is None
    assert refusal(_do(176)) is MissionResult.UNSUPPORTED     # DO_SET_MODE
    assert refusal(_wp(23)) is MissionResult.UNSUPPORTED      # NAV_LAND_LOCAL
    assert refusal(_wp(16, p=(-1.0, 0.0, 0.0, 0.0))) is MissionResult.INVALID_PARAM1
    assert refusal(_wp(16, p=(0.0, 0.0, 0.0, NAN))) is None
    assert refusal(_wp(179, p=(0.0, 0.0, 0.0, NAN))) is MissionResult.INVALID_PARAM4
    assert refusal(_wp(16, frame=1)) is MissionResult.UNSUPPORTED_FRAME
