"""Issue 24: links from the command line. Bad input is one line and exit 2, with nothing
sent; the suite over TCP and over a pseudo-terminal decides as it does over UDP; a target
that hangs up mid-run is reported, and the run still ends and restores."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from mavconform.cli import main

pytestmark = pytest.mark.udp


def _usage(argv: list[str], capsys) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("mavconform: error: "), (code, err)
    return err


@pytest.mark.parametrize("argv, says", [
    (["run", "--target", "serial:/dev/no-such-tty"], "cannot open serial port /dev/no-such-tty"),
    (["run", "--target", "serial:/dev/null:fast"], "bad baud rate 'fast': not a number"),
    (["run", "--target", "smoke:1"], "unknown scheme 'smoke'"),
    (["gcs", "download", "--target", "serial:/dev/no-such-tty", "x.plan"], "cannot open serial port"),
    (["vehicle", "--listen", "serial:/dev/no-such-tty", "--duration", "1"], "cannot open serial port"),
    (["vehicle", "--listen", "tcp:127.0.0.1:5760"], "here we listen: give tcpin"),
    (["vehicle", "--listen", "tcpin:0", "--connect", "udp:127.0.0.1:9"], "--connect adds a UDP peer"),
    (["proxy", "--listen", "udpin:0", "--forward", "tcpin:5760"], "--forward: bad endpoint"),
])
def test_a_bad_link_is_one_line_and_exit_2(argv, says, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert says in _usage(argv, capsys)
    assert list(tmp_path.iterdir()) == []   # nothing written, no report folder


def test_a_port_in_use_is_one_line_and_exit_2(capsys):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        err = _usage(["vehicle", "--listen", f"tcpin:{port}", "--duration", "1"], capsys)
    assert f"cannot listen on TCP 127.0.0.1:{port}" in err


def _vehicle(listen: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen([sys.executable, "-m", "mavconform", "vehicle", "--listen", listen,
                             "--duration", "120", "--quiet"], stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    assert "listening on " in line, line
    return proc, line.split("listening on ")[1].split()[0]


def _run(target: str, out: Path, clauses: str) -> dict:
    done = subprocess.run([sys.executable, "-m", "mavconform", "run", "--target", target, "--clauses", clauses,
                           "--report-dir", str(out), "-q"], capture_output=True, text=True, timeout=300)
    assert done.returncode in (0, 1), done.stdout + done.stderr
    return json.loads((out / "run.json").read_text())


CLAUSES = "MIS.UP.0[1-4],MIS.DN.*,MIS.CLR.*"


def test_the_suite_over_tcp_and_a_pty_decides_as_over_udp(tmp_path):
    outcomes = {}
    for kind, listen, target in (("udp", "udp:127.0.0.1:0", None), ("tcp", "tcpin:0", None),
                                 ("pty", "pty:57600", None)):
        proc, where = _vehicle(listen)
        try:
            target = {"udp": where, "tcp": where.replace("tcpin:", "tcp:"), "pty": where}[kind]
            doc = _run(target, tmp_path / kind, CLAUSES)
        finally:
            proc.kill()
            proc.wait(timeout=10)
        outcomes[kind] = {c["id"]: c["outcome"] for c in doc["clauses"]}
        link = doc["run"]["link"]
        assert link["kind"] == {"udp": "udp", "tcp": "tcp", "pty": "serial"}[kind]
        if kind == "pty":
            assert link["bytes_per_second"] == 5760.0 and link["reply_allowance_s"] > 0
            assert "serial at 5760 bytes/s" in (tmp_path / kind / "run.md").read_text()
        else:
            assert link["bytes_per_second"] is None and link["reply_allowance_s"] == 0
    assert outcomes["udp"] == outcomes["tcp"] == outcomes["pty"]
    assert "pass" in outcomes["udp"].values()


def test_a_target_that_hangs_up_mid_run_is_reported_and_the_run_ends(tmp_path):
    proc, where = _vehicle("tcpin:0")
    port = where.rsplit(":", 1)[1]
    run = subprocess.Popen([sys.executable, "-m", "mavconform", "run", "--target", f"tcp:127.0.0.1:{port}",
                            "--clauses", CLAUSES, "--report-dir", str(tmp_path / "r")],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    second = None
    try:
        decided = 0
        for line in run.stdout:   # the run prints a line per clause; it ends within its bounds
            if line.lstrip().startswith(("PASS", "FAIL", "N/A", "ERROR", "SKIP", "KNOWN")):
                decided += 1
                if decided == 3 and second is None:   # the vehicle goes away, another comes back
                    proc.kill()
                    proc.wait(timeout=10)
                    second, _ = _vehicle(f"tcpin:127.0.0.1:{port}")
        assert run.wait(timeout=300) in (0, 1)
    finally:
        for p in (proc, second, run):
            if p is not None and p.poll() is None:
                p.kill()
                p.wait(timeout=10)
    doc = json.loads((tmp_path / "r" / "run.json").read_text())
    link = doc["volatile"]["link"]
    events = [e["event"] for e in link["history"]]
    assert any(e.startswith(("closed by the peer", "read failed")) for e in events), events
    assert link["connections"] >= 2 and events[-1] == "connected", events
    assert "lost" in (tmp_path / "r" / "run.md").read_text()
    assert doc["restore"]["status"] in ("restored", "unchanged", "failed", "skipped")
    assert doc["restore"]["detail"]
