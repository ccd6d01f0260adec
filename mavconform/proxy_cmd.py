"""`mavconform proxy`: a chaos proxy between a real GCS and a real vehicle, over UDP, TCP or serial."""

from __future__ import annotations

import argparse
import ipaddress
import socket
import sys

from mavconform.fuzz.proxy import DOWN, MAX_LEGS, UP, ChaosProxy, UdpProxy
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import LinkStats, MonotonicClock, UdpDriver, UdpUri
from mavconform.reference_impl.net.links import stream_peer
from mavconform.reference_impl.net.uri import LISTEN_FORMS, PEER_FORMS, parse_link_uri
from mavconform.reference_impl.interrupts import InterruptGuard

from .options import add_fault_options, capture_to, describe_faults, fault_model, positive

DESCRIPTION = """\
Sit between a GCS and a vehicle as a bad radio link. The GCS sends to --listen; the proxy
sends each datagram on to the vehicle at --forward from a port of its own (one per GCS, so
several GCSs can share the vehicle and each gets its own replies), and sends the vehicle's
replies back to that GCS from the listen port. Every datagram, both ways, goes through the
link faults below and, with --capture, into an MCAP file (each frame once, one channel per
direction per GCS, frames the faults dropped on '... (lost)').
Either side may be a TCP connection or a serial line instead (--listen tcpin:PORT,
serial:DEV or pty; --forward tcp:HOST:PORT or serial:DEV): a stream carries one peer, so a
stream --listen serves one GCS and a stream --forward is one connection (one GCS at a
time; a new GCS takes it over). Frames are cut from a stream and faulted one by one.
Runs until Ctrl-C (or SIGTERM) or --duration, then prints per-direction counts. Exit 0, or 2 for a
usage mistake.
"""

EPILOG = """\
faults:
  Every fault applies to each direction on its own (--only limits them to one): uplink is
  GCS -> vehicle, downlink vehicle -> GCS. --reorder is a probability, as for `vehicle`: a
  datagram it picks is held back 50 ms so later ones overtake it. --delay/--jitter are
  aliases of --delay-ms/--jitter-ms. A --drop rule counts its messages per direction, so
  'MISSION_ACK#1' drops the first MISSION_ACK each way (add --only down for the vehicle's).
  The same --seed gives the same fault decisions for the same traffic.

examples:
  mavconform vehicle --listen udp:127.0.0.1:14550 &
  mavconform proxy --listen udp:127.0.0.1:14551 --forward udp:127.0.0.1:14550 \\
      --loss 0.1 --dup 0.05 --reorder 0.05 --delay 20 --jitter 10 --capture run.mcap
  mavconform gcs upload --target udp:127.0.0.1:14551 my.plan
  mavconform proxy --listen udp:127.0.0.1:0 --forward udp:127.0.0.1:14550 \\
      --only down --drop 'MISSION_ACK#1' --duration 30
  mavconform proxy --listen udp:127.0.0.1:14551 --forward tcp:127.0.0.1:5760 --loss 0.05
      # a UDP GCS to ArduPilot SITL's TCP port, through a lossy link
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("proxy", help="a lossy link between a GCS and a vehicle, recording both ways",
                       description=DESCRIPTION, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--listen", required=True, metavar="URI",
                   help=f"where GCSs send to: udp:HOST:PORT, {LISTEN_FORMS} (udp: and udpin: both "
                        "listen; port 0: any free port, printed)")
    p.add_argument("--forward", required=True, metavar="URI",
                   help=f"the vehicle: {PEER_FORMS} (the proxy sends first, so not udpin:)")
    p.add_argument("--only", choices=(UP, DOWN),
                   help="faults on one direction only: up (GCS -> vehicle) or down (vehicle -> GCS)")
    p.add_argument("--max-gcs", type=_max_gcs, default=MAX_LEGS, metavar="N",
                   help=f"GCSs served at once, each with its own port to the vehicle; one more "
                        f"takes over the quietest one's port (default {MAX_LEGS})")
    p.add_argument("--duration", type=positive, metavar="S",
                   help="stop after S seconds (default: run until Ctrl-C)")
    p.add_argument("--capture", metavar="FILE.mcap",
                   help="record every frame, both directions, to an MCAP file")
    p.add_argument("--quiet", action="store_true",
                   help="print only the listening line and the counts at the end")
    add_fault_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    listen = parse_link_uri(args.listen, role="listen", option="--listen")
    forward_uri = parse_link_uri(args.forward, role="peer", option="--forward")
    if isinstance(forward_uri, UdpUri):
        forward: object = _vehicle_address(forward_uri)
        legs = args.max_gcs
    else:
        forward, legs = stream_peer(forward_uri), 1
    faults = fault_model(args)
    up = faults if args.only in (None, UP) else None
    down = (faults.copy() if faults is not None else None) if args.only in (None, DOWN) else None
    proxy = ChaosProxy(forward, up=up, down=down, seed=args.seed, max_legs=legs)
    clock = MonotonicClock()
    if _same_place(listen, forward_uri, forward):
        raise UsageError(f"--forward {args.forward!r} is the proxy's own --listen address")
    with UdpDriver(clock=clock, seed=args.seed) as driver:
        try:
            node = UdpProxy(driver, proxy, listen=listen.address if isinstance(listen, UdpUri) else listen,
                            forward_link=forward_uri)
        except UsageError as exc:
            raise UsageError(f"--listen: {exc}") from None
        where = "both directions" if args.only is None else f"{args.only}link only"
        with capture_to(proxy, args.capture):   # after the bind: a bad address leaves no file
            # Signals are caught before the listening line, so one sent on seeing it stops cleanly.
            try:
                with InterruptGuard():   # SIGTERM too stops it as Ctrl-C does
                    stream = driver.stream_of(node_front(node))
                    here = stream.uri if stream is not None else f"udp:{_host(node.address[0])}:{node.address[1]}"
                    there = f"udp:{_host(forward[0])}:{forward[1]}" if isinstance(forward, tuple) else str(forward_uri)
                    print(f"chaos proxy listening on {here}, forwarding to {there} "
                          f"(faults, {where}: {describe_faults(args)})", flush=True)
                    _serve(driver, node, clock, args)
            except KeyboardInterrupt:
                print("stopped", file=sys.stderr)
        _print_stats(proxy, driver, node)
    return 0


def _serve(driver: UdpDriver, node: UdpProxy, clock: MonotonicClock, args: argparse.Namespace) -> None:
    """Relay until --duration (or Ctrl-C), printing each new GCS as it first speaks."""
    end = None if args.duration is None else clock.now() + args.duration
    while end is None or clock.now() < end:
        step = 1.0 if end is None else max(0.0, min(1.0, end - clock.now()))
        driver.run_until(lambda: bool(node.events), timeout=step)
        while node.events:
            event = node.events.popleft()
            if not args.quiet:
                print(event, flush=True)


def _print_stats(proxy: ChaosProxy, driver: UdpDriver, node: UdpProxy) -> None:
    errors = {UP: 0, DOWN: 0}
    legs = set(node.leg_addresses)
    for (src, _dst), link in driver.stats.items():
        if link.errors:
            errors[UP if src in legs else DOWN] += link.errors
    for direction, label in ((UP, "gcs -> vehicle"), (DOWN, "vehicle -> gcs")):
        print(f"{direction:<4} {label}: {_counts(proxy.stats[direction])}"
              + (f", send errors {errors[direction]}" if errors[direction] else ""))
    extra = [f"{len(node.leg_addresses)} GCS port(s)"]
    if proxy.pending():
        extra.append(f"{proxy.pending()} delayed datagram(s) still in flight at the end")
    if proxy.stray:
        extra.append(f"{proxy.stray} datagram(s) from strangers ignored")
    if proxy.overflowed:
        extra.append(f"{proxy.overflowed} dropped because the delay queue was full")
    print("; ".join(extra), flush=True)


def _counts(s: LinkStats) -> str:
    return (f"in {s.sent}, out {s.delivered}, dropped {s.dropped}, duplicated {s.duplicated}, "
            f"reordered {s.reordered}, corrupted {s.corrupted}")


def _vehicle_address(uri: UdpUri) -> tuple[str, int]:
    """The vehicle's (ip, port) as its replies will show it, so they can be recognised.
    A host name resolves to its IPv4 address if it has one (as the vehicle command binds)."""
    try:
        ip = str(ipaddress.ip_address(uri.host))
    except ValueError:
        ip = _resolve(uri)
    if ipaddress.ip_address(ip).is_unspecified:
        raise UsageError(f"--forward: {str(uri)!r}: {ip} is not an address a vehicle listens at")
    return (ip, uri.port)


def _resolve(uri: UdpUri) -> str:
    last: Exception | None = None
    for family in (socket.AF_INET, socket.AF_UNSPEC):
        try:
            infos = socket.getaddrinfo(uri.host, uri.port, family, socket.SOCK_DGRAM)
        except (OSError, UnicodeError) as exc:
            last = exc
            continue
        if infos:
            return str(infos[0][4][0]).split("%")[0]
    raise UsageError(f"--forward: cannot resolve host {uri.host!r}: {last}")


def node_front(node: UdpProxy) -> object:
    """The proxy's listening node (for the driver's `stream_of`)."""
    return node.front


def _same_place(listen: object, forward_uri: object, forward: object) -> bool:
    """Would the proxy forward to itself? (UDP: the same host and port; a serial line: the same device)."""
    if isinstance(listen, UdpUri) and isinstance(forward, tuple):
        return listen.port == forward[1] and _same_host(listen.host, forward[0])
    device = getattr(listen, "device", None)
    return device is not None and device == getattr(forward_uri, "device", None)


def _same_host(host: str, ip: str) -> bool:
    if host == ip:
        return True
    try:
        return ipaddress.ip_address(host) == ipaddress.ip_address(ip)
    except ValueError:
        return host == "localhost" and ipaddress.ip_address(ip).is_loopback


def _max_gcs(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 1 <= value <= 1024:
        raise argparse.ArgumentTypeError(f"{text!r} is not in 1..1024")
    return value


def _host(host: str) -> str:
    return f"[{host}]" if ":" in host else host

