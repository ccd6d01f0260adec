"""`mavconform run` against MSP flight controllers from the outside: builtin:msp over real TCP
loopback writing every report, a mutant failing the run, one-line usage errors, and a flight
controller that is dead, goes silent mid-run or sends garbage: reported, bounded, never a hang."""

from __future__ import annotations

import json
import socket

import pytest

from mavconform.cli import main
from mavconform.conformance.msp import session as msp_session
from mavconform.conformance.msp.clauses import MSP_CLAUSES
from mavconform.conformance.msp.runner import run_msp_clauses
from mavconform.conformance.msp.session import MspSession
from mavconform.conformance.msp.target import parse_msp_target
from mavconform.conformance.outcome import Outcome
from mavconform.reference_impl.msp.flight_controller import MspFlightController
from mavconform.reference_impl.msp.frame import MspFrame
from mavconform.reference_impl.msp.nodes import MspServerNode

REPORTS = {"run.json", "run.junit.xml", "run.md", "run.html", "run.mcap"}


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_builtin_msp_passes_over_tcp_loopback_and_writes_every_report(tmp_path, capsys) -> None:
    from mcap.reader import make_reader
    code, out, err = _run(capsys, "run", "--target", "builtin:msp", "--report-dir", str(tmp_path))
    assert code == 0, out + err
    assert {p.name for p in tmp_path.iterdir()} == REPORTS
    doc = json.loads((tmp_path / "run.json").read_text())
    assert doc["run"]["role"] == "msp" and doc["identity"]["msp_api"] == "2.5"
    assert doc["identity"]["max_waypoints"] == 120 and doc["volatile"]["address"].startswith("tcp:127.0.0.1:")
    assert [c["id"] for c in doc["clauses"]] == [c.id for c in MSP_CLAUSES]
    assert all(c["outcome"] == "pass" and c["role"] == "msp" for c in doc["clauses"])
    first = doc["clauses"][0]["exchange"]
    assert first[0]["msg"] == "MSP_SET_WP" and first[0]["fields"]["number"] == 1
    assert "MSP API 2.5, 120 waypoints at most, at tcp:127.0.0.1:" in out and "verdict: PASS" in out
    with open(tmp_path / "run.mcap", "rb") as f:
        names = {json.loads(m.data).get("msg") for _, _, m in make_reader(f).iter_messages()}
    assert {"MSP_SET_WP", "MSP_WP", "MSP_WP_GETINFO"} <= names


def test_a_mutant_fails_the_run(tmp_path, capsys) -> None:
    code, out, _ = _run(capsys, "run", "-q", "--target", "msp-mutant:stale-readback", "--report-dir", str(tmp_path))
    assert code == 1 and "verdict: FAIL (1 clause(s)" in out
    doc = json.loads((tmp_path / "run.json").read_text())
    assert {c["id"] for c in doc["clauses"] if c["outcome"] == "fail"} == {"MSP.WP.08"}


@pytest.mark.parametrize("argv,message", [
    (["--target", "msp:bogus:1"], "bad endpoint 'bogus:1'"),
    (["--target", "msp-mutant:nope"], "unknown MSP mutant 'nope'"),
    (["--target", "msp:udpin:14550"], "MSP is asked, never sent first"),
    (["--target", "msp:serial:/dev/no-such-port"], "cannot open serial port /dev/no-such-port"),
    (["--target", "builtin:msp", "--role", "vehicle"], "its clauses are --role msp"),
    (["--role", "msp", "--target", "builtin:spec"], "is no MSP target"),
    (["--target", "builtin:msp", "--profile", "inav"], "--profile is not for an MSP flight controller"),
    (["--target", "builtin:msp", "--clauses", "MIS.UP.01"], "matches no msp clause"),
])
def test_usage_mistakes_get_one_line_and_exit_2(argv, message, capsys, tmp_path) -> None:
    code, out, err = _run(capsys, "run", *argv, "--report-dir", str(tmp_path / "r"))
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "r" / "run.json").exists()


def test_a_dead_flight_controller_is_reported_not_waited_on(tmp_path, capsys) -> None:
    with socket.socket() as s:          # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    code, out, err = _run(capsys, "run", "-q", "--target", f"msp:tcp:127.0.0.1:{port}", "--report-dir", str(tmp_path))
    assert code == 1 and "target unresponsive: no reply to MSP_API_VERSION" in err
    doc = json.loads((tmp_path / "run.json").read_text())
    assert {c["outcome"] for c in doc["clauses"]} == {"error"} and doc["identity"] is None


class _FallsSilent(MspFlightController):
    """Answers `left` requests, then nothing (a flight controller that hung mid-upload)."""

    left = 60

    def handle(self, frame: MspFrame) -> list[MspFrame]:
        self.left -= 1
        return super().handle(frame) if self.left >= 0 else []


def test_silence_mid_run_errors_the_rest_and_claims_nothing_stored(monkeypatch) -> None:
    monkeypatch.setattr(msp_session, "build_server", lambda target: MspServerNode(_FallsSilent()))
    with MspSession(parse_msp_target("builtin:msp"), virtual=True) as session:
        run = run_msp_clauses(session, MSP_CLAUSES)
    outcomes = [r.outcome for r in run.results]
    cut = next(i for i, o in enumerate(outcomes) if o is Outcome.ERROR)
    assert all(o is Outcome.PASS for o in outcomes[:cut])
    assert run.results[cut].detail.startswith("target unresponsive: no reply to MSP_")
    assert all(r.detail.startswith("not run: the flight controller stopped answering") for r in run.results[cut + 1:])
    assert run.restore["status"] == "skipped" and run.unresponsive
    assert session.driver.clock.now() < 10      # bounded: one wait, one probe


class _Noisy(MspServerNode):
    """Every reply comes behind line noise and a broken frame start."""

    def take_outgoing(self):
        return [(b"\x00noise$M>\x05" + data, peer) for data, peer in super().take_outgoing()]


def test_garbage_between_replies_is_counted_and_reported(monkeypatch, tmp_path) -> None:
    from mavconform.conformance.document import RunOptions
    from mavconform.conformance.msp import suite
    monkeypatch.setattr(msp_session, "build_server", lambda target: _Noisy())
    prepared = suite.prepare(RunOptions(target="builtin:msp", role="msp"), report_dir=tmp_path)
    doc, run = suite.execute(prepared, virtual=True)
    assert doc["summary"]["verdict"] == "pass"
    msp = doc["volatile"]["link"]["msp"]
    assert msp["garbage_bytes"] > 0 and msp["bad_checksum"] + msp["bad_header"] > 0
    assert "MSP stream:" in (tmp_path / "run.md").read_text()
