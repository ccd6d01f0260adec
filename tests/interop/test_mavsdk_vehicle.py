"""tools/mavsdk_vehicle.py: MAVSDK's MissionRawServer as a vehicle process, so the script
behind `make run-mavsdk` cannot rot silently. Needs the optional `mavsdk` package
(`pip install -e '.[interop]'`, which `make run-mavsdk` does); skipped without it, except
the usage-error test, which exits before importing it."""

from __future__ import annotations

import contextlib
import re
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Iterator

import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "tools" / "mavsdk_vehicle.py"
LISTENING = re.compile(r"^listening on udp:127\.0\.0\.1:(\d+) ")
GCS = (245, 190)              # the suite's tester ids
EXIT_WAIT = 10.0              # s: the script exits within 5 s of SIGTERM by its own bound


@contextlib.contextmanager
def mavsdk_vehicle(*options: str) -> Iterator[tuple[subprocess.Popen, int]]:
    """Start the script; yield it and the port it printed; kill it afterwards. The first
    line is read without a timeout: the script exits after --duration at the latest."""
    proc = subprocess.Popen([sys.executable, str(SCRIPT), "--duration", "30", *options],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        found = LISTENING.match(line)
        assert found, line + proc.stderr.read()
        yield proc, int(found.group(1))
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=EXIT_WAIT)


def _exchange(port: int, timeout: float = 5.0) -> dict[str, object]:
    """As a GCS on its own 127.0.0.1 socket: HEARTBEAT and MISSION_REQUEST_LIST every 0.5 s
    until the vehicle's HEARTBEAT and MISSION_COUNT have both come; the first of each."""
    from pymavlink.dialects.v20 import common as mavlink2

    mav = mavlink2.MAVLink(None, srcSystem=GCS[0], srcComponent=GCS[1])
    mav.robust_parsing = True
    seen: dict[str, object] = {}
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        sock.settimeout(0.1)
        vehicle = ("127.0.0.1", port)
        deadline = time.monotonic() + timeout
        next_send = 0.0
        while time.monotonic() < deadline and not {"HEARTBEAT", "MISSION_COUNT"} <= set(seen):
            if time.monotonic() >= next_send:
                next_send = time.monotonic() + 0.5
                sock.sendto(mav.heartbeat_encode(mavlink2.MAV_TYPE_GCS, mavlink2.MAV_AUTOPILOT_INVALID,
                                                 0, 0, mavlink2.MAV_STATE_ACTIVE).pack(mav), vehicle)
                sock.sendto(mav.mission_request_list_encode(1, 1, mavlink2.MAV_MISSION_TYPE_MISSION)
                            .pack(mav), vehicle)
            try:
                data = sock.recv(4096)
            except socket.timeout:
                continue
            for msg in mav.parse_buffer(data) or []:
                if msg.get_type() in ("HEARTBEAT", "MISSION_COUNT") and (msg.get_srcSystem(), msg.get_srcComponent()) == (1, 1):
                    seen.setdefault(msg.get_type(), msg)
        if "MISSION_COUNT" in seen:   # end the download, as a GCS does
            sock.sendto(mav.mission_ack_encode(1, 1, mavlink2.MAV_MISSION_ACCEPTED,
                                               mavlink2.MAV_MISSION_TYPE_MISSION).pack(mav), vehicle)
    return seen


@pytest.mark.udp
def test_mavsdk_vehicle_answers_mission_request_list_and_stops_on_sigterm() -> None:
    pytest.importorskip("mavsdk", reason="the optional mavsdk package is not installed (pip install -e '.[interop]')")
    with mavsdk_vehicle() as (proc, port):
        seen = _exchange(port)
        assert "HEARTBEAT" in seen, f"no HEARTBEAT from system 1 component 1 on port {port}"
        heartbeat = seen["HEARTBEAT"]
        assert heartbeat.autopilot != 8 and heartbeat.type != 6   # not INVALID / GCS: the suite's vehicle test
        assert "MISSION_COUNT" in seen, f"MISSION_REQUEST_LIST got no MISSION_COUNT on port {port}"
        count = seen["MISSION_COUNT"]
        assert (count.count, count.mission_type, count.target_system, count.target_component) == (0, 0, *GCS)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=EXIT_WAIT) == 0


@pytest.mark.udp
def test_mavsdk_vehicle_exits_by_itself_after_its_duration() -> None:
    pytest.importorskip("mavsdk", reason="the optional mavsdk package is not installed (pip install -e '.[interop]')")
    started = time.monotonic()
    with mavsdk_vehicle("--duration", "0.5") as (proc, _):
        assert proc.wait(timeout=EXIT_WAIT) == 0
    assert time.monotonic() - started < EXIT_WAIT


@pytest.mark.parametrize("options, message", [
    (["--port", "70000"], "--port must be 0..65535"),
    (["--duration", "0"], "--duration must be > 0"),
    (["--sysid", "x"], "--sysid must be an integer"),
    (["--host", "0.0.0.0"], "unrecognized arguments: --host"),
])
def test_mavsdk_vehicle_usage_errors_are_one_line_and_exit_2(options, message) -> None:
    done = subprocess.run([sys.executable, str(SCRIPT), *options], capture_output=True, text=True,
                          timeout=EXIT_WAIT)
    assert done.returncode == 2
    assert done.stdout == ""
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("mavsdk_vehicle: error: ") and message in lines[0], done.stderr
