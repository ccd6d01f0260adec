"""`mavconform fuzz`: campaigns, saved findings that replay, reports, usage errors, xdist."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mavconform.fuzz.case import LINK_LATENCY, load_case
from mavconform.cli import main
from mavconform.reports.run_document import load_run

PLANTED = "mutant:raises-on-truncated-frame"


def _fuzz(tmp_path: Path, *args: str) -> int:
    return main(["fuzz", "--findings", str(tmp_path / "found"), "--report-dir", str(tmp_path / "rep"),
                 "--database", str(tmp_path / "db"), "-q", *args])


def test_a_clean_campaign_exits_0_and_reports_every_invariant_passing(tmp_path, capsys) -> None:
    assert _fuzz(tmp_path, "--mode", "frames", "--examples", "20", "--seed", "3") == 0
    doc = load_run(tmp_path / "rep" / "fuzz.json")
    assert doc["summary"]["verdict"] == "pass" and doc["fuzz"]["findings"] == []
    ids = {c["id"] for c in doc["clauses"]}
    assert {"FUZZ.FRAMES.target-crash", "FUZZ.FRAMES.no-exception"} <= ids
    assert doc["run"]["examples"] >= 20 and doc["run"]["units"] > 0
    out = capsys.readouterr().out
    assert "findings: none" in out and "examples/s" in out
    assert not list((tmp_path / "found").iterdir())   # created up front, nothing saved


def test_a_planted_bug_is_found_saved_and_replays(tmp_path, capsys) -> None:
    assert _fuzz(tmp_path, "--target", PLANTED, "--mode", "frames", "--examples", "200", "--seed", "1") == 1
    cases = sorted((tmp_path / "found").glob("*.json"))
    assert len(cases) == 1 and cases[0].with_suffix(".mcap").stat().st_size > 0
    case = load_case(cases[0])
    assert case.violation is not None and case.violation.invariant == "no-exception"
    doc = load_run(tmp_path / "rep" / "fuzz.json")
    row = next(c for c in doc["clauses"] if c["id"] == "FUZZ.FRAMES.no-exception")
    assert row["outcome"] == "fail" and row["gating"] and row["exchange"]
    assert f"mavconform fuzz --replay {cases[0]}" in row["detail"]
    assert doc["fuzz"]["findings"][0]["reproduced"] is True
    junit = (tmp_path / "rep" / "fuzz.junit.xml").read_text()
    assert "FUZZ.FRAMES.no-exception" in junit and "<failure" in junit
    capsys.readouterr()

    capture = tmp_path / "again.mcap"
    assert main(["fuzz", "--replay", str(cases[0]), "--capture", str(capture)]) == 1
    out = capsys.readouterr().out
    assert "replayed: no-exception" in out and "a different invariant" not in out
    assert capture.stat().st_size > 0


def test_a_replayed_case_that_no_longer_fails_exits_0(tmp_path, capsys) -> None:
    assert _fuzz(tmp_path, "--target", PLANTED, "--mode", "frames", "--examples", "200", "--seed", "1") == 1
    path = next((tmp_path / "found").glob("*.json"))
    fixed = json.loads(path.read_text())
    fixed["target"] = "builtin:spec"       # the same bytes against a vehicle without the bug
    path.write_text(json.dumps(fixed))
    assert main(["fuzz", "--replay", str(path)]) == 0
    assert "no invariant broke" in capsys.readouterr().out


@pytest.mark.parametrize("args, says", [
    (["--target", "http:1:2"], "bad target"),
    (["--capture", "x.mcap"], "--capture goes with --replay"),
    (["--replay", "missing.json"], "cannot read fuzz case"),
    (["--replay", "missing.json", "--examples", "3"], "--examples, --time, --profile and --restart-cmd do not apply"),
    (["--target", "builtin:spec", "--profile", "px4"], "--profile applies to external (udp:, tcp:, serial: ...) targets"),
    (["--target", "udp:127.0.0.1:9", "--profile", "no-such-profile"], "no-such-profile"),
    (["--database", "redis-ish://x"], "--database"),
    (["--database", "redis://127.0.0.1:1"], "--database redis://127.0.0.1:1: cannot reach the Redis server"),
    (["--database", "redis://127.0.0.1:port"], "not a Redis address"),
    (["--database", "plain-file/db"], "cannot create the directory"),   # issue 12: not silently nothing
])
def test_usage_mistakes_exit_2_with_one_line(tmp_path, capsys, monkeypatch, args, says) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "plain-file").write_text("not a folder")
    assert main(["fuzz", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and "\n" not in err


def test_bad_option_values_exit_2(tmp_path, capsys) -> None:
    for args in (["--examples", "0"], ["--time", "soon"], ["--mode", "bits"]):
        with pytest.raises(SystemExit) as exit_:
            main(["fuzz", *args])
        assert exit_.value.code == 2
    capsys.readouterr()


def test_database_must_be_a_directory(tmp_path, capsys) -> None:
    (tmp_path / "file").write_text("x")
    assert _fuzz(tmp_path, "--database", str(tmp_path / "file")) == 2
    assert "not a directory" in capsys.readouterr().err


def _pytest_fuzz(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    return subprocess.run(
        [sys.executable, "-m", "pytest", "--pyargs", "mavconform.fuzz", "-p", "no:cacheprovider", "-n", "2", "-v",
         "--fuzz-findings", str(tmp_path / "found"), "--fuzz-database", str(tmp_path / "db"), *args],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)


def test_shards_spread_over_cores_with_xdist_and_share_the_example_database(tmp_path) -> None:
    clean = _pytest_fuzz(tmp_path, "--fuzz-target", "builtin:spec", "--fuzz-mode", "frames",
                         "--fuzz-shards", "2", "--fuzz-examples", "10")
    assert clean.returncode == 0, clean.stdout[-2000:]
    assert "2 workers" in clean.stdout and "2 passed" in clean.stdout

    planted = _pytest_fuzz(tmp_path, "--fuzz-target", PLANTED, "--fuzz-mode", "frames",
                           "--fuzz-shards", "2", "--fuzz-examples", "200")
    assert planted.returncode == 1, planted.stdout[-2000:]
    assert "2 failed" in planted.stdout and "mavconform fuzz --replay" in planted.stdout
    assert {"[gw0]", "[gw1]"} <= {w for w in ("[gw0]", "[gw1]") if w in planted.stdout}
    saved = list((tmp_path / "db").rglob("*"))
    assert any(p.is_file() for p in saved), "the found examples are in the shared database"


def test_a_bad_fuzz_option_is_a_pytest_usage_error(tmp_path) -> None:
    done = _pytest_fuzz(tmp_path, "--fuzz-target", "builtin:spec", "--fuzz-mode", "bits")
    assert done.returncode == 4 and "--fuzz-mode" in done.stderr


def test_a_finding_keeps_only_the_steps_its_violation_needs() -> None:
    """The step-removal pass after Hypothesis: steps that do not matter are dropped, judged
    by replaying, and the kept case still breaks the same invariant."""
    from mavconform.fuzz import protocol
    from mavconform.fuzz.campaign import minimise
    from mavconform.fuzz.case import Case, Violation

    item = {"autocontinue": 1, "command": 5000, "current": 0, "frame": 0, "param1": 0.0, "param2": 0.0,
            "param3": 0.0, "param4": 0.0, "x": 0, "y": 0, "z": 0.0}
    upload = {"op": "upload", "type": 1, "items": [item, {**item, "seq": 0}]}   # a repeated seq
    noise = [{"op": "download", "type": 0}, {"op": "download", "type": 2}]
    case = Case("protocol", "mutant:non-atomic-upload", 0, (noise[0], upload, noise[1]),
                Violation("atomic-upload", "seen before minimising"))
    assert protocol.replay(case).invariant == "atomic-upload"
    small = minimise(protocol, case)
    assert small.steps == (upload,) and small.violation.invariant == "atomic-upload"
    assert protocol.replay(Case("protocol", "builtin:spec", 0, small.steps)) is None   # the mutant's bug


@pytest.mark.parametrize("step", [
    {"op": "wait", "seconds": "abc"},
    {"op": "wait", "seconds": 1e12},                 # would walk virtual time for ever
    {"op": "upload", "type": 99, "items": []},
    {"op": "upload", "type": 0, "items": "xx"},
    {"op": "set_current", "seq": 1e9},
])
def test_a_hand_edited_case_is_a_usage_error_not_a_traceback(tmp_path, capsys, step) -> None:
    from mavconform.fuzz.case import Case, save_case

    path = save_case(Case("protocol", "builtin:spec", 0, (step,)), tmp_path)
    assert main(["fuzz", "--replay", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"mavconform: error: {path}") and "\n" not in err


def test_an_unwritable_findings_folder_is_refused_before_the_search(tmp_path, capsys) -> None:
    (tmp_path / "file").write_text("x")
    assert main(["fuzz", "--mode", "frames", "--target", PLANTED, "--findings", str(tmp_path / "file" / "x"),
                 "--database", "none"]) == 2
    captured = capsys.readouterr()
    assert "--findings" in captured.err and "examples" not in captured.out


def test_protocol_fuzzing_holds_px4_and_ardupilot_to_their_own_rules(tmp_path, capsys) -> None:
    """PX4 retries until a protocol timeout (P3); ArduPilot keeps home in mission slot 0
    (A1), stores items compactly (A13) and writes items as they arrive (A2): the oracles
    apply each profile's rules, so neither is a finding."""
    assert _fuzz(tmp_path, "--target", "builtin:px4", "--examples", "60", "--seed", "2") == 0
    assert _fuzz(tmp_path, "--target", "builtin:ardupilot", "--examples", "60", "--seed", "3") == 0


@pytest.mark.udp
def test_protocol_fuzzing_a_single_peer_vehicle_over_udp_is_heard(tmp_path) -> None:
    """Issue 11: real PX4 and ArduPilot SITL send to the GCS port they were given and bind
    their link to that one peer; the fuzzer's probe GCS on a socket of its own was never
    answered, so `still-answers` fired at step 0. All the fuzzer's GCSs now share the one
    socket (udpin: the same port every example), routed by system id."""
    import socket

    from tests.vehicle_process import vehicle_process
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:   # a free port for us
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with vehicle_process("--single-peer", "--connect", f"udp:127.0.0.1:{port}"):
        code = _fuzz(tmp_path, "--target", f"udpin:{port}", "--mode", "protocol",
                     "--examples", "3", "--seed", "4", "--time", "60s")
        doc = load_run(tmp_path / "rep" / "fuzz.json")
        assert code == 0 and doc["fuzz"]["findings"] == [], doc["fuzz"]["findings"]
        # Issue 11: `--time` is a budget the campaign keeps. Over UDP one example can take
        # longer than a whole budget; the first chunk was 8 examples (4x a 60 s budget on
        # real PX4). Now: one example first, and past the budget the steps stop.
        started = time.monotonic()
        code = _fuzz(tmp_path / "budget", "--target", f"udpin:{port}", "--mode", "protocol",
                     "--seed", "5", "--time", "6s")
        elapsed = time.monotonic() - started
    assert code == 0 and elapsed < 6 + 20, elapsed   # the budget, and one step's bounded waits


def test_an_exception_of_ours_is_a_tool_error_not_a_finding(tmp_path, capsys, monkeypatch) -> None:
    """Issue 11: a bug inside mavconform during a campaign is reported apart (exit 3) with
    the steps that led to it saved for the bug report; no finding about the target."""
    from mavconform.fuzz.protocol.steps import Runner

    def broken(self, step):
        if step.get("op") == "download":
            raise KeyError("planted bug in the tool")
        return Runner._real_apply(self, step)

    monkeypatch.setattr(Runner, "_real_apply", Runner.apply, raising=False)
    monkeypatch.setattr(Runner, "apply", broken)
    found = tmp_path / "found"
    assert _fuzz(tmp_path, "--target", "builtin:spec", "--examples", "30", "--database", "none") == 3
    err = capsys.readouterr().err
    assert "tool error" in err and "not a finding about the target" in err and "Traceback" not in err
    (saved,) = found.glob("protocol-tool-error-*.json")
    assert saved.with_suffix(".txt").read_text().count("planted bug in the tool") >= 1
    assert load_case(saved).steps[-1]["op"] == "download"
    assert not list(found.glob("protocol-target-*.json"))


def test_an_exception_outside_any_example_is_a_tool_error_too(tmp_path, capsys, monkeypatch) -> None:
    """E.g. Hypothesis itself raising (FlakyStrategyDefinition): still ours, exit 3."""
    import mavconform.fuzz.protocol as protocol

    def broken_search(*args, **kwargs):
        raise RuntimeError("planted failure in the search loop")

    monkeypatch.setattr(protocol, "search", broken_search)
    found = tmp_path / "found"
    assert _fuzz(tmp_path, "--target", "builtin:spec", "--examples", "3", "--database", "none") == 3
    err = capsys.readouterr().err
    assert "tool error" in err and "planted failure in the search loop" in err and "Traceback" not in err
    (saved,) = found.glob("protocol-tool-error-*.json")
    assert "planted failure" in saved.with_suffix(".txt").read_text()


def test_a_bad_target_is_refused_before_any_banner_or_folder(tmp_path, capsys) -> None:
    code = main(["fuzz", "--target", "udp:1.2.3:5", "--findings", str(tmp_path / "found"),
                 "--report-dir", str(tmp_path / "rep")])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.startswith("mavconform: error: ") and "1.2.3" in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_a_protocol_finding_replays_with_a_marker_per_step(tmp_path, capsys) -> None:
    from mcap.reader import make_reader
    assert _fuzz(tmp_path, "--target", "mutant:non-atomic-upload", "--mode", "protocol", "--examples", "300",
                 "--seed", "1") == 1
    (case_path,) = sorted((tmp_path / "found").glob("*.json"))
    steps = load_case(case_path).steps
    from mavconform.reports.run_document import clause_events
    doc = load_run(tmp_path / "rep" / "fuzz.json")
    row = next(c for c in doc["clauses"] if c["outcome"] == "fail")
    events = clause_events(doc, row)
    peers = {(e["dir"], e["peer"]) for e in events if e["dir"] != "note"}
    assert {("tx", "tester"), ("rx", "tester")} <= peers          # GCS A, and maybe the others:
    assert {peer for _, peer in peers} <= {"tester", "gcs-b", "mute", "probe"}   # what the steps used
    assert f"step 0: {steps[0]['op']}" in [e["msg"] for e in events if e["dir"] == "note"]
    # in virtual time, yet each reply comes a link latency after what it answers: real times
    times = [e["t"] for e in events]
    assert times == sorted(times) and len(set(times)) > len(times) // 2
    first_tx = next(i for i, e in enumerate(events) if e["dir"] == "tx")
    first_rx = next(i for i, e in enumerate(events) if e["dir"] == "rx")
    assert events[first_rx]["t"] - events[first_tx]["t"] >= LINK_LATENCY
    assert load_case(case_path).found_by["latency"] == LINK_LATENCY
    capture = tmp_path / "again.mcap"
    assert main(["fuzz", "--replay", str(case_path), "--capture", str(capture)]) == 1
    with open(capture, "rb") as f:
        marks = [json.loads(m.data)["message"] for _, ch, m in make_reader(f).iter_messages() if ch.topic == "markers"]
    assert marks[0] == f"step 0: {steps[0]['op']}" and len(marks) <= len(steps)
    assert marks == [f"step {i}: {s['op']}" for i, s in enumerate(steps[:len(marks)])]
    capsys.readouterr()


def test_a_case_saved_before_link_latency_replays_over_links_without_it(tmp_path, capsys) -> None:
    """Cases found before the simulated links had a latency (no found_by.latency) replay as
    they were found; a latency that is not a number of seconds is a one-line usage error."""
    assert _fuzz(tmp_path, "--target", "mutant:non-atomic-upload", "--mode", "protocol", "--examples", "300",
                 "--seed", "1") == 1
    (case_path,) = sorted((tmp_path / "found").glob("*.json"))
    doc = json.loads(case_path.read_text())
    old = tmp_path / "old.json"
    del doc["found_by"]["latency"]
    old.write_text(json.dumps(doc))
    capture = tmp_path / "old.mcap"
    assert main(["fuzz", "--replay", str(old), "--capture", str(capture)]) == 1   # still found
    from mcap.reader import make_reader
    with open(capture, "rb") as f:
        first = {}
        for _, channel, message in make_reader(f).iter_messages():
            first.setdefault(channel.topic, message.log_time)
    assert first["a -> vehicle"] == first["vehicle -> a"]   # no latency: answered at that instant
    doc["found_by"]["latency"] = "fast"
    old.write_text(json.dumps(doc))
    capsys.readouterr()
    assert main(["fuzz", "--replay", str(old)]) == 2
    assert capsys.readouterr().err.strip().endswith("found_by.latency: expected seconds in [0, 1], got 'fast'")
