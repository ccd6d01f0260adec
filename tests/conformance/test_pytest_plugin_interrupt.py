"""SIGTERM to `pytest --pyargs mavconform.conformance` leaves the target as it was found and
the reports written, marked interrupted, as `mavconform run` does (issue 12)."""

from __future__ import annotations

import contextlib
import json
import re
import subprocess
import sys
import types
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


def _frame_with_line_less_bytecode():
    with contextlib.nullcontext():   # its exit path has bytecodes without a line on 3.11
        return sys._getframe()


def _interrupt_between_lines() -> pytest.ExceptionInfo:
    """A KeyboardInterrupt whose innermost entry is a bytecode without a line number, as a
    signal landing there leaves it on CPython 3.11 (seen in CI: tb_lineno None)."""
    frame = _frame_with_line_less_bytecode()
    offsets = [2 * i for i, (line, *_) in enumerate(frame.f_code.co_positions()) if line is None]
    if not offsets or types.TracebackType(None, frame, offsets[0], -1).tb_lineno is not None:
        pytest.skip("this Python gives every bytecode a line")
    try:
        raise KeyboardInterrupt
    except KeyboardInterrupt as exc:
        exc.__traceback__.tb_next = types.TracebackType(None, frame, offsets[0], -1)
        return pytest.ExceptionInfo.from_exception(exc)


def test_an_interrupt_on_a_line_less_bytecode_is_still_reported(monkeypatch) -> None:
    from mavconform.conformance import pytest_plugin
    broken = _interrupt_between_lines()
    assert broken.traceback[-1]._rawentry.tb_lineno is None
    with pytest.raises(TypeError):   # pytest's own reporter, unaided
        broken.getrepr(funcargs=True)
    excinfo = _interrupt_between_lines()
    monkeypatch.setattr(pytest_plugin, "_STATE", {"prepared": object(), "signal": "SIGTERM"})
    pytest_plugin.pytest_keyboard_interrupt(excinfo)
    assert "KeyboardInterrupt" in str(excinfo.getrepr(funcargs=True))
    assert pytest_plugin._STATE["interrupted_by"] == "SIGTERM"
