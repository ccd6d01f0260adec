#!/usr/bin/env python3
"""A real ground station (MAVSDK or MAVProxy, from PyPI) uploads, downloads and clears a mission
through `mavconform bridge` to an MSP flight controller, and what it downloads must be what it
uploaded.

    python tools/gcs_through_bridge.py --gcs mavsdk [--msp builtin|tcp:HOST:PORT|serial:DEV] [--out DIR]
    python tools/gcs_through_bridge.py --gcs mavproxy      # MAVProxy from .venv-mavproxy (`make run-msp-bridge-clients` makes it)

The GCS is driven by its adapter (tools/gcs_adapters/, the GCS command contract of
docs/gcs-conformance.md), one operation per process, listening on a free UDP port on 127.0.0.1
that the bridge speaks to first (`bridge --connect`). Operations: upload a 5-item mission,
download it, clear, download again (empty; not asked of MAVProxy, which never ends a download
of 0 items, MP7 of expectations/mavproxy-gcs.toml; its plan's coordinates are ones MAVProxy's
truncation keeps, MP1). Prints one line per operation and a verdict; exit 0
if every operation succeeded and the first download equals the upload (each item as the
mapping stores it: docs/msp-mapping.md), 1 otherwise, 2 for a usage mistake. Every wait is
bounded (each operation 60 s, the bridge's start 10 s).
"""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

from mavconform.conformance.gcs.job import Job, read_result, write_job
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType

ROOT = Path(__file__).resolve().parents[1]

# What the GCSs are known to do otherwise (conformance/expectations/mavproxy-gcs.toml), allowed for here:
# MP1: MAVProxy truncates coordinates (int(deg * 1e7)), so the plan's are ones that truncation keeps;
# MP7: MAVProxy never finishes a download of 0 items, so the download after the clear is not asked of it.
KEEPS_TRUNCATION = {"mavproxy"}
NO_EMPTY_DOWNLOAD = {"mavproxy"}
ADAPTERS = {
    "mavsdk": [sys.executable, str(ROOT / "tools" / "gcs_adapters" / "mavsdk_gcs.py")],
    "mavproxy": [str(ROOT / ".venv-mavproxy" / "bin" / "python"), str(ROOT / "tools" / "gcs_adapters" / "mavproxy_gcs.py")],
}
OP_TIMEOUT = 60.0
START_WITHIN = 60.0   # s for the bridge to say it listens: CI starts it beside other jobs on 2 cores
MISSION = MissionType.MISSION
PLAN = (
    MissionItem(0, 3, Cmd.NAV_WAYPOINT, 0, 0, 0, 0, 473977420, 85455940, 20.0, 1, 1),
    MissionItem(1, 3, Cmd.NAV_WAYPOINT, 0, 0, 0, 0, 473980420, 85460940, 25.5, 0, 1),
    MissionItem(2, 3, Cmd.NAV_LOITER_TIME, 10, 0, 0, 0, 473983420, 85465940, 30.0, 0, 1),
    MissionItem(3, 0, Cmd.NAV_WAYPOINT, 0, 0, 0, 0, 473986420, 85470940, 520.25, 0, 1),
    MissionItem(4, 2, Cmd.NAV_RETURN_TO_LAUNCH, 0, 0, 0, 0, 0, 0, 0.0, 0, 1),
)


def _survives_truncation(v: int) -> int:
    """The nearest integer at or above `v` that int(float(decimal) * 1e7) gives back (MP1)."""
    for candidate in range(v, v + 100):
        if int(float(f"{candidate / 1e7:.7f}") * 1.0e7) == candidate:
            return candidate
    raise ValueError(v)


def plan_for(gcs: str) -> tuple[MissionItem, ...]:
    if gcs not in KEEPS_TRUNCATION:
        return PLAN
    return tuple(replace(it, x=_survives_truncation(it.x), y=_survives_truncation(it.y)) if it.x else it for it in PLAN)


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _key(item: MissionItem) -> tuple:
    return (item.seq, item.frame, int(item.command), item.param1, item.param2, item.param3, item.x, item.y,
            round(item.z, 2))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--gcs", choices=sorted(ADAPTERS), required=True)
    p.add_argument("--msp", default="builtin", help="the flight controller, as `mavconform bridge --msp` takes it")
    p.add_argument("--out", type=Path, help="keep job, result and bridge files here (default: a temporary folder)")
    args = p.parse_args(argv)
    adapter = ADAPTERS[args.gcs]
    if not Path(adapter[0]).exists():
        print(f"gcs_through_bridge: {adapter[0]} is missing (`make run-msp-bridge-clients` installs MAVProxy there)", file=sys.stderr)
        return 2
    out = (args.out or Path(tempfile.mkdtemp(prefix="gcs-bridge-"))).resolve()   # the adapters take absolute paths
    out.mkdir(parents=True, exist_ok=True)
    port = _free_udp_port()
    log = open(out / "bridge.out", "w")
    bridge = subprocess.Popen([sys.executable, "-m", "mavconform", "bridge", "--msp", args.msp, "--listen", "udpin:0",
                               "--connect", f"udp:127.0.0.1:{port}", "--duration", "600"],
                              stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + START_WITHIN
        while "listening on" not in (out / "bridge.out").read_text() and time.monotonic() < deadline:
            if bridge.poll() is not None:
                break
            time.sleep(0.1)
        if "listening on" not in (out / "bridge.out").read_text():
            print(f"gcs_through_bridge: the bridge did not start:\n{(out / 'bridge.out').read_text()}", file=sys.stderr)
            return 1
        return _operations(adapter, port, out, args)
    finally:
        bridge.terminate()
        try:
            bridge.wait(timeout=10)
        except subprocess.TimeoutExpired:
            bridge.kill()
        log.close()


def _operations(adapter: list[str], port: int, out: Path, args: argparse.Namespace) -> int:
    plan = plan_for(args.gcs)
    ops = [("upload", plan), ("download", ()), ("clear", ())]
    if args.gcs not in NO_EMPTY_DOWNLOAD:
        ops.append(("download", ()))
    ok, downloads = True, []
    for n, (op, items) in enumerate(ops):
        job, result = out / f"{n}-{op}.json", out / f"{n}-{op}.result.json"
        write_job(Job(op, MISSION, tuple(items), timeout_s=OP_TIMEOUT), job, result)
        started = time.monotonic()
        try:
            proc = subprocess.run([*adapter, str(port), op, str(job)], capture_output=True, text=True,
                                  timeout=OP_TIMEOUT + 10)
            got = read_result(result, MISSION) if result.exists() else None
        except subprocess.TimeoutExpired:
            proc, got = None, None
        took = time.monotonic() - started
        fine = got is not None and got.ok
        said = got.said if got is not None else (proc.stderr.strip().splitlines()[-1:] if proc else ["timed out"])
        print(f"{args.gcs} {op:<8} {'ok ' if fine else 'FAILED'} {took:5.1f} s  {said}", flush=True)
        ok &= fine
        if op == "download" and got is not None:
            downloads.append(got.items or ())
    same = bool(downloads) and [_key(i) for i in downloads[0]] == [_key(i) for i in plan]
    if downloads:
        print(f"first download: {len(downloads[0])} items, {'equal to' if same else 'NOT equal to'} the "
              f"{len(plan)} uploaded" + (f"; after the clear: {len(downloads[1])} items" if len(downloads) > 1 else
                                         "; no download after the clear (MAVProxy never ends one of 0 items: MP7)"))
        for a, b in zip(plan, downloads[0]):
            if _key(a) != _key(b):
                print(f"  seq {a.seq}: uploaded {_key(a)}, downloaded {_key(b)}")
    same &= len(downloads) < 2 or downloads[1] == ()
    verdict = ok and same
    print(f"verdict: {'PASS' if verdict else 'FAIL'} ({args.gcs} through mavconform bridge to {args.msp}; files in {out})")
    return 0 if verdict else 1


if __name__ == "__main__":
    sys.exit(main())
