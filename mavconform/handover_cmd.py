"""`mavconform handover`: fly a handover scenario in virtual time and report it.

`handover run SCENARIO` builds the scenario's vehicle and ground stations
(reference_impl/handover/scenario_run.py), flies the flight to its end and writes handover.json
(the timeline), handover.html and handover.mcap. `handover list` names the shipped scenarios.
`scenario_argument` and `vehicle_for_scenario` serve `mavconform vehicle --handover` too.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.scenario import Scenario, load_scenario, scenario_path, shipped_scenarios
from mavconform.reference_impl.handover.scenario_fleet import flight_items, vehicle_config
from mavconform.reference_impl.net import McapCapture

DEFAULT_REPORT_DIR = "reports/handover"
SEED_LIMIT = 2**64
EXIT_OK, EXIT_FAIL = 0, 1

DESCRIPTION = """\
Fly an authority-handover scenario in virtual time: the reference vehicle with its system
manager, mission computer and the GCSs' signing keys, one reference GCS per scenario GCS with
its handover agent, each on a link with the scenario's faults. The parent GCS takes control,
uploads the flight and starts it; the run goes on until the flight ends (at most
timeouts.max_duration_s of virtual time). Writes handover.json (the timeline), handover.html
(map, handovers, owner per segment, each handover's messages) and handover.mcap (every frame,
markers at each handover) to --report-dir. Exit 0: the flight ended and every handover
COMPLETED; 1: a handover ABORTED or UNCONFIRMED, or the flight did not end (the lines say
which); 2: a usage mistake (the scenario file names the field)."""

EPILOG = """\
scenarios: a .json / .yaml file (docs/handover-scenarios.md), or a shipped one by name:
  {names}
examples:
  mavconform handover run delivery-flight
  mavconform handover run my-scenario.yaml --seed 7 --report-dir out/
  mavconform vehicle --handover delivery-flight        # the same vehicle over UDP, for real GCSs
"""


def scenario_argument(text: str) -> Scenario:
    """A scenario file, or a shipped scenario's name; a ScenarioError (exit 2) otherwise."""
    return load_scenario(scenario_path(text))


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"{text!r} is outside 0..2^64-1")
    return value


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("handover", help="fly an authority-handover scenario in virtual time",
                       description="Authority handover between ground stations (seed 003): scenarios.")
    commands = p.add_subparsers(dest="handover_command", metavar="COMMAND", required=True,
                                parser_class=type(p))
    run = commands.add_parser("run", help="fly a scenario in virtual time and write its reports",
                              description=DESCRIPTION,
                              epilog=EPILOG.format(names=", ".join(shipped_scenarios())),
                              formatter_class=argparse.RawDescriptionHelpFormatter)
    run.add_argument("scenario", metavar="SCENARIO", help="scenario file (.json, .yaml) or a shipped scenario's name")
    run.add_argument("--report-dir", default=DEFAULT_REPORT_DIR, metavar="DIR",
                     help="where handover.json, handover.html and handover.mcap go (default %(default)s)")
    run.add_argument("--seed", type=_seed, metavar="N", help="the link faults' seed (default: the scenario's)")
    run.add_argument("-q", "--quiet", action="store_true", help="print only the handovers, owners and problems")
    run.set_defaults(run=run_command)
    listing = commands.add_parser("list", help="the shipped scenarios")
    listing.set_defaults(run=list_command)


def list_command(args: argparse.Namespace) -> int:
    for name, path in shipped_scenarios().items():
        print(f"{name:28s} {load_scenario(path).name}")
    return EXIT_OK


def run_command(args: argparse.Namespace) -> int:
    from mavconform.reference_impl.handover.scenario_run import run_scenario
    from mavconform.reports.handover_report import console_lines, timeline, write_handover_reports

    scenario = scenario_argument(args.scenario)
    vehicle_config(scenario)             # its checks (signing all or none) before any file is written
    folder = Path(args.report_dir)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise UsageError(f"{args.report_dir}: cannot create folder: {error.strerror or error}") from None
    with McapCapture(folder / "handover.mcap") as capture:
        run = run_scenario(scenario, seed=args.seed, capture=capture)
    doc = timeline(run)
    paths = write_handover_reports(doc, scenario, folder)
    for line in console_lines(doc, quiet=args.quiet):
        print(line)
    if not args.quiet:
        print(f"reports: {paths['json']}, {paths['html']}, {folder / 'handover.mcap'}")
    sys.stdout.flush()
    return EXIT_OK if doc["summary"]["verdict"] == "pass" else EXIT_FAIL


# --- mavconform vehicle --handover SCENARIO ------------------------------------------------------
def vehicle_for_scenario(scenario: Scenario, base: Any, *, accept_unsigned: bool = False) -> tuple[Any, list[str]]:
    """`base` (the profile's VehicleConfig) with the scenario's system id, home, speed, system
    manager, mission computer and roster; and the lines saying what it runs."""
    own = vehicle_config(scenario)
    if accept_unsigned and own.roster is None:
        raise UsageError(f"--accept-unsigned: the scenario {scenario.source or scenario.name} gives its GCSs no "
                         "signing keys, so nothing is signed or checked: leave the option out")
    config = dataclasses.replace(base, system=own.system, home=own.home, speed=own.speed, control=own.control,
                                 handover=own.handover, roster=own.roster, battery=own.battery,
                                 require_signature=own.require_signature and not accept_unsigned)
    t = scenario.timeouts
    gcss = "; ".join(f"{g.name} system {g.sysid}" + (" (parent)" if g.name == scenario.parent else "")
                     + (f", key {_fingerprint(g.signing.secret)}" if g.signing is not None else ", unsigned")
                     for g in scenario.gcs)
    signing = ("no GCS signs" if own.roster is None else
               "unsigned frames accepted" if accept_unsigned else "every frame must carry its GCS's signature")
    lines = [f"handover: scenario {scenario.name!r}, region method {scenario.region_method.value}; GCSs: {gcss}",
             f"handover: dwell {t.dwell_s:g} s, handover bound {t.handover_bound_s:g} s, commander lost after "
             f"{t.loss_timeout_s:g} s without its HEARTBEAT; {signing}",
             f"handover: the flight ({len(scenario.flight.waypoints)} waypoints, "
             f"{scenario.flight.length_m() / 1000:.1f} km at {scenario.flight.speed_m_s:g} m/s) is the stored mission: "
             f"GCS {scenario.parent} takes control and starts it (MAV_CMD_MISSION_START); the scenario's link "
             f"faults are not applied over UDP (use --loss ...)"]
    return config, lines


def preload_flight(vehicle: Any, scenario: Scenario) -> None:
    """Store the scenario's flight as the vehicle's mission, as if the parent had uploaded it."""
    from mavconform.reference_impl.mission.items import MissionType
    vehicle.server.store.commit(MissionType.MISSION, flight_items(scenario))


def _fingerprint(secret: bytes) -> str:
    import hashlib
    return hashlib.sha256(secret).hexdigest()[:8]


def vehicle_scenario(args: argparse.Namespace) -> Scenario:
    """`vehicle --handover SCENARIO`: the scenario, after refusing the options it sets itself.
    The scenario's vehicle system id becomes --system (1, the default, or the same id)."""
    for given, option, why in ((args.mutant, "--mutant", "a mutant is the plain spec vehicle"),
                               (args.signing_roster, "--signing-roster", "the scenario's GCS keys are the roster"),
                               (args.owner_loss is not None, "--owner-loss", "the scenario's timeouts.loss_timeout_s"),
                               (args.open_when_unowned, "--open-when-unowned",
                                "a handover vehicle takes commands from the GCS in control only")):
        if given:
            raise UsageError(f"{option} and --handover: {why}")
    scenario = scenario_argument(args.handover)
    if args.system not in (1, scenario.vehicle_sysid):
        raise UsageError(f"--system {args.system}: the scenario's vehicle is system {scenario.vehicle_sysid}")
    args.system = scenario.vehicle_sysid
    return scenario
