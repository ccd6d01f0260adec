"""`mavconform bridge`: a MAVLink vehicle whose mission is an MSP flight controller's waypoints."""

from __future__ import annotations

import argparse
import sys
from mavconform.reference_impl.msp.bridge import BridgeConfig, MspBridge, MspLink
from mavconform.reference_impl.msp.jobs import Done, read_mission
from mavconform.reference_impl.msp.links import connect, parse_msp_link
from mavconform.reference_impl.msp.nodes import MspServerNode
from mavconform.reference_impl.net import MonotonicClock, UdpDriver
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.errors import UsageError
from mavconform.reports.text import msp_stream_text
from mavconform.reference_impl.net.uri import LISTEN_FORMS, PEER_FORMS, LinkUri, UdpUri, parse_link_uri, parse_udp_uri
from mavconform.reference_impl.interrupts import InterruptGuard

from .options import capture_to, mavlink_id, positive

BUILTIN = "builtin"
DESCRIPTION = """\
Serve a MAVLink vehicle on UDP, TCP or a serial line whose mission is an MSP flight
controller's waypoint list (INAV's), so QGroundControl, MAVProxy, MAVSDK or `mavconform run`
reach it. Uploads, downloads, clears and set-current are MAVLink's Mission Protocol on the
--listen side (the reference mission engine); on the --msp side each becomes MSP: an upload
is checked item by item against what MSP can hold (docs/msp-mapping.md: a command with no
INAV action, a param with no slot, an altitude that is not whole centimetres, more than 120
items are refused with the MISSION_ACK error the table gives), then written with MSP_SET_WP
and read back with MSP_WP, and only then ACCEPTED; a waypoint that did not store as written
fails the upload (MAV_MISSION_ERROR, with a STATUSTEXT naming it) and the mission held before
is written back. A download reads the list first (MSP_WP_GETINFO, MSP_WP). A clear writes
MSP's "no mission" record (one RTH waypoint of zeros, flagged 0xA5). Set-current asks
MSP2_INAV_SET_WP_INDEX, which INAV takes only while flying a WP mission. MISSION_CURRENT
follows MSP_NAV_STATUS. Fence and rally plans are refused (MSP holds missions only).
"""

EPILOG = """\
examples:
  mavconform bridge --msp tcp:127.0.0.1:5760              # INAV SITL's MSP port; GCS on udp 14550
  mavconform bridge --msp serial:/dev/ttyACM0:115200 --listen udpin:14550
  mavconform bridge --msp builtin --listen udpin:0          # our model of INAV's store, to try it
  mavconform run --target udp:127.0.0.1:14550 --expect msp-bridge   # the MAVLink suite through it
  mavconform bridge --msp tcp:127.0.0.1:5760 --listen udpin:0 --connect udp:127.0.0.1:14540
      # speaks first to a GCS listening on 14540 (MAVSDK's udpin://, MAVProxy's --master=udpin:)
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bridge", help="serve an MSP flight controller's mission as a MAVLink vehicle",
                       description=DESCRIPTION, epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--msp", required=True, metavar="URI",
                   help=f"the MSP flight controller: {PEER_FORMS} (115200 baud unless given), or "
                        f"{BUILTIN} (builtin:msp, our model of INAV 9.1's waypoint store, over TCP loopback)")
    p.add_argument("--listen", default="udp:127.0.0.1:14550", metavar="URI",
                   help=f"where the GCSs reach it: udp:HOST:PORT, {LISTEN_FORMS} (port 0: any free port; "
                        "default %(default)s)")
    p.add_argument("--connect", metavar="URI",
                   help="also send to a GCS that listens at udp:HOST:PORT (MAVSDK's and MAVProxy's udpin:; with a "
                        "UDP --listen)")
    p.add_argument("--system", type=mavlink_id, default=1, help="its MAVLink system id (default 1)")
    p.add_argument("--component", type=mavlink_id, default=1, help="its MAVLink component id (default 1)")
    p.add_argument("--duration", type=positive, metavar="S", help="stop after S seconds (default: until Ctrl-C)")
    p.add_argument("--capture", metavar="FILE.mcap", help="record the MAVLink side's datagrams to an MCAP file")
    p.add_argument("--quiet", action="store_true", help="print only the start-up lines")
    p.set_defaults(run=run)


def _msp_uri(text: str) -> LinkUri | None:
    """--msp: None for builtin, or a link to a listening flight controller (serial: 115200
    baud unless given, INAV's MSP default)."""
    if text.strip().lower() in (BUILTIN, "builtin:msp"):
        return None
    return parse_msp_link(text, role="peer", option="--msp")


def run(args: argparse.Namespace) -> int:
    msp = _msp_uri(args.msp)
    listen = parse_link_uri(args.listen, role="listen", option="--listen")
    gcs = parse_udp_uri(args.connect, role="peer", option="--connect") if args.connect else None
    if gcs is not None and not isinstance(listen, UdpUri):
        raise UsageError("--connect adds a UDP peer to a UDP --listen; a TCP or serial link has one peer")
    clock = MonotonicClock()
    link = MspLink()
    bridge = MspBridge(link, BridgeConfig(system=args.system, component=args.component), wall_clock=clock.wall)
    with UdpDriver(clock=clock) as driver:
        fc = connect(driver, link, msp, server=MspServerNode() if msp is None else None)
        look = _first_look(driver, link, fc)   # before the GCS side runs: one job at a time
        peer, address = attach(driver, bridge, listen, listen=True)
        if peer is not None:
            bridge.endpoint.add_address(peer)
        if gcs is not None:
            bridge.endpoint.add_address(gcs.address)
        stream = driver.stream_of(bridge)
        where = f"udp:{address[0]}:{address[1]}" if stream is None else stream.uri
        named = "builtin:msp over TCP loopback" if msp is None else str(msp)
        print(f"MSP bridge {args.system}/{args.component} listening on {where}; flight controller {named}", flush=True)
        print(look, flush=True)
        with capture_to(driver, args.capture):
            _serve(driver, bridge, clock, args)
    return 0


def _first_look(driver: UdpDriver, link: MspLink, fc: object) -> str:
    """What the flight controller holds now (bounded): a dead one is said, not waited on."""
    got: list = []
    link.runner.start(read_mission(), driver.clock.now(), lambda result, now: got.append(result))
    driver.run_until(lambda: bool(got), timeout=5.0)
    if not got or not isinstance(got[0], Done):
        why = got[0].why if got else "no answer within 5 s"
        return f"flight controller at {fc}: {why} (serving anyway: each operation asks it again)"
    info = got[0].info
    return (f"flight controller at {fc}: {info.count} waypoints, mission valid {int(info.valid)}, "
            f"{info.max_waypoints} at most")


def _serve(driver: UdpDriver, bridge: MspBridge, clock: MonotonicClock, args: argparse.Namespace) -> None:
    end = None if args.duration is None else clock.now() + args.duration
    try:
        with InterruptGuard():   # SIGTERM too stops it as Ctrl-C does
            shown = None
            while end is None or clock.now() < end:
                step = 1.0 if end is None else max(0.0, min(1.0, end - clock.now()))
                driver.run_until(lambda: bool(bridge.events), timeout=step)
                for event in bridge.events:
                    if not args.quiet:
                        print(event, flush=True)
                bridge.events.clear()
                skipped = msp_stream_text(vars(bridge.link.parser.stats))
                if skipped != shown and not args.quiet:   # noise, bad checksums: said as they grow
                    print(f"{skipped} (from the flight controller, skipped)", flush=True)
                    shown = skipped
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)
