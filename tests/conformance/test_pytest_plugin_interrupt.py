"""SIGTERM to `pytest --pyargs mavconform.conformance` leaves the target as it was found and
the reports written, marked interrupted, as `mavconform run` does (issue 12)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from mavconform.reports import check_run

from ..vehicle_process import vehicle_process
from .test_interrupted_run import DEMO, _download, sigterm_after

pytestmark = pytest.mark.udp
DECIDED = re.compile(r"test_clause\[(?P<id>\S+)\] (PASSED|FAILED|SKIPPED|XFAIL)")


def test_sigterm_to_the_pytest_plugin_restores_and_reports(tmp_path: Path, capsys) -> None:
    from mavconform.cli import main
    reports, out = tmp_path / "r", tmp_path / "out.txt"
    with vehicle_process("--quiet") as port:
        target = f"udp:127.0.0.1:{port}"
        assert main(["gcs", "upload", "--target", target, DEMO]) == 0
        before = _download(target, tmp_path / "before.plan", capsys)
        code, _ = sigterm_after([sys.executable, "-m", "pytest", "-v", "-p", "no:cacheprovider", "--pyargs",
                                 "mavconform.conformance", "--mavlink-target", target,
                                 "--mavlink-report-dir", str(reports)],
                                out, 3, DECIDED, stderr=subprocess.STDOUT, cwd=tmp_path)
        after = _download(target, tmp_path / "after.plan", capsys)
    assert code == pytest.ExitCode.INTERRUPTED, out.read_text()
    assert after == before
    doc = json.loads((reports / "run.json").read_text())
    check_run(doc)
    assert doc["run"]["interrupted"] is True and doc["run"]["interrupted_by"] == "SIGTERM"
    assert doc["summary"]["verdict"] == "interrupted" and doc["summary"]["skipped"] > 0
    assert doc["restore"]["status"] in ("restored", "unchanged")
    assert {c["id"] for c in doc["clauses"]} >= {m.group("id") for m in DECIDED.finditer(out.read_text())}
