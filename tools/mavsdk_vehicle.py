#!/usr/bin/env python3
"""MAVSDK's MissionRawServer as a vehicle on UDP loopback, for `mavconform run` to test.

    python tools/mavsdk_vehicle.py [--port N] [--sysid 1] [--compid 1] [--duration 600] [-v]

Starts MAVSDK (the `mavsdk` package from PyPI: its C++ core, wrapped by ctypes; no
mavsdk_server process) configured as an autopilot component, listening on
`udpin://127.0.0.1:PORT`, with the MissionRawServer plugin serving upload, download,
clear and set-current for the mission, fence and rally plans. Everything else
(retries, timeouts, ACK codes) is MAVSDK's own `MavlinkMissionTransferServer`. Like
a companion computer's own server, this script only subscribes to the plugin's
callbacks to report them (with -v); it never acts on the plans, and flies nothing, so
MISSION_ITEM_REACHED is never sent (run the suite without --allow-flight).

The first line on stdout is `listening on udp:127.0.0.1:PORT (...)`: the target to
give `mavconform run --target udp:127.0.0.1:PORT` (a udpin connection learns its peers
from what they send, so the GCS speaks first; MAVSDK then sends everything, HEARTBEAT
included, to every peer heard within 10 s). MAVSDK's own log goes to stderr
(warnings and errors; everything with -v). The process stops on SIGTERM or SIGINT,
and by itself after --duration seconds (exit 0). A bad option, or mavsdk not being
installed, is one line on stderr and exit 2.

Every socket is on 127.0.0.1. MAVSDK refuses port 0 in a connection URL, so with
`--port 0` (the default) the OS picks a free port on a probe socket, which is closed
and handed to MAVSDK; on Linux the script then checks that no other socket shares the
port (MAVSDK binds with SO_REUSEADDR) and picks again if one does.
"""

from __future__ import annotations

import argparse
import signal
import socket
import sys
import threading
import time

HOST = "127.0.0.1"
PROG = "mavsdk_vehicle"
PORT_TRIES = 8
STOP_GRACE_S = 5.0           # MAVSDK's teardown is bounded by this; then the process exits anyway
MAV_COMP_ID_AUTOPILOT1 = 1   # MAVSDK announces MAV_AUTOPILOT_GENERIC only from this component id
PLAN_TYPES = {0: "mission", 1: "fence", 2: "rally", 255: "all"}


class UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:   # one line, exit 2 (argparse prints usage + 2 lines)
        raise UsageError(message)


def _int_in(low: int, high: int, what: str):
    def parse(text: str) -> int:
        try:
            value = int(text, 10)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what} must be an integer, not {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{what} must be {low}..{high}, not {value}")
        return value
    return parse


def _duration(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--duration must be a number of seconds, not {text!r}") from None
    if not 0 < value <= 86400:
        raise argparse.ArgumentTypeError(f"--duration must be > 0 and <= 86400 s, not {text}")
    return value


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = _Parser(prog=PROG, description="Serve MAVSDK's MissionRawServer on udpin://127.0.0.1:PORT "
                "as a vehicle (autopilot component) for `mavconform run --target udp:127.0.0.1:PORT`.")
    p.add_argument("--port", type=_int_in(0, 65535, "--port"), default=0,
                   help="UDP port on 127.0.0.1 (default 0: a free port the OS picks)")
    p.add_argument("--sysid", type=_int_in(1, 255, "--sysid"), default=1,
                   help="MAVLink system id (default 1)")
    p.add_argument("--compid", type=_int_in(1, 255, "--compid"), default=MAV_COMP_ID_AUTOPILOT1,
                   help="MAVLink component id (default 1, MAV_COMP_ID_AUTOPILOT1; MAVSDK sends "
                        "MAV_AUTOPILOT_INVALID in the HEARTBEAT of any other, and mavconform "
                        "does not take such a component for a vehicle)")
    p.add_argument("--duration", type=_duration, default=600.0,
                   help="exit by itself after this many seconds (default 600)")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="MAVSDK's debug log and every plugin callback on stderr")
    return p.parse_args(argv)


def _say(text: str) -> None:
    print(f"{PROG}: {text}", file=sys.stderr, flush=True)


def _probe_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((HOST, 0))
        return s.getsockname()[1]


def _sockets_on_port(port: int) -> int | None:
    """How many IPv4 UDP sockets on this machine are bound to `port` (Linux), else None."""
    try:
        with open("/proc/net/udp", encoding="ascii") as f:
            rows = f.read().splitlines()[1:]
    except OSError:
        return None
    wanted = f"{port:04X}"
    return sum(1 for row in rows if row.split()[1].rsplit(":", 1)[1] == wanted)


def connect(mavsdk, port: int):
    """Add the udpin connection on 127.0.0.1; return (port, connection handle)."""
    from mavsdk import ConnectionResult
    from mavsdk.exceptions import ConnectionError as MavsdkConnectionError

    for _ in range(1 if port else PORT_TRIES):
        chosen = port or _probe_port()
        try:
            handle = mavsdk.add_any_connection_with_handle(f"udpin://{HOST}:{chosen}")
        except MavsdkConnectionError as exc:
            if port or ConnectionResult.BIND_ERROR.name not in str(exc):
                raise UsageError(f"cannot listen on udp:{HOST}:{chosen}: {exc}") from None
            continue   # someone took the probed port in between: pick again
        if _sockets_on_port(chosen) in (None, 1):
            return chosen, handle
        mavsdk.remove_connection(handle)   # another SO_REUSEADDR socket shares it: pick again
        if port:
            raise UsageError(f"udp:{HOST}:{port} is already in use")
    raise UsageError(f"found no free UDP port on {HOST} in {PORT_TRIES} tries")


def serve(args: argparse.Namespace, stop: threading.Event) -> None:
    try:
        import mavsdk
        from mavsdk import Configuration, LogLevel, Mavsdk, log_subscribe
        from mavsdk.plugins.mission_raw_server import MissionRawServer
    except ImportError as exc:
        raise UsageError(f"the mavsdk package is not installed ({exc}); "
                         "pip install -e '.[interop]' (or: make run-mavsdk)") from None

    def log(level, message, file, line) -> bool:   # MAVSDK logs to stdout by default: not ours
        if args.verbose or level >= LogLevel.WARN:
            _say(f"[mavsdk {level.name.lower()}] {message}")
        return True

    log_subscribe(log)
    configuration = Configuration.create_manual(args.sysid, args.compid, True)   # True: always heartbeat
    instance = Mavsdk(configuration)
    try:
        port, _ = connect(instance, args.port)
        server = instance.server_component_by_id(args.compid)
        if server is None:
            raise UsageError(f"MAVSDK has no server component with id {args.compid}")
        plugin = MissionRawServer(server)

        if args.verbose:
            def incoming(result, plan, _):
                types = sorted({PLAN_TYPES.get(i.mission_type, str(i.mission_type)) for i in plan.mission_items})
                _say(f"incoming mission: {result.name}, {len(plan.mission_items)} items {types}")
            plugin.subscribe_incoming_mission(incoming)
            plugin.subscribe_clear_all(lambda t, _: _say(f"clear all: type {PLAN_TYPES.get(t, t)}"))
            plugin.subscribe_current_item_changed(lambda item, _: _say(f"current item: seq {item.seq}"))

        print(f"listening on udp:{HOST}:{port} (MAVSDK {mavsdk.__version__} MissionRawServer, "
              f"system {args.sysid} component {args.compid})", flush=True)
        stop.wait(args.duration)
    finally:
        # bounded teardown: MAVSDK's destroy joins its threads; never hang the caller on it
        threading.Timer(STOP_GRACE_S, _exit_now).start()
        instance.destroy()


def _exit_now() -> None:
    import os
    _say(f"MAVSDK did not stop within {STOP_GRACE_S:g} s; exiting anyway")
    sys.stdout.flush()
    os._exit(0)


def main(argv: list[str] | None = None) -> int:
    stop = threading.Event()

    def on_signal(signum, _frame) -> None:
        stop.set()

    try:
        args = parse_args(argv)
        signal.signal(signal.SIGTERM, on_signal)
        signal.signal(signal.SIGINT, on_signal)
        started = time.monotonic()
        serve(args, stop)
    except UsageError as exc:
        _say(f"error: {exc}")
        return 2
    if args.verbose:
        _say(f"stopped after {time.monotonic() - started:.1f} s")
    return 0


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    import os
    os._exit(code)   # MAVSDK's atexit teardown already ran in serve(); skip the interpreter's
