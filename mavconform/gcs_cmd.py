"""`mavconform gcs ...`: drive a target vehicle with the reference GCS over UDP, TCP or a serial line."""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Any, Iterator

from mavconform.reference_impl.files import Plan, check_writable, load_plan, plan_from_items, plan_types_in, save_plan
from mavconform.reference_impl.files.from_vehicle import facts_from_gcs
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover.control_client import ClientConfig, always
from mavconform.reference_impl.handover.control_messages import DEFAULT_REQUEST_TIMEOUT, TIMEOUT_MAX, TIMEOUT_MIN
from mavconform.reference_impl.handover.control_results import ControlResult, Decision, TakeoverRequested
from mavconform.reference_impl.mission.adaptations import NAMED
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.plan_upload import previous_plans, upload_plan
from mavconform.reference_impl.mission.results import OperationResult
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.net.uri import FORMS, LinkUri, parse_link_uri
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net import MonotonicClock, UdpDriver
from mavconform.reference_impl.session import GcsSession, TargetUnresponsive
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.wire.signing import SigningKey, secret_from_hex, secret_from_passphrase

from .options import capture_to, mavlink_id, seconds_up_to, seq_number, time_scale

DESCRIPTION = """\
Drive a vehicle's Mission Protocol with the reference GCS. The target is a URI:
  udp:HOST:PORT      the vehicle listens there (our reference vehicle, a SITL with a UDP server)
  udpin:[HOST:]PORT  we listen there (default host 127.0.0.1) and the vehicle sends to us
                     first (as PX4/ArduPilot SITL do)
  tcp:HOST:PORT      the vehicle serves TCP there (ArduPilot SITL's 5760, INAV's 5762)
  tcpin:[HOST:]PORT  we listen for the vehicle's TCP connection
  serial:DEVICE[:BAUD]  a flight controller on a serial port (default 57600 baud)
The vehicle is found by its HEARTBEAT, whose autopilot field also picks how the GCS adapts
to it (ArduPilot: home at seq 0, non-terminating NACKs, ...; PX4: ...; anything else: the
spec-exact GCS); --adapt fixes the choice. The adaptations that acted are printed at the end.
`gcs control` asks for, releases or shares operator control of a vehicle that has it
(`mavconform vehicle --operator-control`).
With --signing-key (or --signing-passphrase) every frame is signed with this GCS's own
MAVLink 2 key, as a vehicle with a signing roster requires (`mavconform vehicle
--signing-roster`); such a vehicle drops unsigned frames, so without the key it looks silent.
Exit 0 when every operation succeeded, 1 when one failed or the target never answered, 2 for
a usage mistake.
"""

TYPE_NAMES = {"mission": MissionType.MISSION, "fence": MissionType.FENCE,
              "rally": MissionType.RALLY, "all": MissionType.ALL}


def add_parser(sub: argparse._SubParsersAction) -> None:
    gcs = sub.add_parser("gcs", help="drive a target with the reference GCS",
                         description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    ops = gcs.add_subparsers(dest="operation", metavar="OPERATION", required=True)
    up = ops.add_parser("upload", help="upload a .plan (mission, fence, rally) or .waypoints file",
                        description="Upload every plan type the file holds: a .plan file sets mission, "
                                    "geofence and rally points (an empty one clears that type); a WPL "
                                    ".waypoints file sets the mission only. The parts go in that order "
                                    "and the first one that fails stops the rest; nothing already "
                                    "uploaded is rolled back.")
    up.add_argument("file", metavar="FILE")
    up.add_argument("--keep-going", action="store_true",
                    help="upload every part even after one fails (e.g. the fence and rally points "
                         "of a plan whose mission the vehicle refused)")
    down = ops.add_parser("download", help="download into a .plan or .waypoints file",
                          description="Download the vehicle's plans: all three types into a .plan "
                                      "file, the mission only into a .waypoints file.")
    down.add_argument("file", metavar="FILE")
    clear = ops.add_parser("clear", help="clear plans on the vehicle",
                           description="Send MISSION_CLEAR_ALL for one type or all of them.")
    clear.add_argument("--type", choices=sorted(TYPE_NAMES), default="all", dest="plan_type",
                       help="which plan to clear (default all)")
    setcur = ops.add_parser("set-current", help="set the current mission item",
                            description="Send MISSION_SET_CURRENT (or MAV_CMD_DO_SET_MISSION_CURRENT "
                                        "with --command) and wait for MISSION_CURRENT.")
    setcur.add_argument("seq", type=seq_number, metavar="SEQ", help="mission item number, 0..65535")
    setcur.add_argument("--command", action="store_true", help="use the command instead of the message")
    control = _add_control_parser(ops)
    for p in (up, down, clear, setcur, control):
        p.add_argument("--target", required=True, metavar="URI", help=FORMS)
        p.add_argument("--system", type=mavlink_id, default=255, help="our system id (default 255)")
        p.add_argument("--heartbeat-timeout", type=seconds_up_to(3600), default=5.0, metavar="S",
                       help="how long to wait for the target's HEARTBEAT (default 5)")
        p.add_argument("--time-scale", type=time_scale, default=1.0, metavar="X",
                       help="stretch every protocol timeout by X for slow links (default 1)")
        p.add_argument("--capture", metavar="FILE.mcap", help="record every datagram to an MCAP file")
        keys = p.add_mutually_exclusive_group()
        keys.add_argument("--signing-key", type=_hex_key, metavar="HEX",
                          help="sign every frame with this MAVLink 2 key (64 hex digits): this GCS's "
                               "own key, as the vehicle's roster has it")
        keys.add_argument("--signing-passphrase", type=_passphrase_key, metavar="TEXT",
                          help="the same, the key being SHA-256 of TEXT (as MAVProxy's `signing setup`)")
        p.add_argument("--signing-link-id", type=_link_id, metavar="N",
                       help="link id written into our signatures (0..255, default 0)")
        p.set_defaults(run=run)
    for p in (up, down, clear, setcur):
        p.add_argument("--float", action="store_true",
                       help="download with MISSION_REQUEST / MISSION_ITEM instead of the _INT "
                            "messages (uploads always answer in the form the vehicle asks for)")
        p.add_argument("--adapt", choices=("auto", *NAMED), default="auto",
                       help="how to adapt to the vehicle: auto (from its HEARTBEAT autopilot, the "
                            "default), none (spec-exact), or the set for px4 / ardupilot")


def run(args: argparse.Namespace) -> int:
    target = parse_link_uri(args.target, option="--target")
    if args.operation == "control":
        return _control(args, target)
    # bad files and paths fail before any network I/O
    plan = load_plan(args.file) if args.operation == "upload" else None
    for note in plan.notes if plan is not None else ():
        # e.g. a skipped version-1 fence: uploading the plan clears the vehicle's fence
        print(f"mavconform: warning: {note}", file=sys.stderr)
    if args.operation == "download":
        check_writable(args.file)
    with _session(args, target) as session:
        if not _found(session, target, args.heartbeat_timeout):
            return 1
        gcs = session.gcs
        armed = ", ".join(a.id for a in gcs.adaptations.armed()) or "none"
        print(f"adaptations: {gcs.adaptations.name} ({armed})")
        results = _operate(args, session, plan)
    for r in results:
        print(f"{'ok  ' if r.ok else 'FAIL'} {r.summary()}  [{r.finished - r.started:.2f} s, {r.retries} retries]")
    print(f"adaptations used: {', '.join(gcs.adaptations_used) or 'none'}")
    return 0 if results and all(r.ok for r in results) else 1


def _operate(args: argparse.Namespace, session: GcsSession, plan: Plan | None) -> list[OperationResult]:
    if args.operation == "upload":
        previous = previous_plans(session.gcs.received)   # before anything is replaced
        done = upload_plan([(t, plan.items(t)) for t in plan_types_in(args.file)], session.upload,
                           keep_going=args.keep_going, previous=previous)
        for line in done.report():
            print(line)
        if done.not_sent:
            print("(--keep-going uploads every part even after one fails)")
        return list(done.results)
    if args.operation == "download":
        results = [session.download(t) for t in plan_types_in(args.file)]
        if all(r.ok for r in results):
            got = {r.mission_type: list(r.items) for r in results}
            home, settings = facts_from_gcs(session.gcs)   # HEARTBEAT identity, home (QGC needs both)
            save_plan(plan_from_items(got.get(MissionType.MISSION, ()), got.get(MissionType.FENCE, ()),
                                      got.get(MissionType.RALLY, ()), home, settings), args.file)
            print(f"wrote {args.file}")
        return results
    if args.operation == "clear":
        return [session.clear(TYPE_NAMES[args.plan_type])]
    return [session.set_current(args.seq, via_command=args.command)]


def _found(session: GcsSession, target: LinkUri, timeout: float) -> bool:
    """Wait for the target's HEARTBEAT and say who answered, or say that no one did."""
    try:
        session.wait_for_target(timeout)
    except TargetUnresponsive as exc:
        print(f"mavconform: target unresponsive: {target}: {exc}", file=sys.stderr)
        return False
    gcs = session.gcs
    print(f"target {gcs.target[0]}/{gcs.target[1]} at {target}")
    return True


@contextlib.contextmanager
def _session(args: argparse.Namespace, target: LinkUri, **node: Any) -> Iterator[GcsSession]:
    """A GCS on `target`'s link; `node`: GcsNode keywords (`control_policy`)."""
    clock = MonotonicClock()
    timings = Timings().scaled(args.time_scale)
    config = GcsConfig(system=args.system, timings=timings, download_int=not args.float,
                       adaptations=None if args.adapt == "auto" else NAMED[args.adapt],
                       control=_client_config(args) if args.operation == "control" else None,
                       signing=_signing(args))
    gcs = GcsNode(config, wall_clock=clock.wall, **node)
    with UdpDriver(clock=clock) as driver:
        remote, _ = attach(driver, gcs, target)   # first: a bad address leaves no capture file
        if remote is not None:   # udpin: the vehicle is learnt from its first datagram
            gcs.endpoint.add_address(remote)
        with capture_to(driver, args.capture):
            yield GcsSession(driver, gcs)


# --- signing --------------------------------------------------------------------------------
def _hex_key(text: str) -> bytes:
    try:
        return secret_from_hex(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _passphrase_key(text: str) -> bytes:
    try:
        return secret_from_passphrase(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _link_id(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value <= 255:
        raise argparse.ArgumentTypeError(f"{text!r} is not a link id in 0..255")
    return value


def _signing(args: argparse.Namespace) -> SigningKey | None:
    secret = args.signing_key or args.signing_passphrase
    if secret is None:
        if args.signing_link_id is not None:
            raise UsageError("--signing-link-id needs --signing-key or --signing-passphrase")
        return None
    return SigningKey(secret, args.signing_link_id or 0)


# --- gcs control ----------------------------------------------------------------------------
CONTROL_ACTIONS = ("request", "release", "allow", "disallow")
ANSWERS = {"allow": Decision.ALLOW, "release": Decision.RELEASE, "refuse": Decision.REFUSE}


def _add_control_parser(ops: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = ops.add_parser(
        "control", help="request or release operator control, allow or disallow takeover",
        description="Operator control (MAV_CMD_REQUEST_OPERATOR_CONTROL, development.xml), as the "
                    "vehicle's CONTROL_STATUS names its system manager: request control (held by a "
                    "GCS that must agree, wait up to --timeout for its answer), release it, or, in "
                    "control, allow or disallow takeover by another GCS. Control lasts while this "
                    "GCS's HEARTBEATs do: when the command exits the vehicle drops it after its "
                    "owner-loss time unless --hold keeps it connected.")
    p.add_argument("action", choices=CONTROL_ACTIONS, metavar="ACTION",
                   help="request | release | allow | disallow")
    p.add_argument("--timeout", type=_request_timeout, default=DEFAULT_REQUEST_TIMEOUT, metavar="S",
                   help=f"request: param 3, how long the owner has to answer ({TIMEOUT_MIN:g}..{TIMEOUT_MAX:g}, "
                        f"default {DEFAULT_REQUEST_TIMEOUT:g})")
    p.add_argument("--allow-takeover", action="store_true",
                   help="request: let later requests of other GCSs be granted without asking us")
    p.add_argument("--hold", type=seconds_up_to(24 * 3600), metavar="S",
                   help="stay connected S seconds after the operation (HEARTBEATs keep control), "
                        "answering forwarded requests by --answer and printing control changes")
    p.add_argument("--answer", choices=sorted(ANSWERS), default="refuse",
                   help="how to answer another GCS's request the vehicle forwards while we are in "
                        "control (default refuse: it times out)")
    p.set_defaults(float=False, adapt="auto")   # mission-only options the session reads
    return p


def _request_timeout(text: str) -> float:
    value = seconds_up_to(TIMEOUT_MAX)(text)
    if value < TIMEOUT_MIN:
        raise argparse.ArgumentTypeError(f"{text!r} must be at least {TIMEOUT_MIN:g} seconds (param 3)")
    return value


def _client_config(args: argparse.Namespace) -> ClientConfig:
    base = ClientConfig()
    return ClientConfig(ack_timeout=base.ack_timeout * args.time_scale, request_timeout=args.timeout)


def _control(args: argparse.Namespace, target: LinkUri) -> int:
    with _session(args, target, control_policy=always(ANSWERS[args.answer])) as session:
        if not _found(session, target, args.heartbeat_timeout):
            return 1
        gcs = session.gcs
        if session.wait_for_control_status(args.heartbeat_timeout):
            print(f"control: {_holder(gcs.control.owner, gcs.control.takeover_allowed)} "
                  f"(CONTROL_STATUS from {gcs.control.manager[0]}/{gcs.control.manager[1]})")
        else:
            print(f"mavconform: warning: no CONTROL_STATUS within {args.heartbeat_timeout:g} s: the target "
                  "may not support operator control", file=sys.stderr)
        shown = len(gcs.control_results)
        result = _control_operation(args, session)
        done = gcs.control_results[shown:]   # with answers to forwarded requests meanwhile
        _print_control(done if result in done else [*done, result])   # (a refusal sent nothing)
        if args.hold:
            _hold(session, args.hold, len(gcs.control_results), len(gcs.control_events))
    return 0 if result.ok else 1


def _control_operation(args: argparse.Namespace, session: GcsSession) -> ControlResult:
    if args.action == "request":
        return session.request_control(allow_takeover=args.allow_takeover, timeout=args.timeout)
    if args.action == "release":
        return session.release_control()
    return session.allow_takeover(args.action == "allow")


def _hold(session: GcsSession, seconds: float, results: int, events: int) -> None:
    """Stay connected, printing what happens to control, until `seconds` pass."""
    gcs = session.gcs
    print(f"holding for {seconds:g} s", flush=True)
    end = session.now + seconds
    while session.now < end:
        session.driver.run_until(lambda: len(gcs.control_events) > events or len(gcs.control_results) > results,
                                 timeout=min(1.0, max(0.0, end - session.now)))
        for event in list(gcs.control_events)[events:]:
            if isinstance(event, TakeoverRequested):
                print(f"GCS {event.requester} asks for control (answer within {event.timeout:g} s)", flush=True)
            else:
                print(f"control: {_holder(event.owner, event.takeover_allowed)} (was {event.previous})", flush=True)
        _print_control(gcs.control_results[results:])
        events, results = len(gcs.control_events), len(gcs.control_results)


def _print_control(results: list[ControlResult]) -> None:
    for r in results:
        detail = f" ({r.detail})" if r.detail else ""
        print(f"{'ok  ' if r.ok else 'FAIL'} {r.operation.value}: {r.outcome.value}{detail}  "
              f"[{r.finished - r.started:.2f} s, {r.retries} retries]", flush=True)


def _holder(owner: int, takeover_allowed: bool) -> str:
    who = f"GCS {owner} in control" if owner else "no GCS in control"
    return f"{who}, takeover {'allowed' if takeover_allowed else 'disallowed'}"
