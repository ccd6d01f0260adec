#!/usr/bin/env python3
"""MAVSDK's MissionRaw client as the GCS under test, for `mavconform run --role gcs`.

    python tools/gcs_adapters/mavsdk_gcs.py PORT OP JOBFILE
    (--gcs-cmd 'python tools/gcs_adapters/mavsdk_gcs.py {gcs_port} {op} {file}')

Implements the GCS command contract (docs/gcs-conformance.md) with the `mavsdk` package from PyPI (its C++ core,
wrapped by ctypes; no mavsdk_server process): one operation per run, done by MAVSDK's
own MissionRaw calls, so every retry, timeout and ACK on the wire is MAVSDK's
`MavlinkMissionTransferClient`; the adapter never retries. OP x mission_type:

    upload       upload_mission / upload_geofence / upload_rally_points
    download     download_mission / download_geofence / download_rallypoints
    clear        MissionRaw.clear_mission (mission only); Geofence.clear_geofence (fence);
                 rally: MAVSDK has no call, so the result is "unsupported" (exit 1, nothing sent)
    set-current  MissionRaw.set_current_mission_item (MISSION_SET_CURRENT: the mission,
                 whatever the job's mission_type)

MAVSDK checks a few things before sending anything, and reports them as its result:
a mission upload needs exactly one item with current=1 (CURRENT_INVALID), an empty
upload is NO_MISSION_AVAILABLE, and set_current_mission_item refuses (INVALID_ARGUMENT)
a seq not below the size of a plan it uploaded or downloaded in the same session, which
a real application always has and a one-shot adapter never does. For set-current the
adapter therefore first hands MAVSDK that size without any traffic: it uploads seq+1
placeholder items numbered from 1, which MAVSDK rejects locally (INVALID_SEQUENCE)
before sending anything, having noted the plan size.

Connection: `udpin://127.0.0.1:PORT`: MAVSDK binds 127.0.0.1:PORT and the vehicle speaks
first, as an autopilot does to a ground station (`{gcs_port}`). (An udpout connection
would make MAVSDK speak first, but it binds its socket to 0.0.0.0, on every address, and
has no option to bind elsewhere.) The adapter waits for
the vehicle's HEARTBEAT (an autopilot), then runs the operation with MAVSDK's async call
and waits for its callback, all within the job's timeout_s minus a margin. MAVSDK's own
log goes to stderr. A usage mistake or bad job is one line on stderr and exit 2;
otherwise the result file is written and the exit is 0 (MAVSDK said SUCCESS) or 1.
SIGTERM/SIGINT end the run at once (exit 1, no result file).
"""

from __future__ import annotations

import json
import math
import os
import signal
import sys
import threading
import time

PROG = "mavsdk_gcs"
HOST = "127.0.0.1"
GCS_SYSID, GCS_COMPID = 245, 190   # MAVSDK's own GroundStation defaults (MAV_COMP_ID_MISSIONPLANNER)
OPS = ("upload", "download", "clear", "set-current")
TYPES = {"mission": 0, "fence": 1, "rally": 2}
ITEM_KEYS = ("seq", "frame", "command", "current", "autocontinue",
             "param1", "param2", "param3", "param4", "x", "y", "z")   # the job's order
ITEM_FLOATS = ("param1", "param2", "param3", "param4", "z")
ITEM_INTS = tuple(k for k in ITEM_KEYS if k not in ITEM_FLOATS)
HEARTBEAT_WAIT_MAX_S = 10.0
STOP_GRACE_S = 3.0


class UsageError(Exception):
    pass


def _say(text: str) -> None:
    sys.stderr.write(f"{PROG}: {text}\n")   # one write: MAVSDK's threads log too
    sys.stderr.flush()


def _item(raw, i: int) -> dict:
    if not isinstance(raw, dict):
        raise UsageError(f"items[{i}] is not an object")
    item = {}
    for key in ITEM_INTS:
        v = raw.get(key)
        if not isinstance(v, int) or isinstance(v, bool):
            raise UsageError(f"items[{i}].{key} must be an integer, not {v!r}")
        item[key] = v
    for key in ITEM_FLOATS:
        v = raw.get(key)
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            raise UsageError(f"items[{i}].{key} must be a number, not {v!r}")
        item[key] = float(v)
    return item


def read_job(argv: list[str]) -> tuple[int, dict]:
    if len(argv) != 3:
        raise UsageError("usage: mavsdk_gcs.py PORT OP JOBFILE")
    port_text, op, path = argv
    if not port_text.isdigit() or not 1 <= int(port_text) <= 65535:
        raise UsageError(f"PORT must be 1..65535, not {port_text!r}")
    if op not in OPS:
        raise UsageError(f"OP must be one of {', '.join(OPS)}, not {op!r}")
    try:
        with open(path, encoding="utf-8") as f:
            job = json.load(f)
    except (OSError, ValueError) as exc:
        raise UsageError(f"cannot read job {path}: {exc}") from None
    if not isinstance(job, dict) or job.get("format") != "mavconform-gcs-job/1":
        raise UsageError("job format is not mavconform-gcs-job/1")
    if job.get("op") != op:
        raise UsageError(f"job op {job.get('op')!r} is not OP {op!r}")
    if job.get("mission_type") not in TYPES:
        raise UsageError(f"job mission_type must be one of {', '.join(TYPES)}, not {job.get('mission_type')!r}")
    if not isinstance(job.get("result"), str) or not os.path.isabs(job["result"]):
        raise UsageError("job result must be an absolute path")
    t = job.get("timeout_s")
    if not isinstance(t, (int, float)) or isinstance(t, bool) or not math.isfinite(t) or t <= 0:
        raise UsageError(f"job timeout_s must be a positive number, not {t!r}")
    if op == "upload":
        if not isinstance(job.get("items"), list):
            raise UsageError("job items must be a list for upload")
        job["items"] = [_item(raw, i) for i, raw in enumerate(job["items"])]
    if op == "set-current":
        s = job.get("seq")
        if not isinstance(s, int) or isinstance(s, bool) or not 0 <= s <= 65535:
            raise UsageError(f"job seq must be 0..65535 for set-current, not {s!r}")
    return int(port_text), job


def write_result(job: dict, ok: bool, said: str, items: list | None = None, *, ended: bool = True) -> None:
    """ended=False: MAVSDK never ended the operation by itself; the adapter stopped waiting."""
    result = {"ok": ok, "said": said, "ended": ended}
    if items is not None:
        result["items"] = items
    tmp = job["result"] + ".tmp"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(result, f)
    os.replace(tmp, job["result"])


class Waiter:
    """One MAVSDK callback, waited for in the main thread in short slices (so SIGTERM gets through)."""

    def __init__(self, stop: threading.Event):
        self.stop, self.done, self.value = stop, threading.Event(), None

    def __call__(self, *args) -> None:   # called on MAVSDK's callback thread
        self.value = args
        self.done.set()

    def wait(self, deadline: float):
        while not self.stop.is_set() and time.monotonic() < deadline:
            if self.done.wait(0.1):
                return self.value
        return None


def run(port: int, job: dict, stop: threading.Event) -> int:
    from mavsdk import Configuration, Mavsdk, MavsdkError, log_subscribe
    from mavsdk.plugins.geofence import Geofence
    from mavsdk.plugins.mission_raw import MissionItem, MissionRaw, MissionRawResult

    op, kind = job["op"], job["mission_type"]
    mtype = TYPES[kind]
    started = time.monotonic()
    deadline = started + max(job["timeout_s"] - max(1.0, 0.1 * job["timeout_s"]), 0.5)

    def log(level, message, file, line) -> bool:   # MAVSDK logs to stdout by default: not ours
        _say(f"[mavsdk {level.name.lower()}] {message}")
        return True

    log_subscribe(log)
    instance = Mavsdk(Configuration.create_manual(GCS_SYSID, GCS_COMPID, True))
    try:
        try:
            instance.add_any_connection_with_handle(f"udpin://{HOST}:{port}")
        except MavsdkError as exc:
            write_result(job, False, f"udpin://{HOST}:{port}: {exc}")
            return 1
        found = Waiter(stop)
        heartbeat_s = min(HEARTBEAT_WAIT_MAX_S, deadline - time.monotonic())
        wait_handle = instance.first_autopilot_async(heartbeat_s, found)
        got = found.wait(deadline)
        instance.cancel_first_autopilot(wait_handle)
        if stop.is_set():
            return _terminated()
        if not got or got[0] is None:
            write_result(job, False, f"no vehicle HEARTBEAT on udp:{HOST}:{port} within {heartbeat_s:.1f} s")
            return 1
        raw = MissionRaw(got[0])

        def plan(items):
            return [MissionItem(mission_type=mtype, **it) for it in items]

        call = Waiter(stop)
        if op == "upload":
            name = {"mission": "upload_mission", "fence": "upload_geofence",
                    "rally": "upload_rally_points"}[kind]
            getattr(raw, name + "_async")(plan(job["items"]), call)
        elif op == "download":
            name = {"mission": "download_mission", "fence": "download_geofence",
                    "rally": "download_rallypoints"}[kind]
            getattr(raw, name + "_async")(call)
        elif op == "clear" and kind == "mission":
            name = "clear_mission"
            raw.clear_mission_async(call)
        elif op == "clear" and kind == "fence":
            name = "Geofence.clear_geofence"
            fence = Geofence(got[0])   # held until the callback: a collected plugin frees the callback
            fence.clear_geofence_async(call)
        elif op == "clear":
            write_result(job, False, "unsupported: MAVSDK has no call to clear rally points "
                         "(MissionRaw.clear_mission clears the mission only)")
            return 1
        else:
            name = "set_current_mission_item"
            prime = Waiter(stop)   # tell MAVSDK the plan size; rejected locally, nothing sent
            placeholder = [{k: 0 for k in ITEM_KEYS} for _ in range(job["seq"] + 1)]
            placeholder[0]["seq"] = 1
            raw.upload_mission_async([MissionItem(**it) for it in placeholder], prime)
            primed = prime.wait(deadline)
            if primed is None:
                return _terminated() if stop.is_set() else _gave_up(job, "placeholder upload")
            if primed[0] != MissionRawResult.INVALID_SEQUENCE:
                write_result(job, False, f"placeholder upload: {primed[0].name} (expected INVALID_SEQUENCE)")
                return 1
            raw.set_current_mission_item_async(job["seq"], call)

        answer = call.wait(deadline)
        if answer is None:
            return _terminated() if stop.is_set() else _gave_up(job, name)
        result = answer[0]
        ok = result == MissionRawResult.SUCCESS
        said = f"{name}: {result.name}"
        if op == "download":
            items = [{k: getattr(it, k) for k in ITEM_KEYS} for it in answer[1]]
            said += f", {len(items)} items"
            write_result(job, ok, said, items)
        else:
            write_result(job, ok, said)
        _say(f"{said} after {time.monotonic() - started:.2f} s")
        return 0 if ok else 1
    finally:
        # bounded teardown: MAVSDK's destroy joins its threads; never hang the caller on it
        timer = threading.Timer(STOP_GRACE_S, _exit_now)
        timer.daemon = True
        timer.start()
        instance.destroy()


def _gave_up(job: dict, name: str) -> int:
    write_result(job, False, f"{name}: no result from MAVSDK within the job's timeout_s ({job['timeout_s']:g} s)",
                 ended=False)
    return 1


def _terminated() -> int:
    _say("terminated")
    return 1


def _exit_now() -> None:
    _say(f"MAVSDK did not stop within {STOP_GRACE_S:g} s; exiting anyway")
    os._exit(1)


def main(argv: list[str] | None = None) -> int:
    stop = threading.Event()

    def on_signal(signum, _frame) -> None:
        stop.set()

    try:
        port, job = read_job(sys.argv[1:] if argv is None else argv)
        signal.signal(signal.SIGTERM, on_signal)
        signal.signal(signal.SIGINT, on_signal)
        try:
            import mavsdk  # noqa: F401
        except ImportError as exc:
            raise UsageError(f"the mavsdk package is not installed ({exc}); pip install mavsdk") from None
    except UsageError as exc:
        _say(f"error: {exc}")
        return 2
    try:
        return run(port, job, stop)
    except OSError as exc:   # the result file could not be written
        _say(f"error: {exc}")
        return 1


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)   # MAVSDK's teardown already ran in run(); skip the interpreter's
