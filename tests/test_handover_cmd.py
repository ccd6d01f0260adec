"""`mavconform handover run|list` and `mavconform vehicle --handover` (UDP loopback, OS-chosen
port): what they print, write and exit with, and their usage errors."""

from __future__ import annotations

import json
import re

import pytest
import yaml

from mavconform.cli import main
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR

from .handover.test_control_cli import lines_until, vehicle_process

KEY_A = "ef27221dc0dac97b87ff44e453eb76e90af91e473b82ba51ce224b0a6b175987"   # delivery_flight.json's GCS A


def code_of(argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code)


def test_run_the_delivery_flight_by_name_writes_three_reports_and_exits_0(tmp_path, capsys):
    assert main(["handover", "run", "delivery-flight", "--report-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == ("delivery flight, polygon coverage (thesis 4.6.3): polygon coverage, GCSs A (parent), B, "
                      "seed 403 (virtual time)")
    assert out[1].startswith("2 handovers: A->B at 105.2 s (COMPLETED, ") and ", B->A at 398.8 s (COMPLETED, " in out[1]
    assert out[2].startswith("owner per segment: A 1.9-105.5 s, B 105.5-400.0 s, A 400.0-")
    assert out[3] == "flight ended at its last waypoint at 554.7 s"
    doc = json.loads((tmp_path / "handover.json").read_text(encoding="utf-8"))
    assert doc["summary"]["owners"] == ["A", "B", "A"]
    assert (tmp_path / "handover.html").read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert (tmp_path / "handover.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"


def test_a_yaml_scenario_file_with_another_seed_and_quiet(tmp_path, capsys):
    data = json.loads((SCENARIOS_DIR / "delivery_flight_circles.json").read_text(encoding="utf-8"))
    path = tmp_path / "circles.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    assert main(["handover", "run", str(path), "--seed", "11", "--quiet", "--report-dir", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and out[0].startswith("2 handovers: A->B at ") and out[1].startswith("owner per segment: A ")
    assert json.loads((tmp_path / "out" / "handover.json").read_text(encoding="utf-8"))["run"]["seed"] == 11


def test_an_aborted_handover_exits_1_and_says_which(tmp_path, capsys):
    data = json.loads((SCENARIOS_DIR / "delivery_flight.json").read_text(encoding="utf-8"))
    data["gcs"][1]["link"] = {"up": {"drop": ["COMMAND_LONG"]}}   # B's requests never arrive
    path = tmp_path / "no-b.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    assert main(["handover", "run", str(path), "--report-dir", str(tmp_path)]) == 1
    out = capsys.readouterr().out
    assert re.search(r"^2 handovers: A->B at 105\.\d s \(ABORTED, 11\.25 s\), A->B at 398\.\d s \(ABORTED, 11\.25 s\)$",
                     out, re.M), out
    assert "owner per segment: A 1.9-554.7 s" in out
    assert "FAIL handover 1 A->B ABORTED: control not granted to GCS 254 within 11.25 s" in out


def test_list_names_the_shipped_scenarios(capsys):
    assert main(["handover", "list"]) == 0
    out = capsys.readouterr().out
    for name in ("delivery-flight ", "delivery-flight-circles ", "delivery-flight-waypoints "):
        assert name in out


@pytest.mark.parametrize("argv, message", [
    (["handover", "run", "no-such-scenario"], "no-such-scenario: no such scenario file (shipped scenarios: "),
    (["handover", "run", "delivery-flight", "--seed", "-1"], "outside 0..2^64-1"),
    (["handover", "run"], "the following arguments are required: SCENARIO"),
    (["handover"], "the following arguments are required: COMMAND"),
    (["vehicle", "--handover", "delivery-flight", "--signing-roster", "x.json"],
     "--signing-roster and --handover: the scenario's GCS keys are the roster"),
    (["vehicle", "--handover", "delivery-flight", "--mutant", "no-retry"], "--mutant and --handover"),
    (["vehicle", "--handover", "delivery-flight", "--system", "9"], "--system 9: the scenario's vehicle is system 1"),
    (["vehicle", "--handover", "nowhere.json"], "nowhere.json: no such scenario file"),
])
def test_usage_errors_are_one_line_and_exit_2(argv, message, capsys):
    assert code_of(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mavconform: error: ") and err.count("\n") == 1 and message in err, err


def test_a_bad_scenario_file_names_the_field(tmp_path, capsys):
    data = json.loads((SCENARIOS_DIR / "delivery_flight.json").read_text(encoding="utf-8"))
    data["parent"] = "C"
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    assert code_of(["handover", "run", str(path), "--report-dir", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (f"mavconform: error: {path}: parent: no GCS is named 'C' "
                                       "(the GCSs are 'A', 'B')\n")
    assert not (tmp_path / "handover.json").exists()


@pytest.mark.udp
def test_vehicle_handover_announces_the_scenario_and_serves_the_parent_signed_with_its_key(capsys):
    """The scenario's vehicle over UDP: it says what it runs, holds the flight as its mission,
    grants control to the parent (system 255, signing with A's key) and prints the change."""
    with vehicle_process("--handover", "delivery-flight") as (port, proc):
        target = ["--target", f"udp:127.0.0.1:{port}", "--system", "255", "--signing-key", KEY_A]
        assert main(["gcs", "control", "request", *target]) == 0
        assert "ok   request control: granted" in capsys.readouterr().out
        printed = lines_until(proc, "granted to GCS 255")
    assert printed[0].startswith("operator control on:")
    assert printed[1] == ("handover: scenario 'delivery flight, polygon coverage (thesis 4.6.3)', region method "
                          "polygon; GCSs: A system 255 (parent), key 1503db6d; B system 254, key 4cb71dbc")
    assert printed[2].startswith("handover: dwell 1 s, handover bound 15 s, commander lost after 5 s")
    assert printed[3].startswith("handover: the flight (9 waypoints, 6.6 km at 12 m/s) is the stored mission")
    assert printed[4].startswith("mission: 9 items stored")
    assert printed[-1] == "control: gcs_main 255 (was 0), takeover disallowed: granted to GCS 255"


def test_accept_unsigned_with_a_scenario_that_has_no_keys_is_a_usage_error(capsys) -> None:
    """The option would change nothing: saying so beats letting a user think signing is on."""
    assert main(["vehicle", "--handover", "conformance", "--accept-unsigned"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mavconform: error: --accept-unsigned: the scenario ")
    assert err[0].endswith("gives its GCSs no signing keys, so nothing is signed or checked: leave the option out")
