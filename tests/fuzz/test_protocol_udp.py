"""The protocol fuzzer against a target it reaches over real UDP (127.0.0.1, OS ports).

The vehicle is an in-process reference vehicle served on its own loopback socket by a
second driver in a background thread, so the fuzzer sees it as any remote target: found
by its HEARTBEAT, judged from the wire only (downloads, MISSION_REQUEST_LIST answered).
"""

from __future__ import annotations

import socket
import threading
import time
from contextlib import contextmanager
from typing import Iterator

import pytest

from mavconform.conformance.mutants import MUTANTS
from mavconform.fuzz.case import Case
from mavconform.fuzz.protocol import Knobs, replay, search
from mavconform.fuzz.outcomes import TargetUnresponsive
from mavconform.fuzz.protocol import connection as connection_mod
from mavconform.reference_impl.net import UdpDriver
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

pytestmark = pytest.mark.udp

WAYPOINT = {"frame": 3, "command": 16, "current": 0, "autocontinue": 1, "param1": 0.0,
            "param2": 0.0, "param3": 0.0, "param4": 0.0, "x": 473977420, "y": 85455940, "z": 50.0}


@contextmanager
def served(vehicle: VehicleNode) -> Iterator[str]:
    """`udp:127.0.0.1:PORT` of `vehicle`, served until the block ends (bounded join)."""
    driver = UdpDriver()
    host, port = driver.add_node(vehicle)
    stop = threading.Event()

    def serve() -> None:
        while not stop.is_set():
            driver.run_until(stop.is_set, timeout=0.05)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"udp:{host}:{port}"
    finally:
        stop.set()
        thread.join(timeout=5)
        driver.close()


def test_a_few_examples_against_a_vehicle_on_a_loopback_socket():
    units: list[int] = []
    knobs = Knobs(max_items=4, steps=4, faults=False, max_wait=0.2)
    with served(VehicleNode(VehicleConfig())) as target:
        assert search(target, seed=2, max_examples=3, on_example=units.append, knobs=knobs) == []
    assert len(units) == 3 and sum(units) > 0


def test_over_the_wire_a_download_shows_a_plan_the_vehicle_should_not_hold():
    """count-zero-keeps-plan ACKs an empty upload but keeps the old plan: only a download
    can see it from outside, and the oracle judges that download. Faults apply over UDP too."""
    steps = ({"op": "faults", "up": {"duplicate": 0.2}, "down": {"duplicate": 0.2}},
             {"op": "upload", "type": 0, "items": [WAYPOINT, dict(WAYPOINT, x=1)]},
             {"op": "upload", "type": 0, "items": []},
             {"op": "download", "type": 0})
    with served(VehicleNode(VehicleConfig())) as target:
        assert replay(Case("protocol", target, 0, steps)) is None
    with served(MUTANTS["count-zero-keeps-plan"].build(VehicleConfig())) as target:
        v = replay(Case("protocol", target, 0, steps))
    # the probe after the empty upload hears a count of 2 (step 2), or the download shows it
    assert v is not None and v.invariant == "download-matches-upload" and v.step in (2, 3)


def test_a_silent_target_is_unresponsive_within_the_bound(monkeypatch):
    """Nothing was sent that could have broken it: not a finding, `TargetUnresponsive`."""
    monkeypatch.setattr(connection_mod, "DISCOVERY_TIMEOUT", 0.5)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as silent:
        silent.bind(("127.0.0.1", 0))
        port = silent.getsockname()[1]
        start = time.monotonic()
        with pytest.raises(TargetUnresponsive, match="no HEARTBEAT"):
            replay(Case("protocol", f"udp:127.0.0.1:{port}", 0, ({"op": "download", "type": 0},)))
        with pytest.raises(TargetUnresponsive, match="no HEARTBEAT"):
            search(f"udp:127.0.0.1:{port}", seed=0, max_examples=1)
        assert time.monotonic() - start < 5
