"""Issue 12: Ctrl-C or SIGTERM ends `mavconform fuzz` like its budget: what was found is
saved, the summary printed, the reports written and marked interrupted, exit 130."""

from __future__ import annotations

import os
import selectors
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.fuzz.case import load_case
from mavconform.reports.run_document import load_run

PLANTED = {"protocol": "mutant:non-atomic-upload", "frames": "mutant:raises-on-truncated-frame"}
REPORTS = ("fuzz.json", "fuzz.junit.xml", "fuzz.md", "fuzz.html")
PROGRESS = b" examples ("   # the progress line, printed (off a terminal) after the first example
BOUND = 60.0                # s: the longest any wait of these tests may take


def _fuzz(tmp_path: Path, *args: str) -> int:
    return main(["fuzz", "--findings", str(tmp_path / "found"), "--report-dir", str(tmp_path / "rep"),
                 "--database", "none", "-q", *args])


def _interrupted_doc(tmp_path: Path) -> dict:
    for name in REPORTS:
        assert (tmp_path / "rep" / name).stat().st_size > 0, name
    doc = load_run(tmp_path / "rep" / "fuzz.json")     # checked: a whole, valid document
    assert doc["fuzz"]["interrupted"] is True and doc["run"]["interrupted"] is True
    assert doc["summary"]["verdict"] != "pass"
    return doc


def _interrupt_after(cls: type, name: str, calls: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """`cls.name` raises KeyboardInterrupt (as Ctrl-C would) on its `calls`-th call."""
    real = getattr(cls, name)
    count = [0]

    def interrupted(*args, **kwargs):
        count[0] += 1
        if count[0] == calls:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(cls, name, interrupted)


# --- a signal to the process ------------------------------------------------------------

def _start(tmp_path: Path, *args: str) -> subprocess.Popen[bytes]:
    def sigint_as_by_default() -> None:   # a background job inherits SIGINT ignored
        signal.signal(signal.SIGINT, signal.SIG_DFL)

    return subprocess.Popen(
        [sys.executable, "-m", "mavconform", "fuzz", "--findings", str(tmp_path / "found"),
         "--report-dir", str(tmp_path / "rep"), "--database", "none", "--time", "10m", *args],
        cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=sigint_as_by_default)


def _read_until(proc: subprocess.Popen[bytes], text: bytes, timeout: float = BOUND) -> bytes:
    """What the process wrote on stderr until `text` appeared (bounded)."""
    seen = b""
    deadline = time.monotonic() + timeout
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stderr, selectors.EVENT_READ)
        while text not in seen:
            left = deadline - time.monotonic()
            assert left > 0 and proc.poll() is None, seen.decode(errors="replace")
            if sel.select(left):
                chunk = os.read(proc.stderr.fileno(), 4096)
                assert chunk, seen.decode(errors="replace")     # it closed stderr: it ended
                seen += chunk
    return seen


def _stop(proc: subprocess.Popen[bytes], signum: int) -> tuple[int, str, str]:
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=BOUND)
    return proc.returncode, out.decode(), err.decode()


@pytest.mark.parametrize("mode, signum", [("protocol", signal.SIGTERM), ("frames", signal.SIGINT),
                                          ("frames", signal.SIGTERM)])
def test_a_signal_while_searching_ends_the_campaign_with_reports(tmp_path, mode, signum) -> None:
    proc = _start(tmp_path, "--target", "builtin:spec", "--mode", mode)
    try:
        _read_until(proc, PROGRESS)
        code, out, err = _stop(proc, signum)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=BOUND)
    name = signal.Signals(signum).name
    assert code == 130, err
    assert "examples (shrinking included)" in out and f"interrupted by {name} during search" in out
    assert "findings: none" in out and "Traceback" not in err
    assert "interrupted during search" in err
    doc = _interrupted_doc(tmp_path)
    assert doc["summary"]["verdict"] == "interrupted" and doc["run"]["interrupted_at"] == "search"
    assert doc["run"]["interrupted_by"] == name
    assert doc["run"]["examples"] > 0 and doc["fuzz"]["findings"] == []
    assert all(row["outcome"] == "pass" and "interrupted" in row["detail"] for row in doc["clauses"])


@pytest.mark.udp
@pytest.mark.parametrize("mode", ["protocol", "frames"])
def test_sigterm_ends_a_campaign_against_a_udp_target_too(tmp_path, mode) -> None:
    from tests.vehicle_process import vehicle_process

    with vehicle_process() as port:
        proc = _start(tmp_path, "--target", f"udp:127.0.0.1:{port}", "--mode", mode)
        try:
            _read_until(proc, PROGRESS)
            code, out, err = _stop(proc, signal.SIGTERM)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait(timeout=BOUND)
    assert code == 130, err
    assert "interrupted by SIGTERM during search" in out and "Traceback" not in err
    assert _interrupted_doc(tmp_path)["summary"]["verdict"] == "interrupted"


# --- KeyboardInterrupt in-process ----------------------------------------------------------

@pytest.mark.parametrize("mode, where", [("protocol", ("mavconform.fuzz.protocol.steps", "Runner", "apply")),
                                         ("frames", ("mavconform.fuzz.frames.rig", "Rig", "flush"))])
def test_ctrl_c_while_searching_reports_an_interrupted_campaign(tmp_path, capsys, monkeypatch,
                                                                mode, where) -> None:
    import importlib

    module, cls, name = where
    _interrupt_after(getattr(importlib.import_module(module), cls), name, 40, monkeypatch)
    assert _fuzz(tmp_path, "--target", "builtin:spec", "--mode", mode, "--examples", "100000") == 130
    out, err = capsys.readouterr()
    assert "interrupted during search" in out and "findings: none" in out and "interrupted" in err
    doc = _interrupted_doc(tmp_path)
    assert doc["summary"]["verdict"] == "interrupted" and doc["run"]["examples"] > 0
    assert not list((tmp_path / "found").iterdir())


@pytest.mark.parametrize("mode", ["protocol", "frames"])
def test_ctrl_c_while_a_finding_is_shrunk_saves_it_as_small_as_it_got(tmp_path, capsys, monkeypatch,
                                                                      mode) -> None:
    """The third failing run is Hypothesis shrinking the first: the smallest seen so far is
    saved, replays, and fails the report."""
    if mode == "protocol":
        from mavconform.fuzz.protocol.steps import Runner
        real = Runner.check
        count = [0]

        def check(self):
            violation = real(self)
            if violation is not None:
                count[0] += 1
                if count[0] == 3:
                    raise KeyboardInterrupt
            return violation

        monkeypatch.setattr(Runner, "check", check)
    else:
        import mavconform.fuzz.frames.engine as engine
        _interrupt_after(engine, "_found", 3, monkeypatch)
    assert _fuzz(tmp_path, "--target", PLANTED[mode], "--mode", mode, "--examples", "300", "--seed", "1") == 130
    out = capsys.readouterr().out
    assert "interrupted during shrinking" in out and "findings: " in out
    doc = _interrupted_doc(tmp_path)
    assert doc["summary"]["verdict"] == "fail" and doc["run"]["interrupted_at"] == "shrinking"
    saved = sorted((tmp_path / "found").glob("*.json"))   # one per invariant seen failing
    assert saved and sorted(f["case"] for f in doc["fuzz"]["findings"]) == [str(p) for p in saved]
    assert all(f["reproduced"] for f in doc["fuzz"]["findings"])
    monkeypatch.undo()
    for path in saved:
        assert load_case(path).found_by["interrupted"] == "shrinking"
        assert main(["fuzz", "--replay", str(path)]) == 1     # the case stands on its own


def test_ctrl_c_while_a_finding_is_minimised_saves_it_unminimised(tmp_path, capsys, monkeypatch) -> None:
    from mavconform.fuzz import campaign

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(campaign, "minimise", interrupted)
    assert _fuzz(tmp_path, "--target", PLANTED["protocol"], "--examples", "300", "--seed", "1") == 130
    out = capsys.readouterr().out
    assert "interrupted during saving findings" in out and campaign.INTERRUPTED_NOTE in out
    doc = _interrupted_doc(tmp_path)
    assert doc["summary"]["verdict"] == "fail" and doc["fuzz"]["findings"]
    for finding in doc["fuzz"]["findings"]:   # the first interrupted; any other saved at once
        assert finding["note"] == campaign.INTERRUPTED_NOTE and finding["capture"] is None
        assert load_case(finding["case"]).violation.invariant == finding["invariant"]


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals are handled in the main thread only")
def test_a_signal_python_drops_still_ends_the_campaign(tmp_path, capsys, monkeypatch) -> None:
    """A KeyboardInterrupt raised inside a `__del__` (or Hypothesis's gc callback, where a
    SIGTERM landed in one run of three over UDP) is printed and dropped by Python: the
    campaign notices the signal after the example and stops all the same, quietly."""
    from mavconform.fuzz.protocol.steps import Runner

    class Bomb:
        def __del__(self) -> None:
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):   # the handler runs in here: its KeyboardInterrupt is dropped
                pass

    real = Runner.apply
    count = [0]

    def apply(self, step):
        count[0] += 1
        if count[0] == 20:
            Bomb()
        return real(self, step)

    monkeypatch.setattr(Runner, "apply", apply)
    assert _fuzz(tmp_path, "--target", "builtin:spec", "--time", "30s") == 130
    out, err = capsys.readouterr()
    assert "interrupted by SIGTERM during search" in out and "Exception ignored" not in err
    doc = _interrupted_doc(tmp_path)
    assert doc["summary"]["verdict"] == "interrupted"
    assert doc["volatile"]["duration_s"] < 15, "it stopped after that example, not at the end of its budget"


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals are handled in the main thread only")
def test_a_second_signal_while_the_reports_are_written_waits_for_them(tmp_path, capsys, monkeypatch) -> None:
    from mavconform.reports import write

    real = write.write_reports

    def signalled(*args, **kwargs):
        os.kill(os.getpid(), signal.SIGTERM)      # handled before the next bytecode: mid-write
        return real(*args, **kwargs)

    monkeypatch.setattr(write, "write_reports", signalled)
    assert _fuzz(tmp_path, "--target", "builtin:spec", "--mode", "frames", "--examples", "5") == 130
    out, err = capsys.readouterr()
    assert "findings: none" in out and "interrupted after the campaign had finished" in err
    for name in REPORTS:
        assert (tmp_path / "rep" / name).stat().st_size > 0, name
    assert load_run(tmp_path / "rep" / "fuzz.json")["summary"]["verdict"] == "pass"   # it had finished


def test_a_held_guard_notes_signals_and_restores_the_handlers() -> None:
    from mavconform.reference_impl.interrupts import InterruptGuard

    if threading.current_thread() is not threading.main_thread():
        pytest.skip("signals are handled in the main thread only")
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    with InterruptGuard(held=True) as guard:
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(0)   # let the handler run
    assert guard.received == ["SIGTERM"]
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
