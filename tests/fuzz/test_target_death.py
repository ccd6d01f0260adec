"""A target that dies mid-campaign is the best finding there is (issue 11).

The target is a `mavconform vehicle` in a process of its own that stops after a few
seconds (`--duration`): from the fuzzer's side exactly a crashed autopilot. The campaign
must stop, save a `target-crash` case with the capture of the live traffic that led to it,
say that it was neither replayed nor minimised (no restart hook), and exit 1, with no
traceback. With a restart hook the case is replayed against the restarted target,
reproduces, and is minimised with a restart before every attempt.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
from pathlib import Path

import pytest
from mcap.reader import make_reader

from mavconform.fuzz import campaign
from mavconform.fuzz.case import Case, load_case
from mavconform.fuzz.protocol import replay
from mavconform.cli import main
from tests.vehicle_process import vehicle_process

pytestmark = pytest.mark.udp


def _messages(path: Path) -> int:
    with path.open("rb") as f:
        return sum(1 for _ in make_reader(f).iter_messages())


def test_a_vehicle_process_that_dies_mid_campaign_is_a_saved_target_crash(tmp_path, capsys):
    found, reports = tmp_path / "found", tmp_path / "rep"
    with vehicle_process("--duration", "4") as port:
        start = time.monotonic()
        code = main(["fuzz", "--target", f"udp:127.0.0.1:{port}", "--time", "60s", "--seed", "3",
                     "--findings", str(found), "--report-dir", str(reports), "--database", "none", "-q"])
    assert code == 1
    assert time.monotonic() - start < 45          # the death ends the campaign, not the budget
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    (saved,) = found.glob("protocol-target-crash-*.json")
    case = load_case(saved)
    assert case.violation.invariant == "target-crash" and "no HEARTBEAT" in case.violation.detail
    assert case.steps and case.target == f"udp:127.0.0.1:{port}"
    capture = saved.with_suffix(".mcap")
    assert _messages(capture) > 10                 # the live traffic up to the silence
    assert "not replayed" in out and "--restart-cmd" in out
    doc = json.loads((reports / "fuzz.json").read_text())
    row = next(r for r in doc["clauses"] if r["id"] == "FUZZ.PROTOCOL.target-crash")
    assert row["outcome"] == "fail" and doc["summary"]["verdict"] == "fail"


def test_with_a_restart_hook_the_crash_case_is_replayed_and_minimised(tmp_path):
    """A planted crash (`mutant:dies-on-unknown-ack-result` in its own process): a stray ACK
    with result 200 kills it. The restart hook starts a fresh process on the same port."""
    deadly = {"op": "stray", "during": None, "after": 0.0, "messages": [
        {"msg": "MISSION_ACK", "fields": {"type": 200, "mission_type": 0, "opaque_id": 0},
         "to": "target", "from": "a"}]}
    harmless = ({"op": "download", "type": 0},)
    pids = tmp_path / "pids"
    with vehicle_process("--mutant", "dies-on-unknown-ack-result", "--quiet") as port:
        target = f"udp:127.0.0.1:{port}"
        case = Case("protocol", target, 0, (*harmless, deadly))
        first = replay(case)
        assert first is not None and first.invariant == "target-crash"
    # a restart stops the vehicle it started last (the harmless trial leaves one alive), waits
    # until it is gone, then starts another: without the stop, a new process slow to start on a
    # loaded machine bound the port after the deadly step had killed the old one, and answered
    # the replay's liveness check, so the crash was not seen again
    restart = (f"for p in $(cat {pids} 2>/dev/null); do kill -9 $p 2>/dev/null; "
               "for i in $(seq 100); do kill -0 $p 2>/dev/null || break; sleep 0.05; done; done; "
               f"{sys.executable} -m mavconform vehicle --listen udp:127.0.0.1:{port} --duration 60 --quiet "
               f"--mutant dies-on-unknown-ack-result >/dev/null 2>&1 & echo $! >> {pids}")
    ring = campaign.RingCapture()
    try:
        finding = campaign.save_death(_protocol(), Case("protocol", target, 0, (*harmless, deadly), first),
                                      tmp_path / "found", ring, campaign.Restarter(restart, timeout=20, settle=0.2),
                                      until=time.monotonic() + 60)
    finally:
        for pid in pids.read_text().split() if pids.exists() else ():
            try:
                os.kill(int(pid), signal.SIGKILL)
            except ProcessLookupError:
                pass
    assert finding.reproduced, finding.note
    assert finding.case.steps == (deadly,), finding.note   # the harmless steps were not needed
    assert "minimised from 2 to 1" in finding.note
    assert load_case(finding.path).steps == (deadly,)


def _protocol():
    return campaign.load_mode("protocol")
