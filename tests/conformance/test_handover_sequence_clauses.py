"""The handover-sequence clauses (HO.SEQ.*): the thesis's procedure (seed 003 ch. 4) over MAVLink
operator control, as docs/handover.md maps it. They pass on builtin:spec (its mission computer
loaded from the conformance scenario), are not-applicable on a target without a system manager
or without a mission computer, play the GCSs a given scenario names, leave the target as they
found it, never disturb the mission clauses, and work against a vehicle in another process over
UDP. That each fails on its mutant (and nothing else does) is test_negative_controls.py's."""

from __future__ import annotations

import dataclasses
import json

import pytest

from mavconform.cli import main
from mavconform.conformance import catalogue
from mavconform.conformance.checks.handover_route import route_of
from mavconform.conformance.harness import procedures
from mavconform.conformance.mutants import MUTANTS
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session, build_vehicle
from mavconform.conformance.target_uri import (CONFORMANCE_SCENARIO, SUITE_CONTROL, conformance_scenario,
                                               handover_config, load_handover_scenario, parse_target,
                                               suite_handover)
from mavconform.conformance import session as session_module
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.mission_computer_transitions import HandoverOutcome, McState
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, scenario_from_dict
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

from ..vehicle_process import vehicle_process

SEQ = catalogue.select("HO.SEQ.*")
SEQ_IDS = [c.id for c in SEQ]
HOME = GeoPoint(47.397742, 8.545594)


def _session(uri: str, scenario=None) -> Session:
    target = parse_target(uri)
    return Session(target.with_scenario(scenario) if scenario is not None else target, virtual=True)


def _run(s: Session, clauses=SEQ) -> dict:
    return {r.clause_id: r for r in run_clauses(s, clauses).results}


def _not_passed(results: dict) -> dict:
    return {k: (r.outcome.value, r.detail) for k, r in results.items() if r.outcome is not Outcome.PASS}


# --- the catalogue --------------------------------------------------------------------------------

def test_the_eight_clauses_quote_the_thesis_with_the_levels_its_modal_sentences_give() -> None:
    assert SEQ_IDS == [f"HO.SEQ.{n:02d}" for n in range(1, 9)]
    assert all(c.source.startswith("seeds/003_b23246273ffd6472.txt:") for c in SEQ)
    # 319's "must notify the GCS-A" and what decides who commands: MUST; the means toward the
    # partner and the one-per-entry latch: SHOULD (conformance/catalogue.py says why)
    levels = {c.id: c.level.value for c in SEQ}
    assert {k for k, v in levels.items() if v == "MUST"} == {"HO.SEQ.02", "HO.SEQ.03", "HO.SEQ.04", "HO.SEQ.06",
                                                             "HO.SEQ.07"}
    assert {k for k, v in levels.items() if v == "SHOULD"} == {"HO.SEQ.01", "HO.SEQ.05", "HO.SEQ.08"}
    breakers = {cid: sorted(m.name for m in MUTANTS.values() if cid in m.breaks) for cid in SEQ_IDS}
    assert all(len(names) == 1 for names in breakers.values()), breakers


# --- builtin:spec -------------------------------------------------------------------------------------

def test_every_clause_passes_on_builtin_spec_and_leaves_it_as_found() -> None:
    with _session("builtin:spec") as s:
        s.discover()
        before = procedures.stored(s.t, MissionType.MISSION)
        results = _run(s)
        vehicle = s.vehicle
        after = procedures.stored(s.t, MissionType.MISSION)
        where = vehicle.flight.where(s.driver.clock.now())
    assert _not_passed(results) == {}
    # one cooperative handover, one the commander never answered: aborted within the bound
    done = vehicle.mission_computer.results
    assert [(r.outcome, r.commander, r.partner) for r in done] == [(HandoverOutcome.COMPLETED, 245, 246),
                                                                    (HandoverOutcome.ABORTED, 245, 246)]
    assert [step for step, _ in done[0].steps] == [1, 2, 3, 4, 5, 6]
    assert done[1].duration == pytest.approx(suite_handover().commit_timeout)
    # as found: nobody in control, the plan it held, on the ground where it started
    assert vehicle.owner == 0 and procedures.same_plan(after, before)
    assert not vehicle.flight.flying and vehicle.mission_computer.state is McState.ON_LOAD
    assert haversine_m(GeoPoint(where.lat, where.lon), HOME) < 1.0


def test_the_suite_loads_builtin_specs_mission_computer_from_the_scenario_and_nothing_else_gets_one() -> None:
    config = handover_config(conformance_scenario())
    assert parse_target("builtin:spec").suite_overrides() == {"control": SUITE_CONTROL, "handover": config}
    assert (config.parent, config.gcs_ids, config.dwell, config.bound) == (245, (245, 246), 1.0, 10.0)
    other = _renumbered(201, 202)
    assert parse_target("builtin:spec").with_scenario(other).suite_overrides()["handover"].gcs_ids == (201, 202)
    for uri in ("builtin:px4", "builtin:ardupilot", "mutant:request-not-forwarded"):
        assert "handover" not in parse_target(uri).suite_overrides()
    assert build_vehicle(parse_target("builtin:spec")).mission_computer is None   # as the fuzzers build it


def test_the_mission_clauses_never_start_a_handover_on_builtin_spec() -> None:
    """Every MIS clause, the progress flights included, on the vehicle with its mission
    computer: no handover starts (none of them takes control, and their flights stay in GCS A's
    disc, away from the handover region), and every verdict is a pass, as before."""
    with _session("builtin:spec") as s:
        results = _run(s, catalogue.select("MIS.*"))
        vehicle = s.vehicle
        flown = s.cache["mission_flight"][0].plan.items   # the progress clauses' one flight
    assert _not_passed(results) == {}
    assert vehicle.mission_computer.results == [] and not vehicle.handover_events
    assert any(moved[2] is McState.ON_MISSION for moved in vehicle.mission_computer.recent)   # PRG flew
    route = route_of(conformance_scenario())
    placed = [it for it in flown if it.frame in (0, 3, 5, 6)]
    assert len(placed) >= 5
    for item in placed:   # its take-off, waypoints, loiter and landing: in A's disc, out of the region
        point = GeoPoint.from_e7(item.x, item.y)
        assert route.parent_coverage.contains(point) and not route.inside(point)


# --- not applicable -------------------------------------------------------------------------------

@pytest.mark.parametrize("uri", ["builtin:px4", "builtin:ardupilot"])
def test_a_target_without_operator_control_is_not_applicable(uri: str) -> None:
    with _session(uri) as s:
        results = _run(s)
    assert {r.outcome for r in results.values()} == {Outcome.NOT_APPLICABLE}
    assert all("sent no CONTROL_STATUS" in r.detail for r in results.values())


def test_a_system_manager_without_a_mission_computer_is_not_applicable_after_one_flight(monkeypatch) -> None:
    vehicle = VehicleNode(VehicleConfig(control=SUITE_CONTROL))
    monkeypatch.setattr(session_module, "build_vehicle", lambda uri, **config: vehicle)
    with _session("builtin:spec") as s:
        results = _run(s)
    assert {r.outcome for r in results.values()} == {Outcome.NOT_APPLICABLE}
    assert all("no mission computer" in r.detail for r in results.values())
    flights = [e for e in vehicle.events if e.startswith("mission: 5 items stored")]   # the flight's plan
    assert len(flights) == 1 and vehicle.owner == 0 and not vehicle.flight.flying


def test_without_leave_to_fly_the_clauses_are_skipped() -> None:
    with Session(parse_target("builtin:spec"), virtual=True, allow_flight=False) as s:
        results = _run(s)
    assert {r.outcome for r in results.values()} == {Outcome.SKIPPED}
    assert all("--allow-flight" in r.detail for r in results.values())


# --- the scenario --------------------------------------------------------------------------------------

def _renumbered(a: int, b: int):
    data = json.loads(CONFORMANCE_SCENARIO.read_text(encoding="utf-8"))
    data["gcs"][0]["sysid"], data["gcs"][1]["sysid"] = a, b
    return scenario_from_dict(data, source="renumbered.json", base_dir=SCENARIOS_DIR)


def test_the_tester_plays_the_gcss_the_scenario_names() -> None:
    """GCSs 201 and 202: the builtin's mission computer and the tester both take them from the
    scenario, so the suite's own GCSs (245, 246) only stand by."""
    with _session("builtin:spec", _renumbered(201, 202)) as s:
        results = _run(s)
        done = s.vehicle.mission_computer.results
    assert _not_passed(results) == {}
    assert [(r.commander, r.partner) for r in done] == [(201, 202), (201, 202)]


def test_the_conformance_scenario_puts_the_hold_in_the_lens_between_the_discs() -> None:
    route = route_of(conformance_scenario())
    assert (route.parent, route.partner, route.dwell, route.bound, route.commit) == (245, 246, 1.0, 10.0, 7.5)
    assert route.inside(route.hold) and 124 < haversine_m(HOME, route.hold) < 126
    assert not route.inside(HOME) and route.parent_coverage.contains(HOME)


def test_scenario_mistakes_are_usage_errors(tmp_path) -> None:
    with pytest.raises(UsageError, match="no such scenario file"):
        load_handover_scenario(str(tmp_path / "nowhere.json"))
    with pytest.raises(UsageError, match="need a circle or polygon scenario"):
        load_handover_scenario("delivery-flight-waypoints")
    apart = json.loads(CONFORMANCE_SCENARIO.read_text(encoding="utf-8"))
    apart["gcs"][1]["coverage"]["circle"]["center"] = [47.40, 8.56]   # B's disc far from the path
    path = tmp_path / "apart.json"
    path.write_text(json.dumps(apart), encoding="utf-8")
    with pytest.raises(UsageError, match="never enters a handover region"):
        load_handover_scenario(str(path))
    assert load_handover_scenario("conformance") == conformance_scenario()   # a shipped name, not ./conformance/


def test_run_takes_the_option_and_records_it(tmp_path, capsys) -> None:
    assert main(["run", "--clauses", "HO.SEQ.01", "--handover-scenario", str(tmp_path / "x.json"),
                 "--report-dir", str(tmp_path)]) == 2
    assert "--handover-scenario" in capsys.readouterr().err
    options = dataclasses.replace(__import__("mavconform.conformance.document", fromlist=["RunOptions"]).RunOptions(
        "builtin:spec"), handover_scenario="conformance")
    from mavconform.conformance import suite
    prepared = suite.prepare(options)
    assert prepared.uri.handover_scenario == conformance_scenario()


# --- over UDP, a vehicle in another process -------------------------------------------------------

@pytest.mark.udp
def test_the_clauses_against_a_handover_vehicle_process(tmp_path, capsys) -> None:
    """`mavconform vehicle --handover conformance.json` (closed while nobody is in control, its
    stored mission the scenario's flight, the second GCS on the first one's socket): every
    clause passes and the target is left as it was found. Two flights, flown 4 times faster than
    real (holds and timers as they are): about 45 s."""
    with vehicle_process("--handover", str(CONFORMANCE_SCENARIO), "--duration", "240",
                         "--flight-speedup", "4") as port:
        code = main(["run", "--report-dir", str(tmp_path), "--target", f"udp:127.0.0.1:{port}", "--clauses",
                     "HO.SEQ.*", "--allow-flight", "--handover-scenario", str(CONFORMANCE_SCENARIO)])
        capsys.readouterr()
    doc = json.loads((tmp_path / "run.json").read_text())
    outcomes = {c["id"]: (c["outcome"], c["detail"]) for c in doc["clauses"]}
    assert code == 0 and {k: v for k, v in outcomes.items() if v[0] != "pass"} == {}
    assert list(outcomes) == SEQ_IDS
    assert doc["restore"]["status"] == "unchanged"
    assert doc["run"]["handover_scenario"] == str(CONFORMANCE_SCENARIO)


@pytest.mark.udp
def test_a_vehicle_process_without_operator_control_is_not_applicable(tmp_path, capsys) -> None:
    with vehicle_process() as port:
        code = main(["run", "--report-dir", str(tmp_path), "--target", f"udp:127.0.0.1:{port}", "--clauses",
                     "HO.SEQ.*", "--allow-flight"])
        capsys.readouterr()
    doc = json.loads((tmp_path / "run.json").read_text())
    assert code == 0 and {c["outcome"] for c in doc["clauses"]} == {"not-applicable"}
