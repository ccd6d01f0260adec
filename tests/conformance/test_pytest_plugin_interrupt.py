"""SIGTERM to `pytest --pyargs mavconform.conformance` leaves the target as it was found and
the reports written, marked interrupted, as `mavconform run` does (issue 12)."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mavconform.reports import check_run

from ..vehicle_process import vehicle_process
from .test_interrupted_run import DEMO, WAIT, _download

pytestmark = pytest.mark.udp
DECIDED = re.compile(r"test_clause\[(\S+)\] (PASSED|FAILED|SKIPPED|XFAIL)")


def test_sigterm_to_the_pytest_plugin_restores_and_reports(tmp_path: Path, capsys) -> None:
    from mavconform.cli import main
    reports, out = tmp_path / "r", tmp_path / "out.txt"
    with vehicle_process("--quiet") as port:
        target = f"udp:127.0.0.1:{port}"
        assert main(["gcs", "upload", "--target", target, DEMO]) == 0
        before = _download(target, tmp_path / "before.plan", capsys)
        with out.open("w") as stdout:
            proc = subprocess.Popen([sys.executable, "-m", "pytest", "-v", "-p", "no:cacheprovider", "--pyargs",
                                     "mavconform.conformance", "--mavlink-target", target,
                                     "--mavlink-report-dir", str(reports)],
                                    stdout=stdout, stderr=subprocess.STDOUT, cwd=tmp_path)
            try:
                deadline = time.monotonic() + WAIT
                while len(DECIDED.findall(out.read_text())) < 3:
                    assert proc.poll() is None and time.monotonic() < deadline, out.read_text()
                    time.sleep(0.02)
                proc.send_signal(signal.SIGTERM)
                code = proc.wait(timeout=WAIT)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(timeout=10)
        after = _download(target, tmp_path / "after.plan", capsys)
    assert code == pytest.ExitCode.INTERRUPTED, out.read_text()
    assert after == before
    doc = json.loads((reports / "run.json").read_text())
    check_run(doc)
    assert doc["run"]["interrupted"] is True and doc["run"]["interrupted_by"] == "SIGTERM"
    assert doc["summary"]["verdict"] == "interrupted" and doc["summary"]["skipped"] > 0
    assert doc["restore"]["status"] in ("restored", "unchanged")
    assert {c["id"] for c in doc["clauses"]} >= {cid for cid, _ in DECIDED.findall(out.read_text())}
