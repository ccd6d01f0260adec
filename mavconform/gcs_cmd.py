"""`mavconform gcs ...`: drive a target vehicle with the reference GCS over UDP."""

from __future__ import annotations

import argparse
import contextlib
import sys
from typing import Iterator

from mavconform.reference_impl.files import Plan, check_writable, load_plan, plan_from_items, plan_types_in, save_plan
from mavconform.reference_impl.files.from_vehicle import facts_from_gcs
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.adaptations import NAMED
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.plan_upload import previous_plans, upload_plan
from mavconform.reference_impl.mission.results import OperationResult
from mavconform.reference_impl.net.uri import FORMS, local_bind_for
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net import MonotonicClock, UdpDriver, UdpUri, parse_udp_uri
from mavconform.reference_impl.session import GcsSession, TargetUnresponsive

from .options import capture_to, mavlink_id, seconds_up_to, seq_number, time_scale

DESCRIPTION = """\
Drive a vehicle's Mission Protocol with the reference GCS. The target is a URI:
  udp:HOST:PORT      the vehicle listens there (our reference vehicle, a SITL with a UDP server)
  udpin:[HOST:]PORT  we listen there (default host 127.0.0.1) and the vehicle sends to us
                     first (as PX4/ArduPilot SITL do)
The vehicle is found by its HEARTBEAT, whose autopilot field also picks how the GCS adapts
to it (ArduPilot: home at seq 0, non-terminating NACKs, ...; PX4: ...; anything else: the
spec-exact GCS); --adapt fixes the choice. The adaptations that acted are printed at the end.
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
    for p in (up, down, clear, setcur):
        p.add_argument("--target", required=True, metavar="URI", help=FORMS)
        p.add_argument("--system", type=mavlink_id, default=255, help="our system id (default 255)")
        p.add_argument("--heartbeat-timeout", type=seconds_up_to(3600), default=5.0, metavar="S",
                       help="how long to wait for the target's HEARTBEAT (default 5)")
        p.add_argument("--time-scale", type=time_scale, default=1.0, metavar="X",
                       help="stretch every protocol timeout by X for slow links (default 1)")
        p.add_argument("--float", action="store_true",
                       help="download with MISSION_REQUEST / MISSION_ITEM instead of the _INT "
                            "messages (uploads always answer in the form the vehicle asks for)")
        p.add_argument("--capture", metavar="FILE.mcap", help="record every datagram to an MCAP file")
        p.add_argument("--adapt", choices=("auto", *NAMED), default="auto",
                       help="how to adapt to the vehicle: auto (from its HEARTBEAT autopilot, the "
                            "default), none (spec-exact), or the set for px4 / ardupilot")
        p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    target = parse_udp_uri(args.target, option="--target")
    # bad files and paths fail before any network I/O
    plan = load_plan(args.file) if args.operation == "upload" else None
    for note in plan.notes if plan is not None else ():
        # e.g. a skipped version-1 fence: uploading the plan clears the vehicle's fence
        print(f"mavconform: warning: {note}", file=sys.stderr)
    if args.operation == "download":
        check_writable(args.file)
    with _session(args, target) as session:
        try:
            session.wait_for_target(args.heartbeat_timeout)
        except TargetUnresponsive as exc:
            print(f"mavconform: target unresponsive: {target}: {exc}", file=sys.stderr)
            return 1
        gcs = session.gcs
        print(f"target {gcs.target[0]}/{gcs.target[1]} at {target}")
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


@contextlib.contextmanager
def _session(args: argparse.Namespace, target: UdpUri) -> Iterator[GcsSession]:
    clock = MonotonicClock()
    timings = Timings().scaled(args.time_scale)
    config = GcsConfig(system=args.system, timings=timings, download_int=not args.float,
                       adaptations=None if args.adapt == "auto" else NAMED[args.adapt])
    remote = target.address if target.mode == "udp" else None
    gcs = GcsNode(config, remote=remote, wall_clock=clock.wall)
    bind = target.address if target.mode == "udpin" else (local_bind_for(target.host), 0)
    with UdpDriver(clock=clock) as driver:
        driver.add_node(gcs, bind=bind)   # bind first: a bad address leaves no capture file
        with capture_to(driver, args.capture):
            yield GcsSession(driver, gcs)


