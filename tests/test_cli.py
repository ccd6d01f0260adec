"""The command line: vehicle and gcs over UDP loopback, help texts, usage errors (exit 2)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR, load_plan

from .vehicle_process import vehicle_process

DEMO = str(SAMPLES_DIR / "demo.plan")


@pytest.fixture
def vehicle_port():
    """A `mavconform vehicle` process on 127.0.0.1 with an OS-chosen port; killed afterwards."""
    with vehicle_process("--loss", "0.05") as port:
        yield port


@pytest.mark.udp
def test_gcs_drives_vehicle_process_with_plan_fence_and_rally(vehicle_port, tmp_path, capsys):
    target = f"udp:127.0.0.1:{vehicle_port}"
    assert main(["gcs", "upload", "--target", target, DEMO]) == 0
    back = tmp_path / "back.plan"
    assert main(["gcs", "download", "--target", target, str(back)]) == 0
    sent, got = load_plan(DEMO), load_plan(back)
    assert (got.mission, got.fence, got.rally) == (sent.mission, sent.fence, sent.rally)
    assert main(["gcs", "set-current", "--target", target, "2"]) == 0
    assert main(["gcs", "set-current", "--target", target, "--command", "50"]) == 1
    assert main(["gcs", "clear", "--target", target, "--type", "fence"]) == 0
    assert main(["gcs", "download", "--target", target, str(back)]) == 0
    assert load_plan(back).fence == [] and load_plan(back).mission == sent.mission
    out = capsys.readouterr().out
    assert "upload fence: success" in out and "rejected" in out


@pytest.mark.udp
def test_dead_target_is_a_finding_not_a_hang(capsys):
    # port 9 (discard) on loopback: nobody answers
    assert main(["gcs", "clear", "--target", "udp:127.0.0.1:9", "--heartbeat-timeout", "0.3"]) == 1
    assert "no HEARTBEAT" in capsys.readouterr().err


@pytest.mark.parametrize("argv, needle", [
    (["gcs", "upload", "--target", "http:127.0.0.1:5", DEMO], "unknown scheme 'http'"),
    (["gcs", "upload", "--target", "udp:127.0.0.1", DEMO], "missing port"),
    (["gcs", "upload", "--target", "udp:127.0.0.1:5", "/no/such.plan"], "/no/such.plan: cannot read"),
    (["vehicle", "--listen", "udp:127.0.0.1:99999"], "bad port"),
    (["vehicle", "--loss", "1.5"], "not a probability"),
    (["vehicle", "--drop", "NOT_A_MESSAGE#2"], "NOT_A_MESSAGE"),
    (["gcs", "clear", "--target", "udp:127.0.0.1:5", "--type", "bogus"], "invalid choice"),
    (["frobnicate"], "invalid choice"),
    (["gcs", "set-current", "--target", "udp:127.0.0.1:5", "70000"], "0..65535"),
    (["gcs", "set-current", "--target", "udp:127.0.0.1:5", "--", "-3"], "0..65535"),
    (["gcs", "download", "--target", "udp:127.0.0.1:5", "back.json"], "unknown mission file type"),
    (["gcs", "download", "--target", "udp:127.0.0.1:5", "/no/such/dir/back.plan"], "does not exist"),
    (["vehicle", "--capacity", "-1"], "0..65535"),
    # issue 12: values that used to make a wait endless
    (["gcs", "clear", "--target", "udp:127.0.0.1:5", "--heartbeat-timeout", "1e308"], "at most 3600"),
    (["gcs", "clear", "--target", "udp:127.0.0.1:5", "--time-scale", "1e308"], "at most 100"),
])
def test_usage_mistakes_get_one_line_and_exit_2(argv, needle, capsys):
    with pytest.raises(SystemExit) as exc_info:
        sys.exit(main(argv))
    assert exc_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1, err


def test_bad_plan_file_names_the_file_and_place(tmp_path, capsys):
    bad = tmp_path / "bad.plan"
    bad.write_text('{"fileType": "Plan", "version": 1, "mission": {"version": 2, "items": [{"type": "ComplexItem"}]}}')
    assert main(["gcs", "upload", "--target", "udp:127.0.0.1:5", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(bad) in err and "$.mission" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("argv", [[], ["vehicle"], ["gcs"], ["gcs", "upload"], ["demo"]])
def test_help_explains_every_command(argv):
    out = subprocess.run([sys.executable, "-m", "mavconform", *argv, "--help"],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and "usage: mavconform" in out.stdout and len(out.stdout) > 200


@pytest.mark.udp
def test_demo_main_job_passes():
    out = subprocess.run([sys.executable, "-m", "mavconform", "demo"], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "10/10 steps ok" in out.stdout


def test_a_closed_pipe_is_a_normal_end_not_a_traceback():
    """Issue 12: `mavconform clauses --mutants | head -1` must not end in BrokenPipeError."""
    import subprocess
    import sys
    import os
    read_end, write_end = os.pipe()
    os.close(read_end)                       # the reader is gone before the first write (`head` done)
    try:
        done = subprocess.run([sys.executable, "-m", "mavconform", "clauses", "--mutants"],
                              stdout=write_end, stderr=subprocess.PIPE, timeout=60)
    finally:
        os.close(write_end)
    err = done.stderr.decode()
    assert done.returncode == 0, err
    assert "Traceback" not in err and "BrokenPipe" not in err
