"""Scenario files: the shipped delivery flights, every mistake as one line, the echo, .plan and YAML."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path
from typing import Any, Callable

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.files import plan_from_items, save_plan
from mavconform.reference_impl.handover.emergency import RefugeKind, choose_refuge, usable_range_m
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.regions import Circle, Polygon, RegionMethod
from mavconform.reference_impl.handover.scenario import (
    FORMAT, SCENARIOS_DIR, LinkFaults, ScenarioError, load_scenario, scenario_from_dict, scenario_to_dict,
)
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem
from mavconform.reference_impl.net.faults import DropMessage
from mavconform.reference_impl.wire.signing import secret_from_passphrase

SHIPPED = ("delivery_flight.json", "delivery_flight_circles.json", "delivery_flight_waypoints.json")
POLYGON_FILE = "delivery_flight.json"


def shipped(name: str = POLYGON_FILE) -> dict[str, Any]:
    return json.loads((SCENARIOS_DIR / name).read_text(encoding="utf-8"))


def load_dict(data: Any, name: str = POLYGON_FILE, base_dir: Path = SCENARIOS_DIR):
    return scenario_from_dict(data, source=name, base_dir=base_dir)


def sample_route(scenario, step_m: float = 10.0) -> list[GeoPoint]:
    """Points along the route every ~step_m (straight in lat/lon, as the map draws it)."""
    pts = [w.point for w in scenario.flight.waypoints]
    out = []
    for a, b in zip(pts, pts[1:]):
        n = max(1, int(haversine_m(a, b) / step_m))
        out += [GeoPoint(a.lat + (b.lat - a.lat) * k / n, a.lon + (b.lon - a.lon) * k / n) for k in range(n)]
    return out + [pts[-1]]


# --- the shipped examples ----------------------------------------------------------------

def test_the_examples_are_package_data() -> None:
    folder = resources.files("mavconform.reference_impl.handover") / "scenarios"
    # and conformance.json: the conformance suite's handover clauses' default (HO.SEQ.*)
    assert sorted(p.name for p in folder.iterdir() if p.name.endswith(".json")) == sorted(SHIPPED + ("conformance.json",))


@pytest.mark.parametrize("name, method", list(zip(SHIPPED, (RegionMethod.POLYGON, RegionMethod.CIRCLE,
                                                           RegionMethod.WAYPOINTS))))
def test_each_region_method_has_an_example(name: str, method: RegionMethod) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    assert s.region_method is method
    assert [g.name for g in s.gcs] == ["A", "B"] and s.parent == "A"
    assert s.home == GeoPoint(47.397742, 8.545594, 0)
    assert s.flight.waypoints[0].point.lat == s.flight.waypoints[-1].point.lat == s.home.lat   # back to launch
    assert 5000 < s.flight.length_m() < 8000                                                 # a few km
    assert len(s.rally) == 3 and s.seed == 403


@pytest.mark.parametrize("name", SHIPPED[:2])
def test_the_geographic_examples_fly_out_through_the_overlap_and_back(name: str) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    covered = [s.covering(p) for p in sample_route(s)]
    assert all(covered), "the route never leaves coverage"
    assert covered[0] == ("A",) and covered[-1] == ("A",)
    delivery = s.flight.waypoints[4].point
    assert s.covering(delivery) == ("B",)
    # Outbound and back, each crosses the overlap: A -> AB -> B ... B -> AB -> A.
    runs = [c for i, c in enumerate(covered) if i == 0 or c != covered[i - 1]]
    assert runs == [("A",), ("A", "B"), ("B",), ("A", "B"), ("A",)]
    ((a, b, region),) = s.handover_regions()
    assert (a, b) == ("A", "B") and region.contains(s.flight.waypoints[2].point)


def test_the_waypoint_example_hands_over_at_waypoints_2_and_6() -> None:
    s = load_scenario(SCENARIOS_DIR / SHIPPED[2])
    owners = s.ownership()
    assert owners is not None and s.handover_regions() == () and s.covering(s.home) == ()
    seq_owner = [owners.owner(w.seq) for w in s.flight.waypoints]
    assert seq_owner == ["A", "A", "B", "B", "B", "B", "A", "A", "A"]
    # ...and the places those waypoints are lie in the overlap of the polygon example.
    geo = load_scenario(SCENARIOS_DIR / POLYGON_FILE)
    for seq in (2, 6):
        assert geo.covering(s.flight.waypoints[seq].point) == ("A", "B")


@pytest.mark.parametrize("name", SHIPPED)
def test_the_battery_flies_the_route_with_the_reserve_left(name: str) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    assert usable_range_m(s.initial_battery, s.battery) > s.flight.length_m()
    after = s.initial_battery.after(s.flight.length_m(), s.battery)
    assert after.remaining_wh > s.battery.reserve_wh
    # Over the delivery point with the pack nearly spent, a rally point near it is the refuge.
    delivery = s.flight.waypoints[4].point
    refuge = choose_refuge(delivery, s.home, s.rally, after, s.battery)
    assert refuge.kind is RefugeKind.RALLY and refuge.rally_index == 1


def test_the_example_keys_and_links() -> None:
    s = load_scenario(SCENARIOS_DIR / POLYGON_FILE)
    a, b = s.gcs
    assert a.signing is not None and a.signing.secret.hex() == shipped()["gcs"][0]["signing"]["key"]
    assert b.signing is not None and b.signing.secret == secret_from_passphrase("delivery GCS B example passphrase")
    assert a.sysid == 255 and b.sysid == 254 and s.vehicle_sysid == 1
    assert a.up == a.down and a.up.loss == 0.02
    assert b.down.partitions == ((250.0, 252.0),)
    model = b.up.model()
    assert (model.loss, model.delay, model.partitions) == (0.03, 0.05, ((250.0, 252.0),))
    assert s.timeouts.triggers().loss_timeout_s == 5.0
    assert s.timeouts.max_duration_s == 1160          # 2 x 6598 m / 12 m/s + 60 s, rounded up


# --- the echo ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", SHIPPED)
def test_the_echo_reads_back_to_the_same_scenario(name: str) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    echoed = json.loads(json.dumps(scenario_to_dict(s, secrets=True)))
    assert echoed["format"] == FORMAT
    assert load_dict(echoed, name) == s
    assert scenario_to_dict(load_dict(echoed, name), secrets=True) == echoed


def test_the_echo_keeps_keys_out_unless_asked() -> None:
    s = load_scenario(SCENARIOS_DIR / POLYGON_FILE)
    text = json.dumps(scenario_to_dict(s))
    assert shipped()["gcs"][0]["signing"]["key"] not in text
    assert "passphrase" not in text and s.gcs[1].signing.secret.hex() not in text
    signing = scenario_to_dict(s)["gcs"][0]["signing"]
    assert set(signing) == {"fingerprint", "link_id"} and len(signing["fingerprint"]) == 8


def test_link_faults_echo_only_what_differs_and_split_directions() -> None:
    data = shipped()
    data["gcs"][1]["link"] = {"up": {"loss": 0.5, "drop": ["COMMAND_ACK#2"]}, "down": {"delay": 0.2}}
    del data["gcs"][0]["link"]
    s = load_dict(data)
    echo = scenario_to_dict(s)
    assert "link" not in echo["gcs"][0]
    assert echo["gcs"][1]["link"] == {"up": {"loss": 0.5, "drop": ["COMMAND_ACK#2"]}, "down": {"delay": 0.2}}
    up = s.gcs[1].up
    (rule,) = up.model().rules
    assert isinstance(rule, DropMessage) and (rule.name, rule.nth) == ("COMMAND_ACK", 2)
    assert up.model().rules[0] is not rule                       # a fresh counter for every run
    assert s.gcs[0].up == LinkFaults()


# --- one line per mistake ----------------------------------------------------------------

def _set(path: str, value: Any) -> Callable[[dict], None]:
    """A mutation of the example: set `a.b[1].c` to value (or delete it when value is DELETE)."""
    def apply(data: dict) -> None:
        keys: list[Any] = []
        for part in path.replace("]", "").replace("[", ".").split("."):
            keys.append(int(part) if part.isdigit() else part)
        target = data
        for k in keys[:-1]:
            target = target[k]
        if value is DELETE:
            del target[keys[-1]]
        else:
            target[keys[-1]] = value
    return apply


DELETE = object()

MISTAKES = [
    (_set("gcs.1.coverage.polygon.2.0", 95), "gcs[1].coverage.polygon[2][0]: latitude 95 is outside [-90, 90]"),
    (_set("gcs.0.coverage.polygon", [[47.0, 8.5], [47.5, 8.5], [48.0, 8.5]]),
     "gcs[0].coverage.polygon: zero area: all 3 distinct vertices lie on one line"),
    (_set("gcs.0.coverage.circle", {"center": [47.39, 8.54], "radius_m": -5}),
     "gcs[0].coverage.circle.radius_m: must be more than 0 metres, got -5"),
    (_set("gcs.0.coverage.bubble", 1), "gcs[0].coverage: unknown field 'bubble' (expected circle, waypoints, polygon)"),
    (_set("gcs.1.coverage", {"circle": {"center": [47.41, 8.57], "radius_m": 900}}),
     "gcs[1].coverage.polygon: missing (the scenario uses the polygon method)"),
    (_set("colour", "red"), "unknown field 'colour' (expected format, name, description, seed, region_method, "
                            "vehicle, gcs, parent, home, flight, rally, battery, timeouts)"),
    (_set("format", "v2"), "format: expected 'mavconform-handover-scenario/1', got 'v2'"),
    (_set("seed", DELETE), "seed: missing"),
    (_set("seed", -1), "seed: -1 is outside 0..18446744073709551615"),
    (_set("region_method", "hexagon"),
     "region_method: unknown region method 'hexagon' (expected one of: circle, waypoints, polygon)"),
    (_set("parent", "C"), "parent: no GCS is named 'C' (the GCSs are 'A', 'B')"),
    (_set("gcs", []), "gcs: empty (a scenario needs at least one GCS)"),
    (_set("gcs.1.name", "A"), "gcs[1].name: 'A' is also the name of gcs[0]"),
    (_set("gcs.1.name", " B"), "gcs[1].name: must be non-empty, without leading or trailing spaces, got ' B'"),
    (_set("gcs.1.sysid", 255), "gcs[1].sysid: 255 is also the system id of gcs[0]"),
    (_set("gcs.1.sysid", 1), "gcs[1].sysid: 1 is the vehicle's system id"),
    (_set("gcs.1.sysid", 256), "gcs[1].sysid: 256 is outside 1..255"),
    (_set("gcs.1.sysid", True), "gcs[1].sysid: expected an integer, got True"),
    (_set("gcs.0.signing", {"key": "00" * 32, "passphrase": "x"}),
     "gcs[0].signing: give exactly one of key (64 hex digits) or passphrase"),
    (_set("gcs.0.signing.key", "zz" * 32), "gcs[0].signing.key: a signing key is 64 hex digits (0-9, a-f)"),
    (_set("gcs.0.signing.key", "ab" * 16), "gcs[0].signing.key: a signing key is 64 hex digits, got 32 characters"),
    (_set("gcs.1.signing.passphrase", "Grüße"),
     "gcs[1].signing.passphrase: the passphrase must be ASCII (MAVProxy hashes its ASCII bytes)"),
    (_set("gcs.1.signing.link_id", 300), "gcs[1].signing.link_id: 300 is outside 0..255"),
    (_set("gcs.0.link.loss", 1.5), "gcs[0].link.loss: must be at least 0 and at most 1, got 1.5"),
    (_set("gcs.0.link.delay", -0.1), "gcs[0].link.delay: must be at least 0, got -0.1"),
    (_set("gcs.0.link.lag", 1), "gcs[0].link: unknown field 'lag' (expected loss, duplicate, reorder, "
                                "reorder_delay, delay, jitter, corrupt, partitions, drop)"),
    (_set("gcs.1.link.partitions", [[30, 20]]), "gcs[1].link.partitions[0]: ends (20 s) before it starts (30 s)"),
    (_set("gcs.1.link.partitions", [[30]]), "gcs[1].link.partitions[0]: expected [start_s, end_s], got 1 numbers"),
    (_set("gcs.1.link.drop", ["NO_SUCH_MESSAGE"]),
     "gcs[1].link.drop[0]: bad drop rule 'NO_SUCH_MESSAGE': no message named NO_SUCH_MESSAGE in the dialect"),
    (_set("gcs.1.link", {"up": {"loss": 2}}), "gcs[1].link.up.loss: must be at least 0 and at most 1, got 2"),
    (_set("flight.plan", "x.plan"),
     "flight: give exactly one of path (a list of [lat, lon, alt]) or plan (a .plan file)"),
    (_set("flight.path.3", [47.41, 8.57]), "flight.path[3]: expected [lat, lon, alt] (alt: metres above home)"),
    (_set("flight.path", [[47.397742, 8.545594, 30]]), "flight.path: a flight needs at least 2 waypoints, got 1"),
    (_set("flight.speed_m_s", DELETE), "flight.speed_m_s: missing (the cruise speed of a path flight)"),
    (_set("flight.speed_m_s", 0), "flight.speed_m_s: must be more than 0, got 0"),
    (_set("flight.path.0", [47.45, 8.545594, 30]),
     "flight.path[0]: the flight starts outside the coverage of its parent GCS 'A'"),
    (_set("home", [47.4, "east", 0]), "home[1]: expected a finite number, got 'east'"),
    (_set("rally.1", [47.4, 8.5, 40, 7]), "rally[1]: expected [lat, lon] or [lat, lon, alt], got 4 numbers"),
    (_set("battery.capacity_wh", DELETE), "battery.capacity_wh: missing"),
    (_set("battery.reserve_fraction", 1.2), "battery.reserve_fraction: must be at least 0 and at most 1, got 1.2"),
    (_set("battery.reserve_wh", 3), "battery: give reserve_fraction or reserve_wh, not both"),
    (_set("battery.initial_wh", 95), "battery: give initial_fraction or initial_wh, not both"),
    (_set("timeouts.handover_bound_s", 1.0), "timeouts.handover_bound_s: 1 s leaves no time after the 1 s dwell"),
    (_set("timeouts.loss_timeout_s", 0), "timeouts.loss_timeout_s: must be more than 0, got 0"),
]


@pytest.mark.parametrize("mutate, message", MISTAKES, ids=[m for _, m in MISTAKES])
def test_a_mistake_is_one_line_naming_the_file_and_field(mutate: Callable[[dict], None], message: str) -> None:
    data = shipped()
    mutate(data)
    with pytest.raises(ScenarioError) as caught:
        load_dict(data)
    assert str(caught.value) == f"{POLYGON_FILE}: {message}"
    assert isinstance(caught.value, UsageError)


WAYPOINT_MISTAKES = [
    (_set("gcs.1.coverage.waypoints", [2, 3, 4, 5, 9]),
     "gcs[1].coverage.waypoints: no waypoint 9 in the flight (its seqs: 0..8)"),
    (_set("gcs.1.coverage.waypoints", [1, 2, 3]), "gcs[1].coverage.waypoints: waypoint 1 is also owned by 'A'"),
    (_set("gcs.1.coverage.waypoints", [2, 2]), "gcs[1].coverage.waypoints[1]: waypoint 2 listed twice"),
    (_set("parent", "B"), "flight.path[0]: the first waypoint (0) belongs to 'A', not to the parent GCS 'B'"),
]


@pytest.mark.parametrize("mutate, message", WAYPOINT_MISTAKES, ids=[m for _, m in WAYPOINT_MISTAKES])
def test_waypoint_ownership_mistakes(mutate: Callable[[dict], None], message: str) -> None:
    data = shipped(SHIPPED[2])
    mutate(data)
    with pytest.raises(ScenarioError) as caught:
        load_dict(data, SHIPPED[2])
    assert str(caught.value) == f"{SHIPPED[2]}: {message}"


def test_another_methods_coverage_is_checked_too() -> None:
    data = shipped()
    data["gcs"][0]["coverage"]["circle"] = {"center": [95, 8.5], "radius_m": 100}
    with pytest.raises(ScenarioError, match=r"gcs\[0\]\.coverage\.circle\.center\[0\]: latitude 95 is outside"):
        load_dict(data)
    data["gcs"][0]["coverage"]["circle"] = {"center": [47.39, 8.54], "radius_m": 100}
    assert isinstance(load_dict(data).gcs[0].coverage, Polygon)        # read, but the polygon is used


@pytest.mark.parametrize("text, message", [
    ('{"seed": 1,\n "seed": 2}', "key 'seed' appears twice in one object"),
    ('{"seed": NaN}', "NaN is not a number JSON allows"),
    ('{"seed": 1,,}', "line 1 column 12: invalid JSON: Expecting property name enclosed in double quotes"),
    ("[1, 2]", "expected an object, got [1, 2]"),
])
def test_file_level_mistakes(tmp_path: Path, text: str, message: str) -> None:
    f = tmp_path / "broken.json"
    f.write_text(text)
    with pytest.raises(ScenarioError) as caught:
        load_scenario(f)
    assert str(caught.value) == f"{f}: {message}"


def test_a_missing_file(tmp_path: Path) -> None:
    with pytest.raises(ScenarioError, match=r"nope\.json: cannot read: No such file or directory$"):
        load_scenario(tmp_path / "nope.json")


# --- YAML --------------------------------------------------------------------------------

def test_yaml_reads_to_the_same_scenario(tmp_path: Path) -> None:
    yaml = pytest.importorskip("yaml")
    f = tmp_path / "delivery.yaml"
    f.write_text(yaml.safe_dump(shipped(), sort_keys=False))
    assert load_scenario(f) == load_scenario(SCENARIOS_DIR / POLYGON_FILE)


def test_a_yaml_mistake_has_its_line(tmp_path: Path) -> None:
    pytest.importorskip("yaml")
    f = tmp_path / "bad.yml"
    f.write_text("seed: 1\ngcs: [unclosed\n")
    with pytest.raises(ScenarioError, match=r"bad\.yml: line 3 column 1: invalid YAML: "):
        load_scenario(f)


# --- a flight from a .plan ---------------------------------------------------------------

def _wp(seq: int, lat: float, lon: float, alt: float, command: int = Cmd.NAV_WAYPOINT, frame: int = 3) -> MissionItem:
    return MissionItem(seq=seq, frame=frame, command=command, x=round(lat * 1e7), y=round(lon * 1e7), z=alt)


def _write_plan(folder: Path) -> list[list[float]]:
    route = shipped()["flight"]["path"]
    mission = [_wp(0, *route[0][:2], 30, Cmd.NAV_TAKEOFF)]
    mission.append(MissionItem(seq=1, frame=2, command=Cmd.DO_CHANGE_SPEED, param2=12.0))     # no position
    mission += [_wp(i + 2, lat, lon, alt) for i, (lat, lon, alt) in enumerate(route[1:4])]
    mission.append(_wp(5, route[4][0], route[4][1], 508.1, frame=0))                          # AMSL: 20 m above home
    mission.append(MissionItem(seq=6, frame=2, command=Cmd.NAV_RETURN_TO_LAUNCH))
    rally = [_wp(0, 47.404036, 8.562868, 40, Cmd.NAV_RALLY_POINT)]
    plan = plan_from_items(mission, rally=rally, home=(47.397742, 8.545594, 488.1))
    save_plan(plan, folder / "delivery.plan")
    return route


def test_a_plan_flight_is_read_relative_to_the_scenario(tmp_path: Path) -> None:
    route = _write_plan(tmp_path)
    data = shipped()
    data["flight"] = {"plan": "delivery.plan", "acceptance_radius_m": 5}
    del data["home"], data["rally"]
    s = load_dict(data, "scenario.json", tmp_path)
    assert s.flight.plan == "delivery.plan" and s.flight.speed_m_s == 15.0       # the .plan's cruiseSpeed
    assert s.flight.seqs() == (0, 2, 3, 4, 5, 6)                                 # items with a place, then RTL
    assert s.flight.waypoints[3].point.lat == pytest.approx(route[3][0], abs=1e-7)
    assert s.flight.waypoints[4].point.alt == pytest.approx(20.0, abs=1e-3)      # AMSL made relative to home
    assert s.flight.waypoints[-1].point == s.home == GeoPoint(47.397742, 8.545594, 0.0)
    assert s.rally == (GeoPoint(47.404036, 8.562868, 40.0),)
    echo = scenario_to_dict(s, secrets=True)
    assert echo["flight"] == {"speed_m_s": 15.0, "acceptance_radius_m": 5.0, "plan": "delivery.plan"}
    assert load_dict(echo, "scenario.json", tmp_path) == s


def test_a_plan_flight_under_the_waypoint_method_owns_mission_seqs(tmp_path: Path) -> None:
    _write_plan(tmp_path)
    data = shipped(SHIPPED[2])
    data["flight"] = {"plan": "delivery.plan", "speed_m_s": 10}
    data["gcs"][0]["coverage"]["waypoints"] = [0, 5, 6]
    data["gcs"][1]["coverage"]["waypoints"] = [1, 3]
    with pytest.raises(ScenarioError, match=r"^s\.json: gcs\[1\]\.coverage\.waypoints: no waypoint 1 in the flight "
                                            r"\(its seqs: 0, 2\.\.6\)$"):
        load_dict(data, "s.json", tmp_path)
    data["gcs"][1]["coverage"]["waypoints"] = [2, 3, 4]
    s = load_dict(data, "s.json", tmp_path)
    assert s.ownership().owner(4) == "B" and s.flight.speed_m_s == 10.0


def test_a_missing_plan_names_the_field(tmp_path: Path) -> None:
    data = shipped()
    data["flight"] = {"plan": "gone.plan"}
    with pytest.raises(ScenarioError, match=r"^s\.json: flight\.plan: .*gone\.plan: cannot read: No such file"):
        load_dict(data, "s.json", tmp_path)


def test_circles_of_the_example_are_the_gcs_sites() -> None:
    s = load_scenario(SCENARIOS_DIR / SHIPPED[1])
    a, b = (g.coverage for g in s.gcs)
    assert isinstance(a, Circle) and isinstance(b, Circle)
    assert a.center == GeoPoint(s.home.lat, s.home.lon) and a.radius_m == b.radius_m == 1800.0
    assert haversine_m(a.center, b.center) < a.radius_m + b.radius_m                          # they overlap


def test_a_shipped_scenario_is_found_by_name_and_a_folder_of_that_name_does_not_hide_it(tmp_path, monkeypatch):
    """From a checkout's root, `conformance` is also a folder: the name still means the
    shipped scenario; a file of that name would win."""
    from mavconform.reference_impl.handover.scenario import ScenarioError, scenario_path, shipped_scenarios
    monkeypatch.chdir(tmp_path)
    (tmp_path / "conformance").mkdir()
    assert scenario_path("conformance") == shipped_scenarios()["conformance"]
    (tmp_path / "mine.json").write_text("{}")
    assert scenario_path("mine.json") == Path("mine.json")
    with pytest.raises(ScenarioError, match=r"^nope: no such scenario file \(shipped scenarios: conformance, "):
        scenario_path("nope")
