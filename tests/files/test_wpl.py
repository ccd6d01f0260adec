"""QGC WPL 110 text: round trips, the sample, degE7 precision and one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.files import SAMPLES_DIR, PlanFileError, load_plan, plan_from_items, save_plan
from mavconform.reference_impl.files.wpl import HEADER
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from .conftest import int32s, wpl_plans

ROW = "0\t1\t3\t16\t0\t0\t0\t0\t47.3977419\t8.5455938\t30\t1"
PROPERTY = settings(max_examples=100, deadline=None)  # file I/O: no per-example deadline


def write(path: Path, *lines: str) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


def load_error(path: Path) -> str:
    with pytest.raises(PlanFileError) as caught:
        load_plan(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(str(path))
    return message


@PROPERTY
@given(plan=wpl_plans(), suffix=st.sampled_from([".waypoints", ".txt", ".mission"]))
def test_round_trip_is_exact(scratch_dir: Path, plan, suffix: str) -> None:
    path = scratch_dir / f"round_trip{suffix}"
    save_plan(plan, path)
    assert load_plan(path) == plan


def test_sample_loads_and_round_trips(tmp_path: Path) -> None:
    plan = load_plan(SAMPLES_DIR / "demo.waypoints")
    commands = [item.command for item in plan.mission]
    assert commands == [22, 16, 16, 16, 16, 16, 16, 178, 19, 20]
    assert [item.seq for item in plan.mission] == list(range(10))
    assert plan.mission[0].current == 1 and plan.mission[0].x == 473977419
    assert all(item.mission_type is MissionType.MISSION for item in plan.mission)
    assert not plan.fence and not plan.rally and plan.home is None
    save_plan(plan, tmp_path / "copy.waypoints")
    assert load_plan(tmp_path / "copy.waypoints") == plan


def test_row_zero_is_an_item_not_home(tmp_path: Path) -> None:
    plan = load_plan(write(tmp_path / "m.txt", HEADER, ROW))
    assert plan.home is None and len(plan.mission) == 1 and plan.mission[0].command == 16


# --- precision ---------------------------------------------------------------------------

def test_seven_decimals_are_exact_both_ways(tmp_path: Path) -> None:
    plan = load_plan(write(tmp_path / "m.waypoints", HEADER, ROW))
    assert (plan.mission[0].x, plan.mission[0].y) == (473977419, 85455938)
    save_plan(plan, tmp_path / "out.waypoints")
    assert "\t47.3977419\t8.5455938\t" in (tmp_path / "out.waypoints").read_text()


@pytest.mark.parametrize(("text", "expected"), [
    ("47.39774186", 473977419), ("47.39774185", 473977418),  # beyond degE7: half-even, exactly
    ("-0.0000001", -1), ("1e-7", 1), ("-180", -1_800_000_000),
])
def test_extra_digits_round_like_degE7(tmp_path: Path, text: str, expected: int) -> None:
    row = f"0\t0\t0\t16\t0\t0\t0\t0\t{text}\t0\t0\t1"
    assert load_plan(write(tmp_path / "m.waypoints", HEADER, row)).mission[0].x == expected


@PROPERTY
@given(frame=st.sampled_from([0, 1, 2]), x=int32s, y=int32s)
def test_every_int32_xy_survives_text(scratch_dir: Path, frame: int, x: int, y: int) -> None:
    plan = plan_from_items([MissionItem(seq=0, frame=frame, command=16, x=x, y=y)])
    save_plan(plan, scratch_dir / "xy.waypoints")
    item = load_plan(scratch_dir / "xy.waypoints").mission[0]
    assert (item.x, item.y) == (x, y)


def test_params_are_written_with_the_fewest_float32_digits(tmp_path: Path) -> None:
    item = MissionItem(seq=0, frame=2, command=178, param1=0.10000000149011612, param2=float("nan"))
    save_plan(plan_from_items([item]), tmp_path / "p.waypoints")
    assert "\t0.1\tnan\t" in (tmp_path / "p.waypoints").read_text()
    assert load_plan(tmp_path / "p.waypoints").mission[0] == item


# --- errors ------------------------------------------------------------------------------

def row_with(**columns: str) -> str:
    names = ("INDEX", "CURRENT", "FRAME", "COMMAND", "P1", "P2", "P3", "P4", "X", "Y", "Z", "AUTOCONTINUE")
    values = dict(zip(names, ROW.split("\t")))
    values.update(columns)
    return "\t".join(values[name] for name in names)


@pytest.mark.parametrize(("lines", "line", "problem"), [
    (["QGC WPL 120", ROW], 1, "expected the header 'QGC WPL 110'"),
    ([HEADER, "0\t1\t3\t16\t0\t0\t0\t0\t47.3\t8.5\t30"], 2, "expected 12 columns"),
    ([HEADER, ROW + "\t0"], 2, "found 13"),
    ([HEADER, ROW, row_with(INDEX="1", P1="abc")], 3, "PARAM1 'abc' is not a number"),
    ([HEADER, ROW, row_with(INDEX="1", X="47,39")], 3, "X '47,39' is not a number"),
    ([HEADER, ROW, row_with(INDEX="2")], 3, "INDEX 2 out of order"),
    ([HEADER, row_with(INDEX="1")], 2, "expected 0"),
    ([HEADER, ROW, "", row_with(INDEX="0")], 4, "INDEX 0 out of order"),  # blank lines still count
    ([HEADER, row_with(CURRENT="2")], 2, "CURRENT 2 is outside 0..1"),
    ([HEADER, row_with(AUTOCONTINUE="true")], 2, "AUTOCONTINUE 'true' is not an integer"),
    ([HEADER, row_with(FRAME="3.0")], 2, "FRAME '3.0' is not an integer"),
    ([HEADER, row_with(FRAME="256")], 2, "FRAME 256 is outside 0..255"),
    ([HEADER, row_with(COMMAND="65536")], 2, "COMMAND 65536 is outside 0..65535"),
    ([HEADER, row_with(COMMAND="-1")], 2, "COMMAND -1 is outside"),
    ([HEADER, row_with(X="nan")], 2, "X 'nan' does not fit"),
    ([HEADER, row_with(X="1e999999999")], 2, "X '1e999999999' does not fit"),
    ([HEADER, row_with(P2="sNaN")], 2, "PARAM2 'sNaN' is not a number"),
    ([HEADER, row_with(COMMAND="9" * 5000)], 2, "is outside 0..65535"),
    ([HEADER, row_with(Y="215")], 2, "Y '215' does not fit MISSION_ITEM_INT's int32 in frame 3"),
])
def test_each_problem_names_file_and_line(tmp_path: Path, lines: list[str], line: int, problem: str) -> None:
    path = write(tmp_path / "bad.waypoints", *lines)
    message = load_error(path)
    assert message.startswith(f"{path}:{line}: ") and problem in message, message


def test_errors_are_usage_errors(tmp_path: Path) -> None:
    with pytest.raises(UsageError):
        load_plan(write(tmp_path / "bad.txt", HEADER, "garbage"))


def test_file_that_is_neither_format(tmp_path: Path) -> None:
    path = write(tmp_path / "notes.txt", "hello")
    assert load_error(path) == f"{path}:1: not a mission file: expected a .plan file or the header 'QGC WPL 110', found 'hello'"
    assert ":1: not a mission file" in load_error(write(tmp_path / "empty.waypoints", ""))


def test_missing_file(tmp_path: Path) -> None:
    assert f"{tmp_path / 'absent.waypoints'}: cannot read: " in load_error(tmp_path / "absent.waypoints")


def save_error(plan, path: Path) -> str:
    with pytest.raises(PlanFileError) as caught:
        save_plan(plan, path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(str(path))
    return message


def test_saving_fence_or_rally_as_wpl_is_refused(tmp_path: Path) -> None:
    plan = load_plan(SAMPLES_DIR / "demo.plan")
    message = save_error(plan, tmp_path / "out.waypoints")
    assert "holds only the mission" in message and "8 fence and 3 rally items" in message
    assert not (tmp_path / "out.waypoints").exists()
    save_plan(plan_from_items(plan.mission, home=plan.home), tmp_path / "mission_only.waypoints")


def test_unwritable_values_are_refused(tmp_path: Path) -> None:
    plan = plan_from_items([MissionItem(seq=0, frame=3, command=16, current=2)])
    assert "mission item 0: current 2 is outside 0..1" in save_error(plan, tmp_path / "out.waypoints")
    assert "unknown mission file type '.json'" in save_error(plan_from_items(), tmp_path / "out.json")
