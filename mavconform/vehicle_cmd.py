"""`mavconform vehicle`: serve the reference vehicle over UDP, TCP or a serial line for any GCS."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.authenticity import Roster, load_roster
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.net import MonotonicClock, UdpDriver, parse_udp_uri
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.net.uri import LISTEN_FORMS, UdpUri, parse_link_uri
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile
from mavconform.reference_impl.vehicle import VehicleNode
from mavconform.reference_impl.interrupts import InterruptGuard

from . import handover_cmd
from .options import (add_fault_options, capture_to, describe_faults, fault_model, mavlink_id, positive,
                      seconds_up_to, seq_number)

DESCRIPTION = """\
Serve the reference vehicle on UDP, TCP or a serial line (or a pseudo-terminal it makes)
until interrupted (or --duration): spec-exact by
default, or PX4-like / ArduPilot-like / your own with --profile (`mavconform profiles`
lists what each changes, with the VARIANTS.md row and source of every knob).
It sends HEARTBEAT at 1 Hz, serves mission / geofence / rally upload, download, clear and
set-current, streams MISSION_CURRENT, and flies the mission in real time after
MAV_CMD_MISSION_START (or at once with --autostart). Any GCS that talks to it is served.
With --operator-control it is also its own system manager (MAV_CMD_REQUEST_OPERATOR_CONTROL,
CONTROL_STATUS at 1 Hz): a GCS asks for control first and only that GCS may then change
the plans or send commands; others may still download and are refused with
MISSION_ACK DENIED / COMMAND_ACK NOT_IN_CONTROL. Control changes print as they happen.
With --signing-roster it knows its GCSs by their MAVLink 2 signing keys: each frame is
checked against the key of the GCS whose system id it carries, and dropped (and counted)
if it is unsigned, signed with another key or by a system not in the roster, or a replay;
what it sends to a GCS is signed with that GCS's key. A system not in the roster never
gains operator control, even with --accept-unsigned.
"""

EPILOG = """\
examples:
  mavconform vehicle --listen udp:127.0.0.1:14550
  mavconform vehicle --listen udpin:14550              # the same (udpin:PORT is on 127.0.0.1)
  mavconform vehicle --listen tcpin:5760               # one TCP GCS at a time, as ArduPilot SITL serves
  mavconform vehicle --listen serial:/dev/ttyUSB0:57600  # a GCS on a serial line (a radio, a USB cable)
  mavconform vehicle --listen pty:57600                # a new pseudo-terminal, paced at 57600 baud: a GCS
      # (or `mavconform run --target serial:/dev/pts/N:57600`) opens the device it prints
  mavconform vehicle --profile ardupilot               # home at seq 0, non-atomic upload, ...
  mavconform vehicle --profile my-fork.toml            # base = "px4" plus your overrides
  mavconform vehicle --listen udp:127.0.0.1:0 --loss 0.1 --reorder 0.05 --seed 7
  mavconform vehicle --connect udp:127.0.0.1:14551     # talk first to a GCS listening there
  mavconform vehicle --operator-control --owner-loss 3 # `mavconform gcs control request` first
  mavconform vehicle --handover delivery-flight        # a handover scenario's vehicle (`mavconform handover list`)
  mavconform vehicle --operator-control --signing-roster gcss.json
      # gcss.json: [{"sysid": 201, "name": "A", "key": "<64 hex digits>"},
      #             {"sysid": 202, "name": "B", "passphrase": "words only B knows"}]
      # then: mavconform gcs control request --system 201 --signing-key <A's 64 hex digits> ...
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("vehicle", help="serve the reference vehicle over UDP, TCP or a serial line",
                       description=DESCRIPTION, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--listen", default="udp:127.0.0.1:14550", metavar="URI",
                   help=f"where to listen: udp:HOST:PORT, {LISTEN_FORMS} (udp: and udpin: both "
                        "listen; port 0: any free port; a serial line is paced at its baud rate; "
                        "default %(default)s)")
    p.add_argument("--connect", metavar="URI",
                   help="also send to a GCS that listens at udp:HOST:PORT (as SITL does; with a UDP --listen)")
    p.add_argument("--profile", default="spec", metavar="NAME|FILE",
                   help=f"vehicle profile: {', '.join(BUILTIN_PROFILES)} or a profile TOML file "
                        "(default %(default)s)")
    p.add_argument("--mutant", metavar="NAME",
                   help="serve a mutant (a vehicle with one planted bug, `mavconform clauses --mutants`) "
                        "instead of a profile's vehicle: to try a GCS or a fuzz campaign on a known bug")
    p.add_argument("--system", type=mavlink_id, default=1, help="system id (default 1)")
    p.add_argument("--component", type=mavlink_id, default=1, help="component id (default 1)")
    p.add_argument("--capacity", type=seq_number, metavar="N",
                   help="most mission items stored; more gets MAV_MISSION_NO_SPACE (default: the profile's, 1000)")
    p.add_argument("--autostart", action="store_true", help="start flying as soon as a mission is accepted")
    p.add_argument("--single-peer", action="store_true",
                   help="bind the link to the first GCS address heard, as PX4 and ArduPilot SITL links are "
                        "(the px4 and ardupilot profiles model that in the suite; served here, any GCS may "
                        "connect unless this is given)")
    p.add_argument("--speed", type=positive, default=10.0, metavar="M/S", help="flight speed (default 10)")
    p.add_argument("--flight-speedup", type=positive, default=1.0, metavar="N",
                   help="fly N times faster than real, as SITL's --speedup: legs, climbs and descents; "
                        "holds, loiters and every protocol timer keep their real length (default 1)")
    p.add_argument("--duration", type=positive, metavar="S", help="stop after S seconds (default: run until Ctrl-C)")
    p.add_argument("--capture", metavar="FILE.mcap", help="record every datagram to an MCAP file")
    p.add_argument("--quiet", action="store_true", help="print only the listening line")
    p.add_argument("--operator-control", action="store_true",
                   help="be the system manager of operator control (development.xml 32100): only the GCS "
                        "in control may upload, clear, set the current item or send commands; while no GCS "
                        "is, none may (see --open-when-unowned)")
    p.add_argument("--owner-loss", type=seconds_up_to(3600), metavar="S",
                   help=f"with --operator-control: drop a GCS in control after S seconds without its HEARTBEAT "
                        f"(default {ManagerConfig().owner_loss_timeout:g}); the loss is announced in a STATUSTEXT")
    p.add_argument("--open-when-unowned", action="store_true",
                   help="with --operator-control: while no GCS is in control, let any GCS change the plans "
                        "(for GCSs that never ask for control)")
    p.add_argument("--signing-roster", metavar="FILE.json",
                   help="known GCSs and their MAVLink 2 signing keys, a JSON list of "
                        '{"sysid": N, "key": "64 hex digits" or "passphrase": "...", "name": "...", '
                        '"link_id": N}: every frame must be signed with the key of the GCS it claims '
                        "to be; frames to a GCS are signed with its key")
    p.add_argument("--accept-unsigned", action="store_true",
                   help="with --signing-roster: let unsigned frames through (a signed frame must "
                        "still check out; a system not in the roster still never gains control)")
    p.add_argument("--handover", metavar="SCENARIO",
                   help="be a handover scenario's vehicle (a .json/.yaml file or a shipped name, `mavconform "
                        "handover list`): its system manager, mission computer (coverage, parent, dwell, bound) "
                        "and GCS keys, its flight stored as the mission; handover events print as they happen")
    add_fault_options(p)
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    listen = parse_link_uri(args.listen, role="listen", option="--listen")
    connect = parse_udp_uri(args.connect, role="peer", option="--connect") if args.connect else None
    if connect is not None and not isinstance(listen, UdpUri):
        raise UsageError("--connect adds a UDP peer to a UDP --listen; a TCP or serial link has one peer")
    scenario = handover_cmd.vehicle_scenario(args) if args.handover else None
    profile = load_profile(args.profile)
    behaviour = profile.behaviour
    if args.capacity is not None:
        behaviour = dataclasses.replace(behaviour, capacity={**behaviour.capacity, MissionType.MISSION: args.capacity})
    roster = _roster(args)
    config = dataclasses.replace(profile.config, system=args.system, component=args.component,
                                 autostart=args.autostart, speed=args.speed, behaviour=behaviour,
                                 flight_speedup=args.flight_speedup, single_peer_link=args.single_peer,
                                 control=_control(args))
    if roster is not None:
        config = dataclasses.replace(config, roster=roster, require_signature=not args.accept_unsigned)
    if scenario is not None:
        config, handover_lines = handover_cmd.vehicle_for_scenario(scenario, config, accept_unsigned=args.accept_unsigned)
    faults = fault_model(args)
    clock = MonotonicClock()
    vehicle = _mutant(args.mutant, config, args.profile) if args.mutant else VehicleNode(config, wall_clock=clock.wall)
    if scenario is not None:
        handover_cmd.preload_flight(vehicle, scenario)
    with UdpDriver(clock=clock, seed=args.seed) as driver:
        peer, address = attach(driver, vehicle, listen, listen=True, outgoing=faults, incoming=faults)
        if peer is not None:   # a stream's one peer: heard from or not, it gets HEARTBEATs
            vehicle.endpoint.add_address(peer)
        if connect is not None:
            vehicle.endpoint.add_address(connect.address)
        stream = driver.stream_of(vehicle)
        where = f"udp:{address[0]}:{address[1]}" if stream is None else stream.uri
        with capture_to(driver, args.capture):   # after the bind: a bad address leaves no file
            print(f"reference vehicle {args.system}/{args.component} (profile {profile.name}) listening on "
                  f"{where} (faults: {describe_faults(args)})", flush=True)
            if config.control is not None and not args.quiet:
                unowned = "any GCS may" if config.control.open_when_unowned else "no GCS may"
                print(f"operator control on: until a GCS takes control {unowned} change the plans; "
                      f"a GCS in control is lost after {config.control.owner_loss_timeout:g} s without "
                      "its HEARTBEAT", flush=True)
            if roster is not None and not args.quiet:
                names = ", ".join(g.label for g in roster.gcss)
                unsigned = "accepted" if args.accept_unsigned else "dropped"
                print(f"signing: {len(roster.gcss)} GCSs known from {args.signing_roster} ({names}); "
                      f"unsigned frames {unsigned}", flush=True)
            if scenario is not None and not args.quiet:
                print("\n".join(handover_lines), flush=True)
            _serve(driver, vehicle, clock, args)
    return 0


def _roster(args: argparse.Namespace) -> Roster | None:
    """The --signing-roster file, checked before any socket is opened."""
    if args.signing_roster is None:
        if args.accept_unsigned and not args.handover:
            raise UsageError("--accept-unsigned needs --signing-roster (or --handover)")
        return None
    roster = load_roster(args.signing_roster)
    for i, gcs in enumerate(roster.gcss, 1):
        if gcs.sysid == args.system:
            raise UsageError(f"{args.signing_roster}: entry {i}: sysid {gcs.sysid} is the vehicle's own "
                             "(--system); the roster lists GCSs")
    return roster


def _control(args: argparse.Namespace) -> ManagerConfig | None:
    if not args.operator_control:
        for given, option in ((args.owner_loss is not None, "--owner-loss"),
                              (args.open_when_unowned, "--open-when-unowned")):
            if given:
                raise UsageError(f"{option} needs --operator-control")
        return None
    loss = ManagerConfig().owner_loss_timeout if args.owner_loss is None else args.owner_loss
    return ManagerConfig(owner_loss_timeout=loss, open_when_unowned=args.open_when_unowned)


def _mutant(name: str, config: Any, profile: str) -> VehicleNode:
    from mavconform.conformance.mutants import MUTANTS
    if profile != "spec":
        raise UsageError("--mutant and --profile: a mutant is the spec vehicle with one bug")
    if name not in MUTANTS:
        raise UsageError(f"--mutant: unknown mutant {name!r} (see `mavconform clauses --mutants`)")
    return MUTANTS[name].build(config)


def _serve(driver: UdpDriver, vehicle: VehicleNode, clock: MonotonicClock, args: argparse.Namespace) -> None:
    """Run until --duration (or Ctrl-C or SIGTERM), printing the vehicle's plan events as they happen."""
    end = None if args.duration is None else clock.now() + args.duration
    try:
        with InterruptGuard():   # SIGTERM too stops it as Ctrl-C does
            _relay(driver, vehicle, end, clock, args)
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)


def _relay(driver: UdpDriver, vehicle: VehicleNode, end: float | None, clock: MonotonicClock,
           args: argparse.Namespace) -> None:
    dropped = 0
    while end is None or clock.now() < end:
        step = 1.0 if end is None else max(0.0, min(1.0, end - clock.now()))
        driver.run_until(lambda: bool(vehicle.events), timeout=step)
        for event in vehicle.events:
            if not args.quiet:
                print(event, flush=True)
        vehicle.events.clear()
        dropped = _print_drops(vehicle, dropped, args)


def _print_drops(vehicle: VehicleNode, shown: int, args: argparse.Namespace) -> int:
    """At most once a step, a line when frames were dropped for their signature since the
    last one: the counts by reason and the latest drop (who it claimed to be, from where)."""
    endpoint = vehicle.endpoint
    total = endpoint.rejected_signatures
    if total != shown and not args.quiet and endpoint.rejected:
        reasons = ", ".join(f"{reason} {n}" for reason, n in sorted(endpoint.rejections.items()))
        frames = f"{total} frame{'s' if total != 1 else ''}"
        print(f"signing: {frames} dropped so far ({reasons}); last: {endpoint.rejected[-1]}", flush=True)
    return total
