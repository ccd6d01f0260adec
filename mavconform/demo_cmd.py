"""`mavconform demo`: the reference vehicle and GCS on real UDP loopback, behind a lossy link.

It shows the whole stack working over real sockets. It uploads a plan with mission, geofence and rally points,
downloads it back, compares, clears everything, confirms the vehicle is empty, and prints a
summary. Exit 0 when every step matched, 1 otherwise.
"""

from __future__ import annotations

import argparse
import time

from mavconform.reference_impl.files import SAMPLES_DIR, load_plan, plan_types_in
from mavconform.reference_impl.gcs import GcsNode
from mavconform.reference_impl.mission.items import MissionType, renumber
from mavconform.reference_impl.net import FaultModel, MonotonicClock, UdpDriver
from mavconform.reference_impl.session import GcsSession, TargetUnresponsive
from mavconform.reference_impl.vehicle import VehicleNode

from .options import capture_to, probability

DEFAULT_PLAN = SAMPLES_DIR / "demo.plan"


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("demo", help="reference GCS <-> reference vehicle over lossy UDP loopback",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--plan", default=str(DEFAULT_PLAN), metavar="FILE",
                   help="the .plan or .waypoints file to round-trip (default: the bundled demo.plan)")
    p.add_argument("--loss", type=probability, default=0.1, metavar="P",
                   help="loss probability on each direction of the vehicle's link (default 0.1)")
    p.add_argument("--dup", type=probability, default=0.02, metavar="P", help="duplication (default 0.02)")
    p.add_argument("--reorder", type=probability, default=0.02, metavar="P", help="reordering (default 0.02)")
    p.add_argument("--seed", type=int, default=1, help="seed of the fault decisions (default 1)")
    p.add_argument("--capture", metavar="FILE.mcap", help="record every datagram to an MCAP file")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    plan = load_plan(args.plan)
    types = plan_types_in(args.plan)
    faults = FaultModel(loss=args.loss, duplicate=args.dup, reorder=args.reorder, reorder_delay=0.03)
    clock = MonotonicClock()
    vehicle = VehicleNode(wall_clock=clock.wall)
    started = time.perf_counter()
    rows: list[tuple[str, bool, str]] = []
    with UdpDriver(clock=clock, seed=args.seed) as driver:
        vehicle_at = driver.add_node(vehicle, bind=("127.0.0.1", 0), outgoing=faults, incoming=faults)
        gcs = GcsNode(remote=vehicle_at, wall_clock=clock.wall)
        gcs_at = driver.add_node(gcs, bind=("127.0.0.1", 0))
        with capture_to(driver, args.capture):   # after the binds: a bad address leaves no file
            print(f"vehicle on udp:{vehicle_at[0]}:{vehicle_at[1]}, GCS on udp:{gcs_at[0]}:{gcs_at[1]}; "
                  f"vehicle link: loss {args.loss:g}, dup {args.dup:g}, reorder {args.reorder:g} each way (seed {args.seed})")
            session = GcsSession(driver, gcs)
            try:
                session.wait_for_target(10.0)
            except TargetUnresponsive as exc:
                print(f"FAIL {exc}")
                return 1
            for t in types:
                r = session.upload(t, plan.items(t))
                rows.append((f"upload {t.label} ({len(plan.items(t))} items)", r.ok, _cost(r)))
            for t in types:
                r = session.download(t)
                want = tuple(renumber(plan.items(t), t))
                same = r.ok and r.items == want
                rows.append((f"download {t.label} equals upload", same, _cost(r) if r.ok else r.summary()))
            r = session.clear(MissionType.ALL)
            rows.append(("clear all", r.ok, _cost(r)))
            for t in types:
                r = session.download(t)
                rows.append((f"{t.label} empty after clear", r.ok and r.items == (), _cost(r)))
            stats = driver.stats
    width = max(len(name) for name, _, _ in rows)
    for name, ok, note in rows:
        print(f"  {'ok  ' if ok else 'FAIL'}  {name:<{width}}  {note}")
    sent = sum(s.sent for s in stats.values())
    dropped = sum(s.dropped for s in stats.values())
    passed = sum(ok for _, ok, _ in rows)
    print(f"{passed}/{len(rows)} steps ok in {time.perf_counter() - started:.1f} s; "
          f"{sent} datagrams, {dropped} dropped by the fault model; "
          f"vehicle decode errors: {len(vehicle.endpoint.decode_errors)}")
    return 0 if passed == len(rows) else 1


def _cost(r) -> str:
    return f"{r.finished - r.started:.2f} s, {r.retries} retries" if r.ok else r.summary()
