"""The command path of GCS conformance: the job file, a GCS run as a process per operation over
real UDP on 127.0.0.1, a command that hangs or cannot run the job, and `mavconform run --role gcs`
refusing what makes no sense for a GCS.
"""

from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.conformance.gcs.adapters import CommandAdapter, parse_command
from mavconform.conformance.gcs.checks.common import plan_of
from mavconform.conformance.gcs.harness import GcsHarness
from mavconform.conformance.gcs.job import Job, read_job, read_result, write_job
from mavconform.conformance.gcs.runner import run_gcs_clauses
from mavconform.conformance.catalogue import select
from mavconform.conformance.clause import Role
from mavconform.conformance.outcome import Outcome
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.items import MissionType

ROOT = Path(__file__).resolve().parents[3]
REFERENCE = ROOT / "tools" / "gcs_adapters" / "reference_gcs.py"


def _python(script: str | Path, *args: str) -> str:
    return shlex.join([sys.executable, str(script), *args])


def test_a_job_survives_its_file(tmp_path: Path) -> None:
    job = Job("upload", MissionType.MISSION, tuple(plan_of()), timeout_s=12.0)
    write_job(job, tmp_path / "job.json", tmp_path / "result.json")
    back, result = read_job(tmp_path / "job.json")
    assert back == job and result == tmp_path / "result.json"
    assert json.loads((tmp_path / "job.json").read_text())["format"] == "mavconform-gcs-job/1"


@pytest.mark.parametrize("text,message", [
    ("{", "job file"),
    ('{"format": "other"}', "not a mavconform-gcs-job/1 job"),
    ('{"format": "mavconform-gcs-job/1", "op": "fly", "mission_type": "mission", "result": "r"}', "needs op"),
    ('{"format": "mavconform-gcs-job/1", "op": "set-current", "mission_type": "mission", "result": "r"}',
     "integer seq"),
])
def test_a_bad_job_file_is_named(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "job.json").write_text(text)
    with pytest.raises(ValueError, match=message) as caught:
        read_job(tmp_path / "job.json")
    assert "job.json" in str(caught.value)


@pytest.mark.parametrize("text,message", [
    ("not json", "result file"),
    ('{"said": "x"}', "boolean \\\"ok\\\""),
    ('{"ok": true, "items": [{"seq": 0}]}', "items\\[0\\]: item lacks frame"),
])
def test_a_bad_result_file_is_named(tmp_path: Path, text: str, message: str) -> None:
    (tmp_path / "result.json").write_text(text)
    with pytest.raises(ValueError, match=message):
        read_result(tmp_path / "result.json", MissionType.MISSION)


@pytest.mark.parametrize("template,message", [
    ("", "empty command"),
    ("gcs 'unclosed", "No closing quotation"),
    ("gcs {op} {file}", "lacks {port} \\(or {gcs_port}\\)"),
    ("gcs {port} {file}", "lacks {op}"),
])
def test_a_bad_command_is_a_usage_error(template: str, message: str) -> None:
    with pytest.raises(UsageError, match=message):
        parse_command(template)


@pytest.mark.udp
def test_the_reference_gcs_as_a_command_passes_over_udp(tmp_path: Path) -> None:
    adapter = CommandAdapter(_python(REFERENCE, "{port}", "{op}", "{file}"), workdir=tmp_path)
    clauses = select("MIS.G.UP.05,MIS.G.DN.05,MIS.G.SC.01", role=Role.GCS)
    run = run_gcs_clauses(GcsHarness(adapter, timeout_s=20), clauses)
    assert {r.clause_id: r.outcome for r in run.results} == {c.id: Outcome.PASS for c in clauses}, \
        [(r.clause_id, r.detail) for r in run.results]
    assert run.identity["system"] == 255
    assert sorted(p.name for p in tmp_path.glob("result-*.json")) == [f"result-00{i}.json" for i in (1, 2, 3)]


@pytest.mark.udp
def test_a_command_that_hangs_is_stopped_at_the_bound(tmp_path: Path) -> None:
    hang = tmp_path / "hang.py"
    hang.write_text("import socket, sys, time\n"
                    "s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)\n"
                    "s.bind(('127.0.0.1', 0))\n"
                    "s.sendto(b'\\xfd', ('127.0.0.1', int(sys.argv[1])))\n"   # not a frame: sends nothing
                    "time.sleep(60)\n")
    adapter = CommandAdapter(_python(hang, "{port}", "{op}", "{file}"), workdir=tmp_path)
    run = run_gcs_clauses(GcsHarness(adapter, timeout_s=1.0), select("MIS.G.UP.0[1-4]", role=Role.GCS))
    first = run.results[0]
    assert first.outcome is Outcome.ERROR and "never ended" in first.detail, first.detail
    # three operations in a row with nothing sent: the GCS is not working; the rest is not run
    assert run.results[-1].detail.startswith("not run: the GCS sent nothing in 3 operations")


@pytest.mark.udp
def test_an_adapter_that_cannot_run_the_job_is_an_error_not_a_finding(tmp_path: Path) -> None:
    refuse = tmp_path / "refuse.py"
    refuse.write_text("import sys\nprint('no such GCS installed', file=sys.stderr)\nsys.exit(2)\n")
    adapter = CommandAdapter(_python(refuse, "{port}", "{op}", "{file}"), workdir=tmp_path)
    run = run_gcs_clauses(GcsHarness(adapter, timeout_s=5.0), select("MIS.G.UP.01", role=Role.GCS))
    assert run.results[0].outcome is Outcome.ERROR
    assert "could not run the job" in run.results[0].detail and "no such GCS installed" in run.results[0].detail


@pytest.mark.parametrize("argv,message", [
    (["run", "--role", "gcs", "--allow-flight"], "--allow-flight is for --role vehicle"),
    (["run", "--gcs-cmd", "x {port} {op} {file}"], "--gcs-cmd is for --role gcs"),
    (["run", "--role", "gcs", "--target", "builtin:spec"], "with --role gcs the GCS under test is"),
    (["run", "--role", "gcs", "--target", "gcs-mutant:nope"], "no GCS mutant 'nope'"),
    (["run", "--role", "gcs", "--target", "builtin:gcs", "--gcs-cmd", "x {port} {op} {file}"], "give one"),
    (["run", "--role", "gcs", "--clauses", "MIS.UP.01"], "matches no gcs clause"),
    (["run", "--role", "gcs", "--gcs-timeout", "0"], "--gcs-timeout must be"),
    (["run", "--role", "gcs", "--gcs-cmd", "x {port} {op} {file}", "--clock-speed", "2"],
     "a GCS command lives in real time"),
])
def test_gcs_usage_mistakes_get_one_line_and_exit_2(argv, message, capsys, tmp_path: Path) -> None:
    assert main([*argv, "--report-dir", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_a_baseline_of_the_other_role_is_refused(tmp_path: Path, capsys) -> None:
    gcs_run = tmp_path / "gcs"
    assert main(["run", "--role", "gcs", "--clauses", "MIS.G.UP.01", "--report-dir", str(gcs_run), "-q"]) == 0
    capsys.readouterr()
    assert main(["run", "--clauses", "MIS.UP.01", "--baseline", str(gcs_run / "run.json"),
                 "--report-dir", str(tmp_path / "v")]) == 2
    assert "a run of the gcs clauses; this run is of the vehicle's" in capsys.readouterr().err


def test_a_gcs_mutant_run_writes_reports_that_name_the_role(tmp_path: Path) -> None:
    code = main(["run", "--role", "gcs", "--target", "gcs-mutant:no-final-ack", "--clauses", "MIS.G.DN.05",
                 "--report-dir", str(tmp_path), "-q"])
    assert code == 1
    doc = json.loads((tmp_path / "run.json").read_text())
    assert doc["run"]["role"] == "gcs" and doc["clauses"][0]["role"] == "gcs"
    assert doc["clauses"][0]["outcome"] == "fail" and doc["clauses"][0]["decided_by"] is not None
    assert "MIS.G.DN.05" in (tmp_path / "run.md").read_text()
    assert "MIS.G.DN.05" in (tmp_path / "run.junit.xml").read_text()


def test_the_reference_gcs_and_the_suite_share_a_faster_clock_and_the_report_says_so(tmp_path: Path, capsys) -> None:
    """Issue 27: builtin:gcs (and the GCS mutants) run over UDP on a clock 4x real time, as the
    builtin vehicles do: the GCS's resend timer (about 1.5 s) and the silence bounds are judged
    in that clock's seconds, so the verdicts are real time's. A mutant whose resend comes too
    early fails at either speed; `--clock-speed 1` is real time, and then no link is recorded."""
    clauses = "MIS.G.TO.01,MIS.G.UP.06"
    runs = {}
    for speed, target in (("4", "builtin:gcs"), ("1", "builtin:gcs"), ("4", "gcs-mutant:short-timeout")):
        out = tmp_path / f"{target.split(':')[1]}-{speed}"
        extra = [] if speed == "4" else ["--clock-speed", speed]
        main(["run", "--role", "gcs", "--target", target, "--clauses", clauses, *extra, "--report-dir", str(out)])
        runs[target, speed] = (json.loads((out / "run.json").read_text()), capsys.readouterr().out)
    fast, said = runs["builtin:gcs", "4"]
    assert fast["run"]["link"] == {"kind": "in-process", "bytes_per_second": None, "reply_allowance_s": 0.0,
                                   "clock_speed": 4.0}
    assert "on a clock 4x real time shared with the target" in said
    real, said = runs["builtin:gcs", "1"]
    assert "link" not in real["run"] and "on a clock" not in said
    assert [c["outcome"] for c in fast["clauses"]] == [c["outcome"] for c in real["clauses"]] == ["pass", "pass"]
    # the resend came about 1.5 s of the run's clock after MISSION_COUNT, at either speed
    for doc in (fast, real):
        assert 1.5 <= doc["volatile"]["clauses"]["MIS.G.TO.01"]["duration_s"]
    mutant, _ = runs["gcs-mutant:short-timeout", "4"]
    assert {c["id"]: c["outcome"] for c in mutant["clauses"]}["MIS.G.TO.01"] == "fail"
