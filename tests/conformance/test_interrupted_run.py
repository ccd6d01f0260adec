"""`mavconform run` stopped by a signal (issue 12): SIGTERM, as CI cancel, `timeout` and
`docker stop` send it, used to kill the run outright: the target kept the suite's test
plans and run.mcap was empty. Ctrl-C restored and reported, but its run.json said "pass",
and as a --baseline it hid regressions and listed skipped clauses as "fixed"."""

from __future__ import annotations

import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from mavconform.cli import main
from mavconform.conformance import document, runner, suite
from mavconform.conformance.gating import gate
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.reference_impl.files import SAMPLES_DIR, load_plan
from mavconform.reports import check_run, html_report, junit_xml, markdown_summary

from ..reports.sample import run_document
from ..vehicle_process import vehicle_process

REPORTS = ("run.json", "run.junit.xml", "run.md", "run.html", "run.mcap")
DEMO = str(SAMPLES_DIR / "demo.plan")
DECIDED = re.compile(r"^  (PASS|FAIL|KNOWN|N/A|SKIP|ERROR) +(?P<id>\S+)", re.M)
WAIT = 60.0   # s: the bound on every wait below (the vehicle process lives 60 s)


def _download(target: str, path: Path, capsys) -> tuple:
    assert main(["gcs", "download", "--target", target, str(path)]) == 0, capsys.readouterr()
    plan = load_plan(path)
    return plan.mission, plan.fence, plan.rally


def sigterm_after(argv: list[str], out: Path, count: int, pattern: re.Pattern = DECIDED,
                  **popen: object) -> tuple[int, list[str]]:
    """Run `argv` (stdout to `out`), SIGTERM it once it has printed `count` decided clauses
    (`pattern`'s group "id"); its exit code and those ids. Every wait bounded."""
    with out.open("w") as stdout:
        proc = subprocess.Popen(argv, stdout=stdout, **popen)
        try:
            decided = _await_decided(out, proc, count, pattern)
            proc.send_signal(signal.SIGTERM)
            return proc.wait(timeout=WAIT), decided
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=10)


def _await_decided(out: Path, proc: subprocess.Popen, count: int, pattern: re.Pattern) -> list[str]:
    """The ids of the first `count` clauses the run printed as decided (bounded wait)."""
    deadline = time.monotonic() + WAIT
    while time.monotonic() < deadline:
        decided = [m.group("id") for m in pattern.finditer(out.read_text())]
        if len(decided) >= count:
            return decided
        assert proc.poll() is None, f"the run ended first: {out.read_text()}"
        time.sleep(0.02)
    raise AssertionError(f"fewer than {count} clauses decided in {WAIT} s: {out.read_text()}")


def _mcap_messages(path: Path) -> int:
    with path.open("rb") as f:
        reader = make_reader(f)
        assert reader.get_summary() is not None   # finished: summary and footer written
        return sum(1 for _ in reader.iter_messages())


@pytest.mark.udp
def test_sigterm_restores_the_target_writes_every_report_and_marks_the_run(tmp_path, capsys) -> None:
    reports, out, err = tmp_path / "r", tmp_path / "out.txt", tmp_path / "err.txt"
    with vehicle_process("--quiet") as port:
        target = f"udp:127.0.0.1:{port}"
        assert main(["gcs", "upload", "--target", target, DEMO]) == 0
        before = _download(target, tmp_path / "before.plan", capsys)
        assert all(before), "the vehicle should hold a mission, a fence and rally points"
        with err.open("w") as stderr:
            code, decided = sigterm_after([sys.executable, "-m", "mavconform", "run", "--target", target,
                                           "--report-dir", str(reports)], out, 3, stderr=stderr)
        after = _download(target, tmp_path / "after.plan", capsys)
    assert code == 130, out.read_text() + err.read_text()
    assert after == before
    for name in REPORTS:
        assert (reports / name).stat().st_size > 0, name
    assert _mcap_messages(reports / "run.mcap") > 0
    doc = json.loads((reports / "run.json").read_text())
    check_run(doc)
    assert doc["run"]["interrupted"] is True and doc["run"]["interrupted_by"] == "SIGTERM"
    assert doc["run"]["interrupted_at"] not in decided[:3]
    assert doc["summary"]["verdict"] == "interrupted" and doc["summary"]["skipped"] > 0
    assert doc["restore"]["status"] in ("restored", "unchanged")
    assert "interrupted by SIGTERM" in (reports / "run.md").read_text()
    assert "INTERRUPTED" in (reports / "run.html").read_text()
    assert "<system-err>The run was interrupted" in (reports / "run.junit.xml").read_text()
    assert "interrupted by SIGTERM" in err.read_text()


# --- in-process: where the signal lands -----------------------------------------------------

class SignalLeaked(Exception):
    """SIGTERM reached the test's own handler: nothing in the run took it."""


@pytest.fixture
def sigterm_trap():
    """SIGTERM to this process raises SignalLeaked unless the run handles it (so a run that
    does not fails the test instead of killing the test process)."""
    def trap(signum: int, frame: object) -> None:
        raise SignalLeaked
    previous = signal.signal(signal.SIGTERM, trap)
    yield trap
    signal.signal(signal.SIGTERM, previous)


def _prepared(tmp_path: Path, target: str = "builtin:spec", clauses: str = "MIS.UP.0[1-4],MIS.DN.01"):
    options = document.RunOptions(target=target, clauses=clauses)
    return suite.prepare(options, report_dir=tmp_path)


def _assert_reports(folder: Path) -> dict:
    for name in REPORTS:
        assert (folder / name).stat().st_size > 0, name
    _mcap_messages(folder / "run.mcap")
    return json.loads((folder / "run.json").read_text())


@pytest.mark.udp
def test_a_second_signal_does_not_cut_the_restore_short(tmp_path, monkeypatch, sigterm_trap) -> None:
    """SIGTERM after the second clause stops the run; another one in the middle of the
    restore is noted, and the restore and the reports still finish."""
    restore = runner._restore
    seen: dict = {}

    def restore_hit_by_a_signal(session, snapshot):
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0.05)   # the handler has run: a raise would be here
        seen["restore"] = restore(session, snapshot)
        return seen["restore"]

    monkeypatch.setattr(runner, "_restore", restore_hit_by_a_signal)
    count = []

    def on_result(clause, result) -> None:
        count.append(clause.id)
        if len(count) == 2:
            os.kill(os.getpid(), signal.SIGTERM)

    doc, outcome = suite.execute(_prepared(tmp_path), on_result=on_result)
    assert outcome.interrupted and outcome.interrupted_by == "SIGTERM"
    assert seen["restore"]["status"] == "restored", seen   # the run's uploads were undone
    assert doc["restore"] == seen["restore"]
    assert [c["outcome"] for c in doc["clauses"]] == ["pass", "pass", "skipped", "skipped", "skipped"]
    assert _assert_reports(tmp_path)["summary"]["verdict"] == "interrupted"
    assert signal.getsignal(signal.SIGTERM) is sigterm_trap   # handlers put back


@pytest.mark.udp
def test_a_signal_after_the_last_clause_leaves_the_run_complete(tmp_path, monkeypatch, sigterm_trap) -> None:
    restore = runner._restore

    def restore_hit_by_a_signal(session, snapshot):
        os.kill(os.getpid(), signal.SIGTERM)
        return restore(session, snapshot)

    monkeypatch.setattr(runner, "_restore", restore_hit_by_a_signal)
    doc, outcome = suite.execute(_prepared(tmp_path, clauses="MIS.UP.01"))
    assert not outcome.interrupted and outcome.late_signal == "SIGTERM"
    assert doc["summary"]["verdict"] == "pass" and doc["restore"]["status"] == "restored"


@pytest.mark.udp
def test_a_signal_during_discovery_still_writes_every_report(tmp_path, sigterm_trap) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as quiet:   # bound, never answers
        quiet.bind(("127.0.0.1", 0))
        prepared = _prepared(tmp_path, target=f"udp:127.0.0.1:{quiet.getsockname()[1]}")
        timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGTERM))
        timer.start()
        try:
            doc, outcome = suite.execute(prepared)
        finally:
            timer.cancel()
    assert outcome.interrupted and outcome.interrupted_at == "discovery"
    assert outcome.interrupted_by == "SIGTERM"
    assert {c["outcome"] for c in doc["clauses"]} == {"skipped"}
    assert doc["restore"]["status"] == "skipped"
    assert _assert_reports(tmp_path)["summary"]["verdict"] == "interrupted"


# --- the document, its readers and --baseline ------------------------------------------------

def _interrupted_document() -> dict:
    doc = run_document()
    doc["run"].update(interrupted=True, interrupted_at="MIS.UP.07", interrupted_by="SIGTERM")
    doc["summary"]["verdict"] = "interrupted"
    return doc


def test_every_report_says_the_run_was_interrupted() -> None:
    doc = check_run(_interrupted_document())
    assert "⏹️ INTERRUPTED" in markdown_summary(doc).splitlines()[0]
    assert "interrupted by SIGTERM during MIS.UP.07" in markdown_summary(doc)
    html = html_report(doc)
    assert '<p class="verdict interrupted">⏹️ INTERRUPTED' in html
    assert "interrupted by SIGTERM during MIS.UP.07" in html
    assert "interrupted by SIGTERM during MIS.UP.07" in junit_xml(doc)
    assert 'name="verdict" value="interrupted"' in junit_xml(doc)


def test_an_interrupted_run_cannot_claim_to_pass() -> None:
    doc = _interrupted_document()
    doc["summary"]["verdict"] = "pass"
    with pytest.raises(Exception, match="summary.verdict: 'pass', but run.interrupted is true"):
        check_run(doc)


def test_an_interrupted_run_is_refused_as_baseline(tmp_path, capsys) -> None:
    baseline = tmp_path / "interrupted run.json"
    baseline.write_text(json.dumps(_interrupted_document()))
    code = main(["run", "--baseline", str(baseline), "--report-dir", str(tmp_path / "r")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1, err
    assert str(baseline) in err and "interrupted during MIS.UP.07" in err
    assert not (tmp_path / "r" / "run.json").exists()   # refused before the first datagram


def test_report_render_keeps_the_interrupted_verdict(tmp_path, capsys) -> None:
    path = tmp_path / "run.json"
    path.write_text(json.dumps(_interrupted_document()))
    assert main(["report", "render", str(path), "--markdown", str(tmp_path / "again.md")]) == 0
    assert "INTERRUPTED" in (tmp_path / "again.md").read_text()


def test_only_a_clause_the_baseline_saw_fail_is_fixed() -> None:
    """Skipped, not applicable or undecided in the baseline and passing now is not a fix."""
    baseline = {"MIS.UP.01": "skipped", "MIS.UP.02": "not-applicable", "MIS.UP.03": "error",
                "MIS.UP.04": "fail", "MIS.UP.05": "known-deviation", "MIS.UP.06": "pass"}
    results = [ClauseResult(clause_id, Outcome.PASS) for clause_id in baseline]
    _, summary = gate(results, strict=False, baseline=baseline)
    assert summary["fixed"] == ["MIS.UP.04", "MIS.UP.05"] and summary["regressions"] == []
