"""Benchmark: the main job's wall time, beside the waits its clauses force.

Three runs, all against the spec reference vehicle:
1. virtual time (SimNetwork): the suite's own cost, no real waiting at all;
2. builtin:spec, as `make run` runs it: the vehicle in this process over real UDP loopback,
   the vehicle and the suite sharing a clock BUILTIN_CLOCK_SPEED times real time (goal:
   <= 30 s wall);
3. udp:127.0.0.1:PORT: the vehicle in a separate process (`mavconform vehicle`), which lives
   in real time as every external target does.
For the real-socket runs it prints the sum of waits the clauses force (windows the tester
must watch in full: a silent upload's retries, "no more requests" silences; and waits whose
length the target sets: the next message of its 1 Hz MISSION_CURRENT or HEARTBEAT stream,
its item timeout), in the run clock's seconds and in real ones, and the ratio
(wall - discovery) / real forced. Discovery is the wait for the target's first HEARTBEAT,
whose 1 Hz period the target sets (an in-process vehicle is told where we are, so it costs
nothing there). Goal: <= 1.25, i.e. no slack sleeping; every other wait ends on the event
it waits for.

    python bench/conformance_wall.py [--clauses GLOB] [--clock-speed X]
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.conformance import catalogue  # noqa: E402
from mavconform.conformance.outcome import Outcome  # noqa: E402
from mavconform.conformance.runner import run_clauses  # noqa: E402
from mavconform.conformance.session import BUILTIN_CLOCK_SPEED, Session  # noqa: E402
from mavconform.conformance.target_uri import parse_target  # noqa: E402


def measure(uri: str, clauses, *, virtual: bool = False, clock_speed: float | None = None
            ) -> tuple[float, float, float, float, int]:
    start = time.perf_counter()
    with Session(parse_target(uri), virtual=virtual, clock_speed=clock_speed) as session:
        run = run_clauses(session, clauses)
        speed = session.clock_speed
    wall = time.perf_counter() - start
    passed = sum(r.outcome is Outcome.PASS for r in run.results)
    return wall, run.forced_wait_s, run.discovery_s, speed, passed


def vehicle_process() -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-m", "mavconform", "vehicle", "--listen", "udp:127.0.0.1:0",
                             "--quiet"], stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()
    found = re.search(r"udp:[0-9.]+:(\d+)", line)
    if not found:
        proc.kill()
        raise SystemExit(f"vehicle did not say where it listens: {line!r}")
    return proc, int(found.group(1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--clauses", default="*")
    ap.add_argument("--clock-speed", type=float, default=None,
                    help=f"the in-process run's clock (default {BUILTIN_CLOCK_SPEED:g}, as `make run`)")
    args = ap.parse_args()
    clauses = catalogue.select(args.clauses)
    print(f"{len(clauses)} clauses")
    wall, _, _, _, ok = measure("builtin:spec", clauses, virtual=True)
    print(f"virtual time (SimNetwork):    wall {wall:6.2f} s   passed {ok}/{len(clauses)}")
    for label, uri, proc in (("builtin:spec (in-process UDP)", "builtin:spec", None),
                             ("udp: (separate process)", None, "spawn")):
        if proc == "spawn":
            proc, port = vehicle_process()
            uri = f"udp:127.0.0.1:{port}"
        try:
            wall, forced, discovery, speed, ok = measure(
                uri, clauses, clock_speed=args.clock_speed if proc is None else None)
        finally:
            if proc is not None:
                proc.terminate()
                proc.wait(timeout=5)
        real_forced = forced / speed
        ratio = (wall - discovery) / real_forced if real_forced else float("inf")
        print(f"{label:<30} wall {wall:6.2f} s (of which {discovery:4.2f} s waiting for the first "
              f"HEARTBEAT)   clock {speed:g}x: forced waits {forced:6.2f} clock s = {real_forced:6.2f} s   "
              f"ratio {ratio:5.2f}   passed {ok}/{len(clauses)}")


if __name__ == "__main__":
    main()
