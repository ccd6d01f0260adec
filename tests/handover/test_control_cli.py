"""`mavconform vehicle --operator-control` and `mavconform gcs control` over UDP loopback
(OS-chosen port, every wait bounded), and their usage errors."""

from __future__ import annotations

import contextlib
import subprocess
import sys
import time
from typing import Iterator

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR

from ..vehicle_process import LISTENING


DEMO = str(SAMPLES_DIR / "demo.plan")


@contextlib.contextmanager
def vehicle_process(*options: str) -> Iterator[tuple[int, subprocess.Popen]]:
    """`mavconform vehicle` on an OS-chosen port for at most 60 s (so every read of its
    stdout ends); yields its port and the process; kills it afterwards."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "mavconform", "vehicle", "--listen", "udp:127.0.0.1:0", "--duration", "60",
         *options], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert LISTENING in line, line + proc.stderr.read()
        yield int(line.split(LISTENING)[1].split()[0]), proc
    finally:
        proc.kill()
        proc.wait(timeout=10)


def lines_until(proc: subprocess.Popen, last: str) -> list[str]:
    """The process's stdout lines up to one containing `last` (or its end, by --duration)."""
    lines = []
    for line in proc.stdout:
        lines.append(line.rstrip("\n"))
        if last in line:
            break
    return lines


@pytest.mark.udp
def test_gcs_control_against_a_vehicle_process_with_operator_control(capsys):
    """201 takes control; 202's upload is refused and its request, unanswered by 201 (whose
    command has exited), is refused after its 3 s timeout; 201 releases. The owner-loss time
    is long so that 201 is still in control for the whole exchange."""
    with vehicle_process("--operator-control", "--owner-loss", "60") as (port, proc):
        target = ["--target", f"udp:127.0.0.1:{port}"]
        assert main(["gcs", "control", "request", *target, "--system", "201"]) == 0
        assert "ok   request control: granted" in capsys.readouterr().out

        assert main(["gcs", "upload", *target, "--system", "202", DEMO]) == 1
        assert "DENIED" in capsys.readouterr().out

        started = time.monotonic()
        assert main(["gcs", "control", "request", *target, "--system", "202", "--timeout", "3"]) == 1
        out = capsys.readouterr().out
        assert "control: GCS 201 in control, takeover disallowed" in out
        assert "FAIL request control: refused" in out
        assert time.monotonic() - started < 10.0

        assert main(["gcs", "control", "release", *target, "--system", "201"]) == 0
        assert "ok   release control: released" in capsys.readouterr().out
        printed = lines_until(proc, "released by GCS 201")   # the vehicle's control changes, as they happened
    assert printed[0].startswith("operator control on")
    assert printed[1:] == ["control: gcs_main 201 (was 0), takeover disallowed: granted to GCS 201",
                           "control: refused MISSION_COUNT: GCS 202 is not in control (gcs_main 201)",
                           "control: gcs_main 0 (was 201), takeover disallowed: released by GCS 201"]


@pytest.mark.parametrize("argv, message", [
    (["vehicle", "--owner-loss", "3"], "--owner-loss needs --operator-control"),
    (["vehicle", "--open-when-unowned"], "--open-when-unowned needs --operator-control"),
    (["gcs", "control", "request", "--target", "udp:127.0.0.1:9", "--timeout", "2"], "at least 3 seconds"),
    (["gcs", "control", "request", "--target", "udp:127.0.0.1:9", "--timeout", "61"], "at most 60 seconds"),
    (["gcs", "control", "grab", "--target", "udp:127.0.0.1:9"], "invalid choice"),
])
def test_control_usage_errors_exit_2(argv, message, capsys):
    """Refused before any socket is opened (argparse exits, a command returns)."""
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    assert message in capsys.readouterr().err
