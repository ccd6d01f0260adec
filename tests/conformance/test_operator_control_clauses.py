"""The operator-control clauses (HO.CTL.*): they pass on the builtin system manager, are
not-applicable on a target without one, leave another operator's control alone, and work
against a vehicle in another process over UDP. That each fails on its mutant (and nothing
else does) is test_negative_controls.py's, which runs every mutant."""

from __future__ import annotations

import dataclasses
import json

import pytest

from mavconform.cli import main
from mavconform.conformance import catalogue, session as session_module
from mavconform.conformance.mutants import MUTANTS
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session, build_vehicle
from mavconform.conformance.target_uri import SUITE_CONTROL, parse_target, suite_handover
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_manager import ControlManager
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

from ..vehicle_process import vehicle_process

HO = catalogue.select("HO.CTL.*")
HO_IDS = [c.id for c in HO]


def _run(uri: str, clauses=HO) -> dict:
    with Session(parse_target(uri), virtual=True) as s:
        return {r.clause_id: r for r in run_clauses(s, clauses).results}


def _serve(monkeypatch, vehicle: VehicleNode) -> None:
    """The next Session's in-process vehicle is `vehicle` (whatever its URI says)."""
    monkeypatch.setattr(session_module, "build_vehicle", lambda uri, **config: vehicle)


def test_the_catalogue_has_the_thirteen_clauses_from_development_xml() -> None:
    assert HO_IDS == [f"HO.CTL.{n:02d}" for n in range(1, 14)]
    assert all(c.source.startswith("mavlink-upstream/development.xml:") for c in HO)
    assert {c.level.value for c in HO} == {"SHOULD", "MAY"}   # the XML words none of them MUST
    breakers = {cid: sorted(m.name for m in MUTANTS.values() if cid in m.breaks) for cid in HO_IDS}
    assert all(len(names) == 1 for names in breakers.values()), breakers


def test_every_ho_clause_passes_on_builtin_spec() -> None:
    results = _run("builtin:spec")
    assert {k: (r.outcome.value, r.detail) for k, r in results.items() if r.outcome is not Outcome.PASS} == {}


@pytest.mark.parametrize("uri", ["builtin:px4", "builtin:ardupilot", "mutant:no-final-ack"])
def test_a_target_without_a_system_manager_is_not_applicable(uri: str) -> None:
    results = _run(uri)
    assert {r.outcome for r in results.values()} == {Outcome.NOT_APPLICABLE}
    assert all("sent no CONTROL_STATUS" in r.detail for r in results.values())


def test_the_suite_turns_control_on_for_builtin_spec_only_and_the_fuzzers_never() -> None:
    assert parse_target("builtin:spec").suite_overrides() == {"control": SUITE_CONTROL, "handover": suite_handover()}
    assert SUITE_CONTROL.open_when_unowned
    for uri in ("builtin:px4", "builtin:ardupilot", "mutant:no-final-ack"):
        assert parse_target(uri).suite_overrides() == {}
    fuzzed = build_vehicle(parse_target("builtin:spec"))   # as the fuzzers build it
    assert fuzzed.control is None and fuzzed.mission_computer is None


class _NoRequests(ControlManager):
    """Streams CONTROL_STATUS but leaves 32100 to the vehicle, which answers UNSUPPORTED."""

    def consumes(self, msg) -> bool:
        return False

    def handle(self, frame, now):
        return [] if cm.is_request_control(frame.msg) else super().handle(frame, now)


def test_a_target_that_answers_the_request_unsupported_is_not_applicable(monkeypatch) -> None:
    _serve(monkeypatch, VehicleNode(VehicleConfig(control=SUITE_CONTROL), manager_class=_NoRequests))
    results = _run("builtin:spec")
    assert results["HO.CTL.01"].outcome is Outcome.PASS   # the stream is there to judge
    rest = {k: r for k, r in results.items() if k != "HO.CTL.01"}
    assert {r.outcome for r in rest.values()} == {Outcome.NOT_APPLICABLE}
    assert all("answered MAV_RESULT_UNSUPPORTED" in r.detail for r in rest.values())


class _HeldByAnother(ControlManager):
    """GCS 77, another operator, holds control for as long as the test lasts."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._grant((77, 190), False, 0.0)


def test_another_operators_control_is_left_alone(monkeypatch) -> None:
    config = dataclasses.replace(SUITE_CONTROL, owner_loss_timeout=3600.0)
    vehicle = VehicleNode(VehicleConfig(control=config), manager_class=_HeldByAnother)
    _serve(monkeypatch, vehicle)
    results = _run("builtin:spec")
    assert results["HO.CTL.01"].outcome is Outcome.PASS
    for cid in HO_IDS[1:]:
        assert results[cid].outcome is Outcome.ERROR, (cid, results[cid].detail)
        assert "GCS 77 is in control" in results[cid].detail
    stats = vehicle.control.stats
    assert vehicle.owner == 77 and (stats.refused, stats.forwarded, stats.released) == (0, 0, 0)


def test_the_owner_loss_wait_follows_an_in_process_vehicles_own_time(monkeypatch) -> None:
    """A vehicle that drops a silent owner after 20 s (longer than the 15 s any external
    target is given) passes, because the suite built it and knows its time."""
    config = dataclasses.replace(SUITE_CONTROL, owner_loss_timeout=20.0)
    _serve(monkeypatch, VehicleNode(VehicleConfig(control=config)))
    result = _run("builtin:spec", catalogue.select("HO.CTL.13"))["HO.CTL.13"]
    assert result.outcome is Outcome.PASS, result.detail


def test_mission_clause_exchanges_do_not_record_the_control_status_stream() -> None:
    """What keeps reports stable with the builtin's 1 Hz CONTROL_STATUS: mission clauses'
    exchanges never hold it, though the tester receives it."""
    with Session(parse_target("builtin:spec"), virtual=True) as s:
        results = run_clauses(s, catalogue.select("MIS.UP.0[1-3],MIS.CUR.06,MIS.FRM.04")).results
        streamed = sum(f.msg._type == "CONTROL_STATUS" for _, f in s.t.node.inbox)
    assert streamed >= 3 and all(r.outcome is Outcome.PASS for r in results)
    assert not [e for r in results for e in r.exchange if e["msg"] == "CONTROL_STATUS"]


# --- over UDP, a vehicle in another process ------------------------------------------------------

def _run_cli(capsys, folder, *argv: str) -> tuple[int, dict]:
    code = main(["run", "--report-dir", str(folder), *argv])
    capsys.readouterr()
    return code, json.loads((folder / "run.json").read_text())


@pytest.mark.udp
def test_ho_clauses_against_a_vehicle_process_with_operator_control(tmp_path, capsys) -> None:
    """`mavconform vehicle --operator-control`: closed while nobody is in control (the
    builtin's is open), and the second GCS shares the first one's socket, as for any
    external target. Every clause passes and the target is left as it was found."""
    with vehicle_process("--operator-control") as port:
        code, doc = _run_cli(capsys, tmp_path, "--target", f"udp:127.0.0.1:{port}", "--clauses", "HO.CTL.*")
    outcomes = {c["id"]: (c["outcome"], c["detail"]) for c in doc["clauses"]}
    assert code == 0 and {k: v for k, v in outcomes.items() if v[0] != "pass"} == {}
    assert list(outcomes) == HO_IDS
    assert doc["restore"]["status"] == "unchanged"


@pytest.mark.udp
def test_ho_clauses_against_a_vehicle_process_without_it_are_not_applicable(tmp_path, capsys) -> None:
    with vehicle_process() as port:
        code, doc = _run_cli(capsys, tmp_path, "--target", f"udp:127.0.0.1:{port}", "--clauses", "HO.CTL.0[1-3]")
    assert code == 0
    assert {c["outcome"] for c in doc["clauses"]} == {"not-applicable"}
