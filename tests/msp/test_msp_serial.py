"""MSP over a serial line: builtin:msp served on a pseudo-terminal (paced at its baud rate) in
another process, judged by the MSP clauses as `msp:serial:/dev/pts/N`, and bridged to MAVLink
by `mavconform bridge --msp serial:...`."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from mavconform.cli import main

pytestmark = pytest.mark.udp
SERVE = """
import sys
from mavconform.reference_impl.msp.nodes import MspServerNode
from mavconform.reference_impl.net.serial_link import PtyLink
from mavconform.reference_impl.net.stream_framer import PassThrough
from mavconform.reference_impl.net.udp import UdpDriver
with UdpDriver() as driver:
    link = PtyLink(int(sys.argv[1]), driver.clock.now())
    driver.add_stream(MspServerNode(), link, framer=PassThrough())
    print(link.device, flush=True)
    driver.run_for(float(sys.argv[2]))
"""


@pytest.fixture
def pty_fc():
    """builtin:msp on a new pseudo-terminal at 115200 baud, for 90 s at most; its device."""
    proc = subprocess.Popen([sys.executable, "-c", SERVE, "115200", "90"], stdout=subprocess.PIPE, text=True)
    try:
        yield proc.stdout.readline().strip()
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_the_msp_clauses_over_a_serial_line(pty_fc, tmp_path, capsys) -> None:
    assert pty_fc.startswith("/dev/")
    code = main(["run", "-q", "--target", f"msp:serial:{pty_fc}", "--clauses", "MSP.WP.0[1-3],MSP.FR.*",
                 "--report-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0, out
    doc = json.loads((tmp_path / "run.json").read_text())
    assert doc["run"]["link"]["kind"] == "serial" and doc["run"]["link"]["bytes_per_second"] == 11520
    assert all(c["outcome"] == "pass" for c in doc["clauses"])


def test_the_bridge_over_a_serial_line(pty_fc, tmp_path) -> None:
    bridge = subprocess.Popen([sys.executable, "-m", "mavconform", "bridge", "--msp", f"serial:{pty_fc}",
                               "--listen", "udpin:0", "--duration", "60"], stdout=subprocess.PIPE, text=True)
    try:
        line = bridge.stdout.readline()
        assert f"flight controller serial:{pty_fc}:115200" in line, line
        port = line.split("udp:127.0.0.1:")[1].split(";")[0]
        run = subprocess.run([sys.executable, "-m", "mavconform", "run", "--target", f"udp:127.0.0.1:{port}",
                              "--clauses", "MIS.UP.01,MIS.DN.01,MIS.CLR.01", "--report-dir", str(tmp_path), "-q"],
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)
