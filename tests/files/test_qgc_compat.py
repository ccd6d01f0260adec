"""Issue 13: .plan files as QGroundControl writes and reads them.

Written files carry every key QGC's loader requires (qgc_loader.py mirrors it); the reader
takes what QGC takes: version-1 fence and rally blocks (skipped, with a note), the legacy
item forms, terrain items whose altitude is null, DO_JUMP targets named by doJumpId.
"""

from __future__ import annotations

import copy
import json
import math
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import pytest
from hypothesis import given, settings

from mavconform.reference_impl.files import SAMPLES_DIR, PlanFileError, load_plan, plan_from_items, save_plan
from mavconform.reference_impl.files.from_vehicle import home_from_messages, settings_from_heartbeat
from mavconform.reference_impl.files.plan import MissionSettings
from mavconform.reference_impl.files.qgc_plan import REQUIRED_KEYS, fallback_home
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem

from . import qgc_loader
from .conftest import qgc_plans

FIXTURES = Path(__file__).parent / "fixtures"


def write_json(path: Path, document) -> Path:
    path.write_text(json.dumps(document, indent=4))
    return path


def fixture(name: str) -> dict:
    return json.loads((FIXTURES / name).read_text())


def error(path: Path) -> str:
    with pytest.raises(PlanFileError) as caught:
        load_plan(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"{path}: "), message
    return message


# --- what is written -------------------------------------------------------------------------

@pytest.mark.parametrize("source", [SAMPLES_DIR / "demo.plan", *sorted(FIXTURES.glob("*.plan"))],
                         ids=lambda p: p.stem)
def test_a_written_plan_has_every_key_qgc_requires(tmp_path: Path, source: Path) -> None:
    save_plan(load_plan(source), tmp_path / "out.plan")
    document = json.loads((tmp_path / "out.plan").read_text())
    assert qgc_loader.problems(document) == []
    for path, keys in REQUIRED_KEYS.items():
        parts = path.removeprefix("$").strip(".").split(".") if path != "$" else []
        objects = [document]
        for part in parts:
            objects = [o[p] for o in objects for p in ([part[:-2]] if part.endswith("[]") else [part])]
            if part.endswith("[]"):
                objects = [x for o in objects for x in o]
        for obj in objects:
            assert set(keys) <= obj.keys(), (path, sorted(set(keys) - obj.keys()))


@settings(max_examples=60, deadline=None)
@given(plan=qgc_plans())
def test_any_written_plan_would_load_in_qgc(tmp_path_factory, plan) -> None:
    path = tmp_path_factory.mktemp("plans") / "any.plan"
    save_plan(plan, path)
    assert qgc_loader.problems(json.loads(path.read_text())) == []


def test_a_plan_without_home_gets_the_one_qgc_would_guess(tmp_path: Path) -> None:
    """QGC's _setPlannedHomePositionFromFirstCoordinate: 30 m north of the first location."""
    mission = [MissionItem(0, 2, Cmd.DO_CHANGE_SPEED, param2=5.0),
               MissionItem(1, 3, Cmd.NAV_WAYPOINT, x=473977419, y=85455938, z=30.0)]
    save_plan(plan_from_items(mission), tmp_path / "p.plan")
    home = json.loads((tmp_path / "p.plan").read_text())["mission"]["plannedHomePosition"]
    assert home[1:] == [8.5455938, 0.0]
    assert math.isclose((home[0] - 47.3977419) * math.pi / 180 * 6371.0072e3, 30.0, abs_tol=0.01)
    assert fallback_home([]) == (0.0, 0.0, 0.0)


def test_vehicle_identity_and_speeds_are_written_and_read_back(tmp_path: Path) -> None:
    plan = replace(load_plan(SAMPLES_DIR / "demo.plan"),
                   settings=MissionSettings(firmware_type=3, vehicle_type=2, cruise_speed=12.5, hover_speed=4))
    save_plan(plan, tmp_path / "p.plan")
    mission = json.loads((tmp_path / "p.plan").read_text())["mission"]
    assert (mission["firmwareType"], mission["vehicleType"]) == (3, 2)
    assert (mission["cruiseSpeed"], mission["hoverSpeed"]) == (12.5, 4)
    assert mission["globalPlanAltitudeMode"] == 0           # Mixed: each item has its own mode
    assert load_plan(tmp_path / "p.plan").settings == plan.settings


def test_items_with_a_location_carry_qgc_altitude_keys(tmp_path: Path) -> None:
    mission = [MissionItem(0, 3, Cmd.NAV_WAYPOINT, x=473977419, y=85455938, z=30.5),
               MissionItem(1, 0, 195, x=473977419, y=85455938, z=510.0),      # DO_SET_ROI_LOCATION
               MissionItem(2, 10, Cmd.NAV_WAYPOINT, x=473977419, y=85455938, z=25.0),
               MissionItem(3, 2, 2000, param2=2.0)]                            # IMAGE_START_CAPTURE
    save_plan(plan_from_items(mission), tmp_path / "p.plan")
    items = json.loads((tmp_path / "p.plan").read_text())["mission"]["items"]
    modes = [(i.get("AltitudeMode"), i.get("Altitude"), i.get("AMSLAltAboveTerrain", "absent")) for i in items]
    assert modes == [(1, 30.5, None), (2, 510, None), (4, 25, None), (None, None, "absent")]


# --- DO_JUMP: targets by doJumpId --------------------------------------------------------------

def test_do_jump_names_its_target_by_doJumpId(tmp_path: Path) -> None:
    plan = load_plan(FIXTURES / "plain.plan")
    jump = plan.mission[3]
    assert (jump.command, jump.param1, jump.param2) == (Cmd.DO_JUMP, 1.0, 1.0)   # doJumpId 2: item 1
    save_plan(plan, tmp_path / "p.plan")
    written = json.loads((tmp_path / "p.plan").read_text())["mission"]["items"][3]
    assert written["params"][0] == 2 and load_plan(tmp_path / "p.plan") == plan


def test_do_jump_ids_need_not_be_positions(tmp_path: Path) -> None:
    """QGC numbers items from 1 and skips numbers for complex items: the id decides."""
    document = fixture("plain.plan")
    for item in document["mission"]["items"]:
        item["doJumpId"] *= 10
    document["mission"]["items"][3]["params"][0] = 20
    assert load_plan(write_json(tmp_path / "p.plan", document)).mission[3].param1 == 1.0


def test_a_do_jump_to_no_item_is_refused_both_ways(tmp_path: Path) -> None:
    document = fixture("plain.plan")
    document["mission"]["items"][3]["params"][0] = 9
    message = error(write_json(tmp_path / "p.plan", document))
    assert "$.mission.items[3].params[0]: DO_JUMP target 9 is no item's doJumpId" in message
    jump = MissionItem(0, 2, Cmd.DO_JUMP, param1=4.0)
    with pytest.raises(PlanFileError, match=r"mission item 0: DO_JUMP target \(param1\) 4 is not an item"):
        save_plan(plan_from_items([jump]), tmp_path / "out.plan")


# --- version-1 geoFence / rallyPoints: skipped, as QGC skips them ----------------------------

def test_version_1_fence_and_rally_are_skipped_with_a_note() -> None:
    plan = load_plan(FIXTURES / "fence_rally_v1.plan")
    assert (plan.fence, plan.rally, len(plan.mission)) == ([], [], 3)
    assert [n.split(": ")[1] for n in plan.notes] == ["$.geoFence", "$.rallyPoints"]
    assert all("QGroundControl skips it" in n and "\n" not in n for n in plan.notes)


def test_a_fence_without_version_is_skipped_too(tmp_path: Path) -> None:
    """GeoFenceController::load ignores a block with no version ("version 1 or prior")."""
    document = fixture("plain.plan")
    del document["geoFence"]["version"]
    plan = load_plan(write_json(tmp_path / "p.plan", document))
    assert plan.fence == [] and len(plan.notes) == 1 and len(plan.rally) == 2


# --- legacy item forms ---------------------------------------------------------------------

def test_legacy_items_read_as_their_modern_form(tmp_path: Path) -> None:
    legacy = load_plan(FIXTURES / "legacy_items.plan")
    document = fixture("legacy_items.plan")
    for item in document["mission"]["items"]:
        params = item.pop("params", None) or [item.pop(f"param{i}") for i in range(1, 5)]
        item["params"] = [*params, *item.pop("coordinate")]
    modern = load_plan(write_json(tmp_path / "modern.plan", document))
    assert legacy.mission == modern.mission
    assert [(i.command, i.param1, i.param4, i.z) for i in legacy.mission] == [
        (22, 0.0, 0.0, 15.0), (16, 3.0, 90.0, 15.0), (16, 0.0, 0.0, 18.0), (20, 0.0, 0.0, 0.0)]
    assert legacy.mission[1].x == 473983000


@pytest.mark.parametrize(("edit", "where", "problem"), [
    (lambda item: item.pop("coordinate"), "$.mission.items[0].coordinate", "missing required key"),
    (lambda item: item.pop("param3"), "$.mission.items[0].params", "missing required key"),
    (lambda item: item.update(param2="x"), "$.mission.items[0].param2", "expected a number"),
    (lambda item: item.update(coordinate=[47.1, 8.2]), "$.mission.items[0].coordinate", "expected [lat, lon, alt]"),
    (lambda item: item.update(coordinate=[47.1, 300, 5]), "$.mission.items[0].coordinate[1]", "does not fit"),
])
def test_legacy_item_problems_name_the_key(tmp_path: Path, edit, where: str, problem: str) -> None:
    document = fixture("legacy_items.plan")
    edit(document["mission"]["items"][0])
    message = error(write_json(tmp_path / "p.plan", document))
    assert f": {where}: " in message and problem in message, message


def test_params_beside_coordinate_must_be_four(tmp_path: Path) -> None:
    document = fixture("legacy_items.plan")
    document["mission"]["items"][2]["params"] = [0, 2, 0, 0, 0, 0, 0]
    assert "$.mission.items[2].params: expected 4 params beside 'coordinate', found 7" in error(
        write_json(tmp_path / "p.plan", document))


# --- terrain items with a null altitude ----------------------------------------------------

def test_null_terrain_altitudes_are_resolved_as_qgc_keeps_them() -> None:
    mission = load_plan(FIXTURES / "terrain_null_altitude.plan").mission
    # CalcAboveTerrain: param7 = AMSLAltAboveTerrain; TerrainFrame: param7 = Altitude
    assert [(i.frame, i.z) for i in mission[1:4]] == [(0, 530.25), (0, 533.5), (10, 35.0)]


def test_a_null_altitude_with_nothing_to_resolve_it_from_is_refused(tmp_path: Path) -> None:
    document = fixture("terrain_null_altitude.plan")
    document["mission"]["items"][2]["AMSLAltAboveTerrain"] = None
    message = error(write_json(tmp_path / "p.plan", document))
    assert "$.mission.items[2].params[6]: the altitude is null and so is AMSLAltAboveTerrain" in message
    document = fixture("terrain_null_altitude.plan")
    document["mission"]["items"][3]["Altitude"] = None
    assert "$.mission.items[3].params[6]: the altitude is null and so is Altitude" in error(
        write_json(tmp_path / "p.plan", document))


@pytest.mark.parametrize(("key", "value", "problem"), [
    ("AltitudeMode", None, "$.mission.items[1].AltitudeMode: expected an integer"),
    ("AltitudeMode", 9, "$.mission.items[1].AltitudeMode: 9 is outside 0..5"),
    ("Altitude", "40", "$.mission.items[1].Altitude: expected a number"),
])
def test_altitude_keys_are_checked(tmp_path: Path, key: str, value, problem: str) -> None:
    document = fixture("terrain_null_altitude.plan")
    document["mission"]["items"][1][key] = value
    assert problem in error(write_json(tmp_path / "p.plan", document))


def test_altitude_keys_come_together(tmp_path: Path) -> None:
    document = fixture("terrain_null_altitude.plan")
    del document["mission"]["items"][1]["AMSLAltAboveTerrain"]
    assert "$.mission.items[1].AMSLAltAboveTerrain: missing required key" in error(
        write_json(tmp_path / "p.plan", document))


def test_a_number_in_params_wins_over_the_altitude_keys(tmp_path: Path) -> None:
    """QGC uploads param7; the keys only say how it was made."""
    document = fixture("terrain_null_altitude.plan")
    document["mission"]["items"][1]["params"][6] = 531
    assert load_plan(write_json(tmp_path / "p.plan", document)).mission[1].z == 531.0


# --- mission settings are checked ----------------------------------------------------------

@pytest.mark.parametrize(("key", "value", "problem"), [
    ("firmwareType", "PX4", "$.mission.firmwareType: expected an integer"),
    ("vehicleType", 300, "$.mission.vehicleType: 300 is outside 0..255"),
    ("cruiseSpeed", -1, "$.mission.cruiseSpeed: a speed must be a finite number >= 0"),
    ("globalPlanAltitudeMode", 7, "$.mission.globalPlanAltitudeMode: 7 is outside 0..5"),
])
def test_mission_settings_are_checked(tmp_path: Path, key: str, value, problem: str) -> None:
    document = copy.deepcopy(fixture("plain.plan"))
    document["mission"][key] = value
    assert problem in error(write_json(tmp_path / "p.plan", document))


# --- what a download knows about the vehicle -----------------------------------------------

def _msg(kind: str, **fields):
    return SimpleNamespace(get_type=lambda: kind, **fields)


def test_home_comes_from_home_position_then_item_0() -> None:
    item0 = _msg("MISSION_ITEM_INT", seq=0, mission_type=0, frame=0, x=473977420, y=85455940, z=488.0)
    fence0 = _msg("MISSION_ITEM_INT", seq=0, mission_type=1, frame=0, x=1, y=1, z=0.0)
    home = _msg("HOME_POSITION", latitude=473000000, longitude=85000000, altitude=500500)
    assert home_from_messages([item0, fence0], home_at_seq0=True) == (47.397742, 8.545594, 488.0)
    assert home_from_messages([item0], home_at_seq0=False) is None          # item 0 is a plan item
    assert home_from_messages([home, item0], home_at_seq0=True) == (47.3, 8.5, 500.5)
    at_null_island = _msg("MISSION_ITEM", seq=0, mission_type=0, frame=0, x=0.0, y=0.0, z=0.0)
    assert home_from_messages([at_null_island], home_at_seq0=True) is None   # QGC ignores it too


def test_settings_come_from_the_heartbeat() -> None:
    assert settings_from_heartbeat(SimpleNamespace(autopilot=12, type=2)) == MissionSettings(12, 2)
    assert settings_from_heartbeat(None) == MissionSettings()
