"""The profiles from the command line: `run --target builtin:NAME --expect NAME`,
`vehicle --profile`, and `profiles`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mavconform.conformance import expectations
from mavconform.conformance.expectations import BUNDLED
from mavconform.cli import main


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _without(name: str, clause: str, tmp_path: Path) -> str:
    """The bundled expectations file with one [[deviation]] table removed."""
    tables = (BUNDLED / f"{name}.toml").read_text().split("[[deviation]]")
    kept = [t for t in tables if f'"{clause}"' not in t]
    assert len(kept) == len(tables) - 1
    path = tmp_path / f"{name}-minus-one.toml"
    path.write_text("[[deviation]]".join(kept))
    return str(path)


@pytest.mark.udp
def test_px4_run_exits_0_with_only_known_deviations(tmp_path, capsys) -> None:
    code, out, _ = _run(capsys, "run", "--target", "builtin:px4", "--expect", "px4", "-q",
                        "--report-dir", str(tmp_path))
    assert code == 0, out
    doc = json.loads((tmp_path / "run.json").read_text())
    listed = len(expectations.load("px4"))
    assert doc["summary"]["known-deviation"] == listed and doc["summary"]["fail"] == 0
    assert doc["summary"]["error"] == 0 and doc["identity"]["autopilot"] == 12


@pytest.mark.udp
def test_ardupilot_run_exits_0_and_a_removed_line_makes_it_exit_1(tmp_path, capsys) -> None:
    # a quick subset over UDP (the whole list is checked in virtual time by test_self_check)
    clauses = "MIS.UP.01,MIS.UP.04,MIS.UP.11,MIS.IDL.01"
    code, out, _ = _run(capsys, "run", "--target", "builtin:ardupilot", "--expect", "ardupilot",
                        "--clauses", clauses, "-q", "--report-dir", str(tmp_path / "a"))
    assert code == 0, out
    assert "known-deviation        3" in out
    code, out, _ = _run(capsys, "run", "--target", "builtin:ardupilot", "--clauses", clauses, "-q",
                        "--expect", _without("ardupilot", "MIS.UP.11", tmp_path),   # a MUST: it gates
                        "--report-dir", str(tmp_path / "b"))
    assert code == 1 and "fail                   1" in out


@pytest.mark.udp
def test_a_listed_deviation_that_passes_is_reported(tmp_path, capsys) -> None:
    code, out, _ = _run(capsys, "run", "--target", "builtin:px4", "--expect", "ardupilot",
                        "--clauses", "MIS.UP.15", "--report-dir", str(tmp_path))
    assert code == 0, out
    (clause,) = json.loads((tmp_path / "run.json").read_text())["clauses"]
    assert clause["outcome"] == "pass" and "deviation no longer observed" in clause["detail"]


@pytest.mark.udp
def test_vehicle_serves_a_profile_and_names_it(capsys) -> None:
    code, out, _ = _run(capsys, "vehicle", "--profile", "ardupilot", "--listen", "udp:127.0.0.1:0",
                        "--duration", "0.2", "--quiet")
    assert code == 0 and "(profile ardupilot) listening on udp:127.0.0.1:" in out


def test_bad_profile_is_a_usage_error(tmp_path, capsys) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[[knob]]\nknob = "warp"\nvalue = 1\n')
    code, _, err = _run(capsys, "vehicle", "--profile", str(bad), "--duration", "0.1")
    assert code == 2 and str(bad) in err and "unknown knob 'warp'" in err and err.count("\n") == 1
    code, _, err = _run(capsys, "run", "--target", "builtin:betaflight")
    assert code == 2 and "px4" in err


def test_profiles_lists_show_and_json(capsys) -> None:
    code, out, _ = _run(capsys, "profiles")
    assert code == 0 and all(name in out for name in ("spec", "px4", "ardupilot"))
    code, out, _ = _run(capsys, "profiles", "--show", "px4")
    assert code == 0 and "alternative P1:" in out and "P4   (same-as-spec)" in out
    code, out, _ = _run(capsys, "profiles", "--show", "ardupilot", "--json")
    doc = json.loads(out)
    assert {k["variant"] for k in doc["knobs"]} >= {"A1", "A2", "A19"}
    assert any(d["variant"] == "A18" and d["kind"] == "not-reproduced" for d in doc["documented"])
    code, out, _ = _run(capsys, "profiles", "--knobs")
    assert code == 0 and "retry_cap" in out
