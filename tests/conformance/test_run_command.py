"""`mavconform run`, `clauses` and `report render` from the outside: exit codes, reports,
one-line usage errors, baseline gating, expectations, and the pytest plugin."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from mavconform.conformance import expectations
from mavconform.conformance.gating import apply_expectations, gate
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.cli import main
from mavconform.reference_impl.errors import UsageError

pytestmark = pytest.mark.udp
REPORTS = {"run.json", "run.junit.xml", "run.md", "run.html", "run.mcap"}


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_run_against_builtin_writes_all_five_reports(tmp_path, capsys) -> None:
    code, out, _ = _run(capsys, "run", "--clauses", "MIS.UP.0[1-3],MIS.DN.01", "--report-dir", str(tmp_path))
    assert code == 0, out
    assert {p.name for p in tmp_path.iterdir()} == REPORTS
    doc = json.loads((tmp_path / "run.json").read_text())
    assert [c["id"] for c in doc["clauses"]] == ["MIS.UP.01", "MIS.UP.02", "MIS.UP.03", "MIS.DN.01"]
    assert all(c["outcome"] == "pass" for c in doc["clauses"])
    assert doc["identity"]["system"] == 1 and doc["volatile"]["address"].startswith("127.0.0.1:")
    assert "verdict: PASS" in out and "PASS  MIS.UP.01" in out


def test_the_capture_marks_where_each_clause_starts_and_how_it_ended(tmp_path, capsys) -> None:
    from mcap.reader import make_reader
    code, out, _ = _run(capsys, "run", "--target", "mutant:no-final-ack", "--clauses", "MIS.UP.01,MIS.UP.03",
                        "--report-dir", str(tmp_path))
    assert code == 1, out
    with open(tmp_path / "run.mcap", "rb") as f:
        marks = [(json.loads(msg.data)["message"], json.loads(msg.data)["level"], msg.log_time)
                 for _, channel, msg in make_reader(f).iter_messages() if channel.topic == "markers"]
    outcome = {c["id"]: c["outcome"] for c in json.loads((tmp_path / "run.json").read_text())["clauses"]}
    assert [m for m, _, _ in marks] == ["clause MIS.UP.01", f"clause MIS.UP.01: {outcome['MIS.UP.01']}",
                                        "clause MIS.UP.03", f"clause MIS.UP.03: {outcome['MIS.UP.03']}"]
    assert outcome["MIS.UP.03"] != "pass" and marks[3][1] != marks[1][1]
    assert [t for _, _, t in marks] == sorted(t for _, _, t in marks)


def test_mutant_fails_the_run_and_baseline_gates_only_regressions(tmp_path, capsys) -> None:
    spec_dir, mut_dir = tmp_path / "spec", tmp_path / "mut"
    clauses = "MIS.UP.1[56]"
    assert _run(capsys, "run", "--clauses", clauses, "--report-dir", str(spec_dir))[0] == 0
    code, out, _ = _run(capsys, "run", "--target", "mutant:count-zero-keeps-plan", "--clauses", clauses,
                        "--report-dir", str(mut_dir))
    assert code == 1 and "FAIL  MIS.UP.16" in out and "requirement:" in out
    # against a baseline where UP.16 passed: a regression, exit 1
    code, out, _ = _run(capsys, "run", "--target", "mutant:count-zero-keeps-plan", "--clauses", clauses,
                        "--report-dir", str(tmp_path / "m2"), "--baseline", str(spec_dir / "run.json"))
    assert code == 1 and "regression(s): MIS.UP.16" in out
    # against a baseline where it already failed: no regression, exit 0
    code, out, _ = _run(capsys, "run", "--target", "mutant:count-zero-keeps-plan", "--clauses", clauses,
                        "--report-dir", str(tmp_path / "m3"), "--baseline", str(mut_dir / "run.json"))
    assert code == 0 and "0 regression(s)" in out


def test_should_failure_gates_only_with_strict(tmp_path, capsys) -> None:
    args = ["run", "--target", "mutant:float-requests", "--clauses", "MIS.UP.15", "--report-dir", str(tmp_path)]
    assert _run(capsys, *args)[0] == 0
    assert _run(capsys, *args, "--strict")[0] == 1


def test_expectations_turn_a_failure_into_a_known_deviation(tmp_path, capsys) -> None:
    exp = tmp_path / "fork.toml"
    exp.write_text('[[deviation]]\nclause = "MIS.UP.16"\nvariant = "X1"\nreason = "keeps the plan"\n'
                   '[[deviation]]\nclause = "MIS.UP.01"\nreason = "used to fail"\n')
    code, out, _ = _run(capsys, "run", "--target", "mutant:count-zero-keeps-plan", "--clauses",
                        "MIS.UP.01,MIS.UP.16", "--expect", str(exp), "--report-dir", str(tmp_path / "r"))
    assert code == 0, out
    doc = json.loads((tmp_path / "r" / "run.json").read_text())
    by_id = {c["id"]: c for c in doc["clauses"]}
    assert by_id["MIS.UP.16"]["outcome"] == "known-deviation"
    assert by_id["MIS.UP.01"]["outcome"] == "pass"
    assert "deviation no longer observed" in by_id["MIS.UP.01"]["detail"]


def test_dead_target_is_reported_fast(tmp_path, capsys) -> None:
    import socket
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as quiet:   # bound, never answers
        quiet.bind(("127.0.0.1", 0))
        port = quiet.getsockname()[1]
        code, out, err = _run(capsys, "run", "--target", f"udp:127.0.0.1:{port}", "--clauses", "MIS.UP.01",
                              "--time-scale", "0.2", "--report-dir", str(tmp_path))
    assert code == 1
    assert "no HEARTBEAT" in err and err.count("\n") == 1
    assert json.loads((tmp_path / "run.json").read_text())["clauses"][0]["outcome"] == "error"


@pytest.mark.parametrize("argv,message", [
    (["run", "--target", "http:127.0.0.1:5"], "unknown scheme"),
    (["run", "--target", "udp:127.0.0.1:99999"], "bad port"),
    (["run", "--target", "mutant:nope"], "unknown mutant"),
    (["run", "--clauses", "MIS.NOPE.*"], "matches no vehicle clause"),
    (["run", "--clauses", ""], "no pattern given"),          # issue 12: not "run everything"
    (["run", "--level", ""], "no level given"),
    (["run", "--level", " , "], "no level given"),
    (["run", "--baseline", "/nonexistent/run.json"], "/nonexistent/run.json"),
    (["run", "--expect", "nosuchautopilot"], "nosuchautopilot"),
    (["run", "--target", "builtin:spec", "--profile", "px4"], "--profile is for an external target"),
    (["run", "--target", "udp:127.0.0.1:9", "--profile", "nosuchprofile"], "--profile: "),
    (["run", "--time-scale", "0"], "must be a finite number > 0"),
    (["run", "--time-scale", "-1"], "must be a finite number > 0"),     # issue 12: one message for both
    (["run", "--time-scale", "1e308"], "must be at most 100"),          # issue 12: not an endless wait
    (["run", "--clock-speed", "0"], "must be a finite number > 0"),
    (["run", "--clock-speed", "17"], "must be at most 16"),
    (["run", "--target", "udp:127.0.0.1:9", "--clock-speed", "2"], "external target, which lives in real time"),
    (["run", "--role", "gcs", "--time-scale", "2"], "--time-scale is for --role vehicle"),
    (["report", "render", "/nonexistent/run.json"], "/nonexistent/run.json"),
])
def test_usage_mistakes_get_one_line_and_exit_2(argv, message, capsys, tmp_path) -> None:
    with pytest.raises(SystemExit) if argv[1] in ("--time-scale", "--clock-speed") else _no_raise():
        code = main(argv + (["--report-dir", str(tmp_path)] if argv[0] == "run" else []))
        assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


class _no_raise:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_bad_baseline_file_is_a_usage_error(tmp_path, capsys) -> None:
    bad = tmp_path / "old.json"
    bad.write_text("{not json")
    code, _, err = _run(capsys, "run", "--baseline", str(bad), "--report-dir", str(tmp_path / "r"))
    assert code == 2 and str(bad) in err


def test_report_render_rewrites_html(tmp_path, capsys) -> None:
    assert _run(capsys, "run", "--target", "mutant:int-only", "--clauses", "MIS.UP.14",
                "--report-dir", str(tmp_path))[0] == 1
    out = tmp_path / "again.html"
    assert _run(capsys, "report", "render", str(tmp_path / "run.json"), "--html", str(out))[0] == 0
    html = out.read_text()
    assert "MIS.UP.14" in html and "<svg" in html


def test_clauses_lists_and_filters(capsys) -> None:
    code, out, _ = _run(capsys, "clauses", "--clauses", "MIS.UP.*", "--level", "SHOULD")
    assert code == 0 and "MIS.UP.07" in out and "MIS.UP.01" not in out
    code, out, _ = _run(capsys, "clauses", "--mutants", "--clauses", "MIS.UP.16")
    assert "mutant:count-zero-keeps-plan" in out


def test_expectations_file_errors_name_the_entry(tmp_path) -> None:
    bad = tmp_path / "x.toml"
    bad.write_text('[[deviation]]\nclause = "MIS.NOPE.01"\nreason = "r"\n')
    with pytest.raises(UsageError, match=r"x.toml: deviation\[0\]: unknown clause"):
        expectations.load(str(bad))
    bad.write_text("deviation = 3")
    with pytest.raises(UsageError, match="array of tables"):
        expectations.load(str(bad))
    bad.write_text('[[deviation]]\nreason = "r"\n')       # issue 12: not "unknown clause None"
    with pytest.raises(UsageError, match=r"x.toml: deviation\[0\]: missing 'clause'"):
        expectations.load(str(bad))
    bad.write_text('[[deviation]]\nclause = 4\nreason = "r"\n')
    with pytest.raises(UsageError, match=r"deviation\[0\]: 'clause' must be a clause id string"):
        expectations.load(str(bad))


def test_gating_rules() -> None:
    results = [ClauseResult("MIS.UP.01", Outcome.FAIL), ClauseResult("MIS.UP.07", Outcome.FAIL),
               ClauseResult("MIS.OID.01", Outcome.FAIL), ClauseResult("MIS.UP.02", Outcome.ERROR),
               ClauseResult("MIS.UP.03", Outcome.NOT_APPLICABLE)]
    flags, _ = gate(results, strict=False, baseline=None)
    assert flags == {"MIS.UP.01": True, "MIS.UP.07": False, "MIS.OID.01": False, "MIS.UP.02": True,
                     "MIS.UP.03": False}
    assert gate(results, strict=True, baseline=None)[0]["MIS.UP.07"] is True
    flags, summary = gate(results, strict=False, baseline={"MIS.UP.01": "pass", "MIS.UP.02": "error"})
    assert summary["regressions"] == ["MIS.UP.01"] and not flags["MIS.UP.02"]
    apply_expectations(results, {"MIS.UP.01": expectations.Deviation("MIS.UP.01", "why", "A1")})
    assert results[0].outcome is Outcome.KNOWN_DEVIATION and results[0].expectation == "A1: why"
    assert gate(results, strict=True, baseline=None)[0]["MIS.OID.01"] is False   # MAY never gates


def test_an_expectation_excuses_only_the_failure_it_names() -> None:
    """Review of the real-target runs: a known deviation must not hide a different failure
    of the same clause."""
    seen = "the item due was requested again 19 times; expected at most 5"
    dev = expectations.Deviation("MIS.UP.09", "uncapped retries", "P3",
                                 observed=expectations.observed_pattern(seen))
    assert dev.observed == "the item due was requested again * times; expected at most *"
    same_kind = ClauseResult("MIS.UP.09", Outcome.FAIL, "the item due was requested again 21 times; expected at most 5")
    other = ClauseResult("MIS.UP.09", Outcome.FAIL, "the upload stalled or never ended: no MISSION_ACK")
    apply_expectations([same_kind, other], {"MIS.UP.09": dev})
    assert same_kind.outcome is Outcome.KNOWN_DEVIATION
    assert other.outcome is Outcome.FAIL and other.detail.startswith("fails otherwise than the known deviation")
    assert gate([other], strict=False, baseline=None)[0]["MIS.UP.09"] is False   # a SHOULD
    apply_expectations([other], {"MIS.UP.09": dev})   # applied twice (live and at the end): once
    assert other.detail.count("fails otherwise") == 1


def test_report_expectations_drafts_a_file_that_loads(tmp_path, capsys) -> None:
    report = tmp_path / "m"
    assert main(["run", "--target", "mutant:no-retry", "--clauses", "MIS.UP.0?", "-q",
                 "--report-dir", str(report)]) == 1
    capsys.readouterr()
    out = tmp_path / "drafted.toml"
    assert main(["report", "expectations", str(report / "run.json"), "--seen-on", "mutant:no-retry",
                 "--output", str(out)]) == 0
    drafted = expectations.load(str(out))
    assert drafted and all(d.observed and d.evidence and d.seen_on == "mutant:no-retry"
                           for d in drafted.values())
    assert all(d.reason.startswith("unconfirmed") for d in drafted.values())
    assert main(["run", "--target", "mutant:no-retry", "--clauses", "MIS.UP.0?", "-q",
                 "--expect", str(out), "--report-dir", str(tmp_path / "again")]) == 0


def test_pytest_plugin_runs_clauses_as_tests(tmp_path) -> None:
    def pytest_run(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--pyargs",
                               "mavconform.conformance", *args], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    ok = pytest_run("--mavlink-target", "builtin:spec", "--mavlink-clauses", "MIS.UP.01,MIS.UP.16",
                    "--mavlink-report-dir", str(tmp_path / "r"))
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "2 passed" in ok.stdout and (tmp_path / "r" / "run.html").is_file()
    bad = pytest_run("--mavlink-target", "mutant:count-zero-keeps-plan", "--mavlink-clauses", "MIS.UP.16")
    assert bad.returncode == 1 and "MIS.UP.16" in bad.stdout
    usage = pytest_run("--mavlink-target", "nope:1")
    assert usage.returncode == 4 and "unknown scheme" in usage.stderr
    forgot = pytest_run()                       # issue 12: not "1 skipped", exit 0
    assert forgot.returncode == 4 and "needs --mavlink-target" in forgot.stdout + forgot.stderr


def test_no_reply_leaks_into_the_next_clause(tmp_path, capsys) -> None:
    """Regression: a clause that ended before the target's last reply (UP.02 once did) let
    that reply answer the next clause's first expectation."""
    assert _run(capsys, "run", "--clauses", "MIS.UP.0[1-4],MIS.DN.01,MIS.CLR.01", "--report-dir", str(tmp_path))[0] == 0
    doc = json.loads((tmp_path / "run.json").read_text())
    for clause in doc["clauses"]:
        events = [e for e in clause["exchange"] if e["dir"] != "note"]
        first_tx = next(i for i, e in enumerate(events) if e["dir"] == "tx")
        early = [e["msg"] for e in events[:first_tx] if e["msg"] not in ("MISSION_CURRENT", "STATUSTEXT")]
        assert early == [], (clause["id"], early)


def test_udp_localhost_target_in_another_process(tmp_path, capsys) -> None:
    """Regression: `localhost` and the learned 127.0.0.1 were two addresses, so every
    scripted message reached the target twice and correct targets failed."""
    import re
    vehicle = subprocess.Popen([sys.executable, "-m", "mavconform", "vehicle", "--listen", "udp:127.0.0.1:0",
                                "--quiet", "--duration", "60"], stdout=subprocess.PIPE, text=True)
    try:
        port = re.search(r"udp:127\.0\.0\.1:(\d+)", vehicle.stdout.readline()).group(1)
        code, out, _ = _run(capsys, "run", "--target", f"udp:localhost:{port}", "--clauses",
                            "MIS.UP.0[26],MIS.DN.05,MIS.TYP.02", "--report-dir", str(tmp_path))
    finally:
        vehicle.terminate()
        vehicle.wait(timeout=10)
    assert code == 0, out


def test_the_builtin_vehicle_and_the_suite_share_a_faster_clock_and_the_report_says_so(tmp_path, capsys) -> None:
    """Issue 27: the main job runs on a clock 4x real time; the timers judged (the 1 Hz
    MISSION_CURRENT stream, an upload's item timeout) are in that clock's seconds, so they
    pass at any speed, and the run says which clock it lived on. `--clock-speed 1` is real time."""
    clauses = "MIS.CUR.06,MIS.UP.07"
    code, out, _ = _run(capsys, "run", "--clauses", clauses, "--report-dir", str(tmp_path / "fast"))
    assert code == 0, out
    fast = json.loads((tmp_path / "fast" / "run.json").read_text())
    assert fast["run"]["link"] == {"kind": "in-process", "bytes_per_second": None, "reply_allowance_s": 0.0,
                                   "clock_speed": 4.0}
    assert "on a clock 4x real time shared with the target" in out
    assert "on a clock 4x real time" in (tmp_path / "fast" / "run.md").read_text()
    code, out, _ = _run(capsys, "run", "--clauses", clauses, "--clock-speed", "1", "--report-dir", str(tmp_path / "real"))
    assert code == 0, out
    real = json.loads((tmp_path / "real" / "run.json").read_text())
    assert "clock_speed" not in real["run"]["link"] and "on a clock" not in out
    assert [c["outcome"] for c in real["clauses"]] == [c["outcome"] for c in fast["clauses"]] == ["pass", "pass"]
    # a clause's own span is in clock seconds: about the same for both runs (the stream's 1 s period)
    for doc in (fast, real):
        assert doc["volatile"]["clauses"]["MIS.CUR.06"]["duration_s"] >= 1.0


def test_time_scale_does_not_fail_correct_timers(tmp_path, capsys) -> None:
    """The target's own timers are not stretched: --time-scale widens the accepted bound only."""
    code, out, _ = _run(capsys, "run", "--clauses", "MIS.UP.07,MIS.CUR.06", "--time-scale", "3", "--strict",
                        "--report-dir", str(tmp_path))
    assert code == 0, out


@pytest.mark.udp
def test_profile_says_what_an_external_target_is(capsys, tmp_path) -> None:
    """Issue 24: INAV's HEARTBEAT says "generic autopilot", so its profile cannot be chosen
    from it: --profile names it, and the plans are compared in that profile's stored form."""
    from ..vehicle_process import vehicle_process
    with vehicle_process("--quiet") as port:
        code = main(["run", "--target", f"udp:127.0.0.1:{port}", "--profile", "ardupilot", "--clauses", "MIS.UP.01",
                     "--report-dir", str(tmp_path), "-q"])
    doc = json.loads((tmp_path / "run.json").read_text())
    assert code == 0 and doc["run"]["profile"] == "ardupilot"
    assert "--profile ardupilot" in doc["identity"]["stored_form"], doc["identity"]["stored_form"]
