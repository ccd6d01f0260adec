"""QGroundControl .plan JSON: round trips, the sample, fence grouping and JSON-path errors."""

from __future__ import annotations

import copy
import json
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable

import pytest
from hypothesis import given, settings

from mavconform.reference_impl.files import SAMPLES_DIR, Plan, PlanFileError, load_plan, plan_from_items, save_plan
from mavconform.reference_impl.files.qgc_plan import fallback_home
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from .conftest import qgc_plans

PROPERTY = settings(max_examples=100, deadline=None)  # file I/O: no per-example deadline


def simple_item(command: int = 16, frame: int = 3, params: list | None = None) -> dict:
    return {"autoContinue": True, "command": command, "doJumpId": 1, "frame": frame,
            "params": params if params is not None else [0, 0, 0, None, 47.3977419, 8.5455938, 30],
            "type": "SimpleItem"}


def valid_document() -> dict[str, Any]:
    return {
        "fileType": "Plan", "groundStation": "QGroundControl", "version": 1,
        "mission": {"cruiseSpeed": 15, "firmwareType": 12, "hoverSpeed": 5, "vehicleType": 2, "version": 2,
                    "plannedHomePosition": [47.3977419, 8.5455938, 488.1], "items": [simple_item()]},
        "geoFence": {"version": 2, "breachReturn": [47.3975, 8.546, 40],
                     "polygons": [{"version": 1, "inclusion": True,
                                   "polygon": [[47.4, 8.543], [47.4002, 8.547], [47.3962, 8.5496]]}],
                     "circles": [{"version": 1, "inclusion": False,
                                  "circle": {"center": [47.3966, 8.5484], "radius": 25}}]},
        "rallyPoints": {"version": 2, "points": [[47.3995, 8.544, 30]]},
    }


def write_json(path: Path, document: Any) -> Path:
    path.write_text(json.dumps(document, indent=4))
    return path


def one_line_error(action: Callable[[], object], path: Path) -> str:
    with pytest.raises(PlanFileError) as caught:
        action()
    message = str(caught.value)
    assert "\n" not in message and message.startswith(str(path)), message
    return message


@PROPERTY
@given(plan=qgc_plans())
def test_round_trip_is_exact(scratch_dir: Path, plan: Plan) -> None:
    """Exact, but for a plan without home: the file gets the home QGC would make up."""
    path = scratch_dir / "round_trip.plan"
    save_plan(plan, path)
    assert load_plan(path) == replace(plan, home=plan.home or fallback_home(plan.mission))


def test_sample_loads_and_round_trips(tmp_path: Path) -> None:
    plan = load_plan(SAMPLES_DIR / "demo.plan")
    assert [item.command for item in plan.mission] == [22, 16, 16, 16, 16, 16, 16, 19, 20]
    assert plan.home == (47.3977419, 8.5455938, 488.1)
    assert [item.command for item in plan.fence] == [5001] * 6 + [5004, 5000]
    assert {item.param1 for item in plan.fence[:6]} == {6.0} and plan.fence[6].param1 == 25.0
    assert plan.fence[7].z == 40.0 and plan.fence[7].frame == 3
    assert [(item.command, item.frame) for item in plan.rally] == [(5100, 3)] * 3
    assert [item.seq for item in plan.fence] == list(range(8))
    assert all(item.mission_type is MissionType.FENCE for item in plan.fence)
    assert plan.mission[1].param4 != plan.mission[1].param4  # null yaw is NaN
    save_plan(plan, tmp_path / "copy.plan")
    assert load_plan(tmp_path / "copy.plan") == plan


def test_written_file_has_qgc_layout(tmp_path: Path) -> None:
    save_plan(load_plan(SAMPLES_DIR / "demo.plan"), tmp_path / "out.plan")
    document = json.loads((tmp_path / "out.plan").read_text())
    assert (document["fileType"], document["version"]) == ("Plan", 1)
    assert document["mission"]["plannedHomePosition"] == [47.3977419, 8.5455938, 488.1]
    first = document["mission"]["items"][0]
    assert first == {"autoContinue": True, "command": 22, "doJumpId": 1, "frame": 3,
                     "params": [0, 0, 0, None, 47.3977419, 8.5455938, 30], "type": "SimpleItem",
                     "AltitudeMode": 1, "Altitude": 30, "AMSLAltAboveTerrain": None}
    fence = document["geoFence"]
    assert fence["breachReturn"] == [47.3975, 8.546, 40]
    assert fence["circles"] == [{"circle": {"center": [47.3966, 8.5484], "radius": 25},
                                 "inclusion": False, "version": 1}]
    assert len(fence["polygons"][0]["polygon"]) == 6 and fence["polygons"][0]["inclusion"] is True
    assert document["rallyPoints"]["points"][0] == [47.3995, 8.544, 30]


def test_wpl_sample_converts_to_plan_keeping_items(tmp_path: Path) -> None:
    """.plan has no `current` flag: everything else carries over."""
    mission = load_plan(SAMPLES_DIR / "demo.waypoints").mission
    save_plan(plan_from_items(mission), tmp_path / "converted.plan")
    converted = load_plan(tmp_path / "converted.plan").mission
    assert converted == [replace(item, current=0) for item in mission]


def test_degE7_is_exact(tmp_path: Path) -> None:
    item = load_plan(write_json(tmp_path / "p.plan", valid_document())).mission[0]
    assert (item.x, item.y) == (473977419, 85455938)


def test_fence_in_any_groupable_order_is_written_in_qgc_order(tmp_path: Path) -> None:
    """The return point may come first (as some vehicles store it); reading gives QGC's order."""
    canonical = load_plan(write_json(tmp_path / "p.plan", valid_document()))
    reordered = canonical.with_items(MissionType.FENCE, [canonical.fence[-1], *canonical.fence[:-1]])
    save_plan(reordered, tmp_path / "out.plan")
    assert load_plan(tmp_path / "out.plan").fence == canonical.fence


def test_plan_helpers() -> None:
    item = MissionItem(seq=7, frame=3, command=Cmd.NAV_RALLY_POINT)
    plan = plan_from_items(rally=[item, item])
    assert [(i.seq, i.mission_type) for i in plan.items(MissionType.RALLY)] == [(0, MissionType.RALLY), (1, MissionType.RALLY)]
    moved = plan.with_items(MissionType.FENCE, plan.rally)
    assert moved.rally == plan.rally and [i.mission_type for i in moved.fence] == [MissionType.FENCE] * 2
    with pytest.raises(ValueError):
        plan.items(MissionType.ALL)


# --- load errors -------------------------------------------------------------------------

def _set(path: list, value: Any) -> Callable[[dict], None]:
    def edit(document: dict) -> None:
        target = document
        for key in path[:-1]:
            target = target[key]
        if value is _DELETE:
            del target[path[-1]]
        else:
            target[path[-1]] = value
    return edit


_DELETE = object()
_ITEM = ["mission", "items", 0]


@pytest.mark.parametrize(("edit", "where", "problem"), [
    (_set(["mission", "items"], _DELETE), "$.mission.items", "missing required key"),
    (_set(["mission"], _DELETE), "$.mission", "missing required key"),
    (_set(["fileType"], "Mission"), "$.fileType", "expected 'Plan'"),
    (_set(["version"], 2), "$.version", "unsupported version 2 (expected 1)"),
    (_set(["geoFence", "version"], 3), "$.geoFence.version", "unsupported version 3 (expected 2)"),
    (_set(["rallyPoints", "version"], _DELETE), "$.rallyPoints.version", "missing required key"),
    (_set([*_ITEM, "command"], "16"), "$.mission.items[0].command", "expected an integer, found a string"),
    (_set([*_ITEM, "command"], 70000), "$.mission.items[0].command", "70000 is outside 0..65535"),
    (_set([*_ITEM, "frame"], 3.5), "$.mission.items[0].frame", "expected an integer, found the number 3.5"),
    (_set([*_ITEM, "autoContinue"], 1), "$.mission.items[0].autoContinue", "expected a bool"),
    (_set([*_ITEM, "params"], [0] * 6), "$.mission.items[0].params", "expected 7 params, found 6"),
    (_set([*_ITEM, "params"], {"a": 1}), "$.mission.items[0].params", "expected an array, found an object"),
    (_set([*_ITEM, "params", 2], "x"), "$.mission.items[0].params[2]", "expected a number"),
    (_set([*_ITEM, "params", 4], None), "$.mission.items[0].params[4]", "does not fit"),
    (_set([*_ITEM, "params", 5], 215), "$.mission.items[0].params[5]", "int32 y in frame 3"),
    (_set([*_ITEM, "type"], "Fancy"), "$.mission.items[0].type", "unknown item type 'Fancy'"),
    (_set(["mission", "plannedHomePosition"], [47, 8]), "$.mission.plannedHomePosition", "expected [lat, lon, alt]"),
    (_set(["mission", "plannedHomePosition", 0], -90.5), "$.mission.plannedHomePosition[0]", "latitude -90.5 is outside [-90, 90]"),
    (_set(["rallyPoints", "points", 0, 0], 91), "$.rallyPoints.points[0][0]", "latitude 91 is outside"),
    (_set(["geoFence", "polygons", 0, "polygon", 1, 1], 180.5), "$.geoFence.polygons[0].polygon[1][1]", "longitude 180.5 is outside [-180, 180]"),
    (_set(["geoFence", "polygons", 0, "polygon"], [[47, 8], [47.1, 8]]), "$.geoFence.polygons[0].polygon", "at least 3 vertices, found 2"),
    (_set(["geoFence", "polygons", 0, "inclusion"], _DELETE), "$.geoFence.polygons[0].inclusion", "missing required key"),
    (_set(["geoFence", "circles", 0, "circle", "radius"], 0), "$.geoFence.circles[0].circle.radius", "positive finite"),
    (_set(["geoFence", "circles", 0, "circle", "radius"], -5), "$.geoFence.circles[0].circle.radius", "positive finite"),
    (_set(["geoFence", "breachReturn"], [47.3, 8.5]), "$.geoFence.breachReturn", "expected [lat, lon, alt]"),
    (_set(["rallyPoints", "points"], None), "$.rallyPoints.points", "expected an array, found null"),
])
def test_each_problem_names_file_and_json_path(tmp_path: Path, edit, where: str, problem: str) -> None:
    document = copy.deepcopy(valid_document())
    edit(document)
    path = write_json(tmp_path / "bad.plan", document)
    message = one_line_error(lambda: load_plan(path), path)
    assert message.startswith(f"{path}: {where}: ") and problem in message, message


def test_numbers_json_cannot_hold_as_int32_are_path_errors(tmp_path: Path) -> None:
    path = tmp_path / "huge.plan"
    path.write_text(json.dumps(valid_document()).replace('"command": 16', '"command": 1e400'))
    assert f"{path}: $.mission.items[0].command: " in one_line_error(lambda: load_plan(path), path)
    path.write_text(json.dumps(valid_document()).replace("47.3977419, 8.5455938, 30", "1e999999999, 8, 30"))
    assert f"{path}: $.mission.items[0].params[4]: " in one_line_error(lambda: load_plan(path), path)


def test_complex_item_is_refused_by_path(tmp_path: Path) -> None:
    document = valid_document()
    document["mission"]["items"].append({"type": "ComplexItem", "complexItemType": "survey", "version": 5})
    path = write_json(tmp_path / "demo.plan", document)
    assert one_line_error(lambda: load_plan(path), path) == (
        f"{path}: $.mission.items[1]: ComplexItem (survey) is not supported; "
        "convert it to simple items in QGroundControl first")


def test_optional_sections_may_be_absent(tmp_path: Path) -> None:
    document = valid_document()
    del document["geoFence"], document["rallyPoints"], document["mission"]["plannedHomePosition"]
    plan = load_plan(write_json(tmp_path / "p.plan", document))
    assert (plan.fence, plan.rally, plan.home) == ([], [], None) and len(plan.mission) == 1


def test_invalid_json_gives_line_and_column(tmp_path: Path) -> None:
    path = tmp_path / "broken.plan"
    path.write_text('{\n  "fileType": "Plan",\n  "version": ,\n}\n')
    message = one_line_error(lambda: load_plan(path), path)
    assert message.startswith(f"{path}: line 3 column 14: invalid JSON: "), message


def test_unreadable_files(tmp_path: Path) -> None:
    missing = tmp_path / "absent.plan"
    assert f"{missing}: cannot read: " in one_line_error(lambda: load_plan(missing), missing)
    assert "cannot read" in one_line_error(lambda: load_plan(tmp_path), tmp_path)  # a directory
    binary = tmp_path / "binary.plan"
    binary.write_bytes(b"\xff\xfe\x00garbage")
    assert "not UTF-8" in one_line_error(lambda: load_plan(binary), binary)


# --- save errors -------------------------------------------------------------------------

def vertex(count: float, command: int = Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION, frame: int = 0) -> MissionItem:
    return MissionItem(seq=0, frame=frame, command=command, param1=count, x=473977419, y=85455938)


@pytest.mark.parametrize(("fence", "rally", "problem"), [
    ([vertex(4)] * 3, [], "fence item 0: polygon declares 4 vertices but only 3 follow"),
    ([vertex(3)] * 2 + [vertex(3, Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION)], [], "fence item 0: polygon declares 3"),
    ([vertex(3), vertex(4), vertex(3)], [], "fence item 1: vertex count (param1) 4 differs from 3"),
    ([vertex(2)] * 2, [], "fence item 0: polygon vertex count (param1) 2 is not a whole number >= 3"),
    ([vertex(float("nan"))], [], "is not a whole number >= 3"),
    ([vertex(3.5)] * 3, [], "is not a whole number >= 3"),
    ([vertex(3, Cmd.NAV_WAYPOINT)], [], "fence item 0: command 16 is not a fence command"),
    ([vertex(0, Cmd.NAV_FENCE_RETURN_POINT)] * 2, [], "fence item 1: a second return point"),
    ([vertex(0, Cmd.NAV_FENCE_CIRCLE_INCLUSION)], [], "fence item 0: circle radius (param1) 0 is not a positive"),
    ([vertex(3, frame=1)] * 3, [], "fence item 0: frame 1 is not a global frame"),
    ([], [vertex(0, Cmd.NAV_WAYPOINT)], "rally item 0: command 16 is not MAV_CMD_NAV_RALLY_POINT"),
])
def test_unwritable_fence_and_rally_are_refused(tmp_path: Path, fence, rally, problem: str) -> None:
    path = tmp_path / "out.plan"
    message = one_line_error(lambda: save_plan(plan_from_items(fence=fence, rally=rally), path), path)
    assert problem in message, message
    assert not path.exists()


def test_unwritable_mission_and_home_are_refused(tmp_path: Path) -> None:
    path = tmp_path / "out.plan"
    infinite = plan_from_items([MissionItem(seq=0, frame=3, command=16, param2=float("inf"))])
    assert "mission item 0: inf cannot be written: JSON has no infinity" in one_line_error(
        lambda: save_plan(infinite, path), path)
    bad_home = plan_from_items(home=(95.0, 8.0, 0.0))
    assert "home: latitude 95.0 is outside [-90, 90]" in one_line_error(lambda: save_plan(bad_home, path), path)


def test_a_plan_longer_than_mission_count_can_say_is_refused_up_front(tmp_path):
    """Issue 12: a .plan of 70,000 items ended in a struct.error traceback at upload."""
    import json

    from mavconform.reference_impl.files import PlanFileError, load_plan
    item = {"type": "SimpleItem", "autoContinue": True, "command": 16, "frame": 3,
            "params": [0, 0, 0, None, 47.0, 8.0, 50]}
    doc = {"fileType": "Plan", "version": 1, "groundStation": "QGroundControl",
           "mission": {"version": 2, "items": [dict(item, doJumpId=i + 1) for i in range(70_000)],
                       "plannedHomePosition": [47.0, 8.0, 0]},
           "geoFence": {"version": 2, "polygons": [], "circles": []},
           "rallyPoints": {"version": 2, "points": []}}
    path = tmp_path / "big.plan"
    path.write_text(json.dumps(doc))
    with pytest.raises(PlanFileError, match=r"big.plan: the mission plan has 70000 items; .* at most 65535"):
        load_plan(path)
