#!/usr/bin/env python3
"""MAVProxy as the GCS under test: one mission operation per run, for `mavconform run --role gcs`.

    .venv-mavproxy/bin/python tools/gcs_adapters/mavproxy_gcs.py PORT OP JOBFILE
    (--gcs-cmd '.venv-mavproxy/bin/python tools/gcs_adapters/mavproxy_gcs.py {gcs_port} {op} {file}')

Implements the GCS command contract (docs/gcs-conformance.md), in MAVProxy's own venv (it
needs no mavconform). Runs the installed `mavproxy.py` as a child process
(`--master=udpin:127.0.0.1:PORT`: MAVProxy binds 127.0.0.1:PORT and the vehicle speaks first,
as an autopilot does to a ground station; an udpout master would leave pymavlink's socket
unbound, which the OS binds on every address) and types
MAVProxy's own commands on its stdin, as a user at its prompt would; MAVProxy's wp / fence /
rally modules (MissionItemProtocolModule) do all the protocol work. This script only:
  - writes the job's items as a "QGC WPL 110" file for `<wp|fence|rally> load FILE` (MAVProxy's
    fence and rally loaders read that format too). Coordinates of commands that MAVProxy
    treats as having a location are written as the exact decimal x/1e7; MAVProxy converts them
    back to int itself (that conversion is under test). Other fields at full float precision.
  - decides ok/said from MAVProxy's own printed lines. MAVProxy's modules never look at a
    MISSION_ACK; its link module prints every one ("Got MISSION_ACK: TYPE_MISSION: ACCEPTED"),
    and that line of the job's type is the result of upload and clear. set-current (`wp set N`,
    missions only) ends with its printed "Got COMMAND_ACK: DO_SET_MISSION_CURRENT: ..." or
    "waypoint N". A download (`<cmd> list`) is done when MAVProxy prints the items; MAVProxy
    prints x/y with 10 decimals (read back as round(v*1e7), exact), the rest comes from
    `<cmd> savelocal FILE` (local, no traffic; %f, 6 decimals) followed by `<cmd> status`.
  - gives up at a deadline well inside timeout_s (MAVProxy has no timeout of its own on
    several paths and then prints nothing): exit 1, said = MAVProxy's last line.

Quiet start: --no-state (no logs), --streamrate=-1 (no REQUEST_DATA_STREAM), only the one
module the job needs in --default-modules (so no param fetch, no other plan types), HOME set to
a temp dir (no ~/.mavinit.scr). MAVProxy fetches no plan on connect anyway. What cannot be
turned off: its HEARTBEAT, and with the wp module MAV_CMD_GET_HOME_POSITION every 2 s until
HOME_POSITION arrives. A bad job is one line on stderr and exit 2; SIGTERM kills MAVProxy.
"""

from __future__ import annotations

import json
import math
import os
import queue
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from decimal import Decimal

PROG = "mavproxy_gcs"
MAVPROXY = os.path.join(os.path.dirname(os.path.abspath(sys.executable)), "mavproxy.py")
COMMANDS = {"mission": "wp", "fence": "fence", "rally": "rally"}
ACK_TYPES = {"mission": "TYPE_MISSION", "fence": "TYPE_FENCE", "rally": "TYPE_RALLY"}
OPS = ("upload", "download", "clear", "set-current")
ITEM_KEYS = ("seq", "frame", "command", "current", "autocontinue",
             "param1", "param2", "param3", "param4", "x", "y", "z")
PROMPT = re.compile(r"^(?:\S+> )+")   # "MANUAL> ", "Mode(0x00000000)> " (a generic autopilot's)
LISTED = re.compile(r"^(\d+) (\d+) (\S+) (\S+) (\S+) p1=\S+ p2=\S+ p3=\S+ p4=\S+ cur=\d+ auto=\d+$")
ACK = re.compile(r"^Got MISSION_ACK: (\S+): (\S+)$")
CMD_ACK = re.compile(r"^Got COMMAND_ACK: DO_SET_MISSION_CURRENT: (\S+)$")
STARTED = "online system"


class BadJob(Exception):
    pass


class Terminated(Exception):
    pass


def read_job(path: str, op: str) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            job = json.load(f)
    except (OSError, ValueError) as exc:
        raise BadJob(f"cannot read job {path}: {exc}") from None
    if not isinstance(job, dict) or job.get("format") != "mavconform-gcs-job/1":
        raise BadJob("job format is not mavconform-gcs-job/1")
    if op not in OPS or job.get("op") != op:
        raise BadJob(f"op {op!r} is not one of {OPS} or differs from the job's {job.get('op')!r}")
    if job.get("mission_type") not in COMMANDS:
        raise BadJob(f"mission_type {job.get('mission_type')!r} is not mission, fence or rally")
    if not isinstance(job.get("result"), str) or not job["result"]:
        raise BadJob("job has no result path")
    t = job.get("timeout_s")
    if isinstance(t, bool) or not isinstance(t, (int, float)) or not 0 < t < 86400:
        raise BadJob(f"timeout_s must be a positive number, not {t!r}")
    if op == "upload":
        items = job.get("items")
        if not isinstance(items, list) or not all(
                isinstance(i, dict) and all(k in i for k in ITEM_KEYS) for i in items):
            raise BadJob(f"upload needs items, each with {', '.join(ITEM_KEYS)}")
    if op == "set-current":
        if job["mission_type"] != "mission":
            raise BadJob("MAVProxy sets the current item of missions only (wp set N)")
        if isinstance(job.get("seq"), bool) or not isinstance(job.get("seq"), int) or job["seq"] < 0:
            raise BadJob(f"set-current needs seq >= 0, not {job.get('seq')!r}")
    return job


def has_location(command: int) -> bool:
    """MissionItemProtocolModule.has_location: scale x/y by 1e7 or not."""
    from pymavlink import mavutil
    enum = mavutil.mavlink.enums["MAV_CMD"]
    return command in enum and getattr(enum[command], "has_location", True)


def write_wpl(path: str, items: list) -> None:
    lines = ["QGC WPL 110"]
    for n, it in enumerate(items):
        loc = has_location(int(it["command"]))
        xy = [format(Decimal(int(it[k])).scaleb(-7), "f") if loc else str(int(it[k])) for k in "xy"]
        lines.append("\t".join([str(n), str(int(it["current"])), str(int(it["frame"])),
                                str(int(it["command"]))]
                               + [repr(float(it[f"param{i}"])) for i in range(1, 5)]
                               + xy + [repr(float(it["z"])), str(int(it["autocontinue"]))]))
    with open(path, "w", encoding="ascii") as f:
        f.write("\n".join(lines) + "\n")


def read_download(path: str, listed: list) -> list:
    with open(path, encoding="ascii") as f:
        rows = [ln.split("\t") for ln in f.read().splitlines()[1:] if ln.strip() and not ln.startswith("#")]
    items = []
    for n, r in enumerate(rows):
        cmd = int(r[3])
        xs, ys = (listed[n][2], listed[n][3]) if len(listed) == len(rows) else (r[8], r[9])
        scale = 1e7 if has_location(cmd) else 1.0
        xy = [round(float(v) * scale) if math.isfinite(float(v)) else 0 for v in (xs, ys)]
        items.append({"seq": int(r[0]), "frame": int(r[2]), "command": cmd, "current": int(r[1]),
                      "autocontinue": int(r[11]), "param1": float(r[4]), "param2": float(r[5]),
                      "param3": float(r[6]), "param4": float(r[7]), "x": xy[0], "y": xy[1],
                      "z": float(r[10])})
    return items


class MAVProxy:
    def __init__(self, port: int, module: str, home: str):
        script = MAVPROXY if os.path.exists(MAVPROXY) else shutil.which("mavproxy.py")
        if script is None:
            raise OSError("mavproxy.py is neither next to this python nor on PATH")
        argv = [sys.executable, "-u", script, f"--master=udpin:127.0.0.1:{port}", "--no-state",
                "--streamrate=-1", f"--default-modules={module}"]
        env = dict(os.environ, HOME=home, PYTHONUNBUFFERED="1")
        env.pop("DISPLAY", None)
        self.proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, env=env, cwd=home,
                                     start_new_session=True, text=True, bufsize=1)
        self.lines: queue.Queue = queue.Queue()
        self.last = "MAVProxy printed nothing"
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        for raw in self.proc.stdout:
            line = PROMPT.sub("", raw.strip()).strip()
            if line:
                self.lines.put(line)
        self.lines.put(None)

    def send(self, command: str) -> None:
        self.proc.stdin.write(command + "\n")
        self.proc.stdin.flush()

    def next_line(self, deadline: float) -> str | None:
        """MAVProxy's next printed line; None at the deadline. Raises EOFError if it exited."""
        try:
            line = self.lines.get(timeout=max(0.0, deadline - time.monotonic()))
        except queue.Empty:
            return None
        if line is None:
            self.lines.put(None)
            raise EOFError(f"MAVProxy exited (rc {self.proc.poll()}); it last said: {self.last}")
        self.last = line
        return line

    def wait_for(self, test, deadline: float):
        """First line for which test(line) is not None; None at the deadline."""
        while (line := self.next_line(deadline)) is not None:
            if (verdict := test(line)) is not None:
                return verdict
        return None

    def stop(self) -> None:
        if self.proc.poll() is None:
            try:
                os.killpg(self.proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        self.proc.wait(timeout=5)


def run(mp: MAVProxy, job: dict, tmp: str, deadline: float) -> dict:
    op, mtype = job["op"], job["mission_type"]
    cmd, acktype = COMMANDS[mtype], ACK_TYPES[mtype]
    # MAVProxy never ended the operation itself: the harness tells a hang from a failure by this
    gave_up = lambda: {"ok": False, "ended": False,  # noqa: E731
                       "said": f"gave up waiting; MAVProxy last said: {mp.last}"}

    if mp.wait_for(lambda ln: True if ln.startswith(STARTED) else None, deadline) is None:
        return {"ok": False, "said": f"no vehicle HEARTBEAT; MAVProxy last said: {mp.last}"}

    def acked(line: str):
        m = ACK.match(line)
        if m and m.group(1) == acktype:
            return {"ok": m.group(2) == "ACCEPTED", "said": line}
        if line.startswith("Unable to load"):
            return {"ok": False, "said": line}
        return None

    if op in ("upload", "clear"):
        if op == "upload":
            plan = os.path.join(tmp, "plan.txt")
            write_wpl(plan, job["items"])
            mp.send(f"{cmd} load {plan}")
        else:
            mp.send(f"{cmd} clear")
        return mp.wait_for(acked, deadline) or gave_up()

    if op == "set-current":
        seq = job["seq"]
        mp.send(f"wp set {seq}")

        def current(line: str):
            m = CMD_ACK.match(line)
            if m:
                return {"ok": m.group(1) == "ACCEPTED", "said": line}
            return {"ok": True, "said": line} if line == f"waypoint {seq}" else None
        return mp.wait_for(current, deadline) or gave_up()

    # download: `list` prints the items once all came; then dump them locally (no traffic)
    mp.send(f"{cmd} list")
    listed: list = []
    expected = [None]

    def listing(line: str):
        m = re.match(r"^Requesting (\d+) ", line)
        if m:
            expected[0], listed[:] = int(m.group(1)), []
        elif (m := LISTED.match(line)) and expected[0] is not None:
            listed.append(m.groups())
        return True if expected[0] and len(listed) == expected[0] else None
    if mp.wait_for(listing, deadline) is None:
        return gave_up()
    said = mp.last
    dump = os.path.join(tmp, "download.txt")
    mp.send(f"{cmd} savelocal {dump}")
    mp.send(f"{cmd} status")
    if mp.wait_for(lambda ln: True if ln.startswith("Have ") else None, deadline) is None:
        return gave_up()
    return {"ok": True, "said": f"downloaded {len(listed)} items; {said}",
            "items": read_download(dump, listed)}


def main(argv: list[str]) -> int:
    if len(argv) != 3 or not argv[0].isdigit() or not 0 < int(argv[0]) < 65536:
        print(f"{PROG}: usage: mavproxy_gcs.py PORT OP JOBFILE", file=sys.stderr)
        return 2
    started = time.monotonic()
    try:
        job = read_job(argv[2], argv[1])
    except BadJob as exc:
        print(f"{PROG}: bad job: {exc}", file=sys.stderr)
        return 2
    timeout = float(job["timeout_s"])
    deadline = started + max(1.0, timeout - max(2.0, 0.15 * timeout))

    def on_term(signum, _frame):
        raise Terminated(f"signal {signum}")
    signal.signal(signal.SIGTERM, on_term)
    signal.signal(signal.SIGINT, on_term)

    mp = None
    with tempfile.TemporaryDirectory(prefix="mavproxy_gcs.") as tmp:
        try:
            mp = MAVProxy(int(argv[0]), COMMANDS[job["mission_type"]], tmp)
            result = run(mp, job, tmp, deadline)
        except EOFError as exc:
            result = {"ok": False, "said": str(exc)}
        except Terminated as exc:
            result = {"ok": False, "said": f"terminated ({exc}); MAVProxy last said: {mp.last if mp else '-'}"}
        except (OSError, ValueError, IndexError) as exc:
            result = {"ok": False, "said": f"adapter error: {exc}; MAVProxy last said: {mp.last if mp else '-'}"}
        finally:
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            if mp is not None:
                mp.stop()
    try:
        with open(job["result"], "w", encoding="utf-8") as f:
            json.dump(result, f)
    except OSError as exc:
        print(f"{PROG}: cannot write result {job['result']}: {exc}", file=sys.stderr)
    if not result["ok"]:
        print(f"{PROG}: {result['said']}", file=sys.stderr)
    return 0 if result["ok"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
