"""`mavconform fault-table`: how the reference GCS copes with each vehicle profile and with
QGroundControl's MockLink failure modes, as a Markdown (or JSON) report.

Runs in virtual time (a second or so of wall time), deterministic: the same options give the
same bytes, so CI regenerates docs/fault-tolerance.md and compares.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.interop import report
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile

DESCRIPTION = """\
The reference GCS against vehicle profiles, in virtual time:
  1. a round trip (upload, download, set-current, clear) of mission, fence and rally plans
     under loss, duplication and reordering, with the adaptations the GCS used;
  2. every QGroundControl MockLink mission failure mode (no response to request list, error
     ACK on request 1, missing final ACK, ...) injected in front of each profile's vehicle:
     does the GCS recover, or fail cleanly (one result, both ends idle, plan untouched unless
     it said the outcome is unknown), and after how many virtual seconds;
  3. the catalogue of adaptations (what each does, where it comes from).
Exit 0 when every round trip succeeded and no cell failed uncleanly, 1 otherwise, 2 for a
usage mistake.
"""


def default_profiles() -> list:
    """Every builtin profile the reference GCS can drive: a vehicle that ignores the _INT mission
    messages (inav) waits for the GCS's fallback to MISSION_ITEM / MISSION_REQUEST."""
    return [p for p in (load_profile(name) for name in BUILTIN_PROFILES) if not p.int_messages_ignored]


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fault-table", help="GCS interop and MockLink fault-tolerance report",
                       description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--profile", action="append", metavar="NAME|FILE", dest="profiles",
                   help=f"a vehicle profile (builtin: {', '.join(BUILTIN_PROFILES)}; or a profile "
                        "file); repeat for several (default: every builtin one the reference GCS can "
                        "drive: not inav, which ignores the _INT mission messages)")
    p.add_argument("--format", choices=("md", "json"), default="md", help="output format (default md)")
    p.add_argument("--output", metavar="FILE", help="write the report here instead of stdout")
    p.add_argument("--seed", type=int, default=0, help="seed of the virtual networks (default 0)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    profiles = ([load_profile(name) for name in args.profiles] if args.profiles
                else default_profiles())
    if len({p.name for p in profiles}) != len(profiles):
        raise UsageError("--profile: the same profile is named twice")
    out = Path(args.output) if args.output else None
    if out is not None and not out.parent.is_dir():
        raise UsageError(f"--output {args.output}: no such directory {str(out.parent)!r}")
    result = report.run(profiles, seed=args.seed)
    text = report.render_markdown(result) if args.format == "md" else report.render_json(result)
    if out is None:
        sys.stdout.write(text)
    else:
        try:
            out.write_text(text)
        except OSError as exc:
            raise UsageError(f"--output {args.output}: {exc.strerror or exc}") from None
        print(f"wrote {out}")
    for trip in result.trips:
        for step in trip.steps:
            if not step.ok:
                print(f"FAIL round trip {trip.profile}: {step.what}: {step.problem}", file=sys.stderr)
    for cell in result.table.unclean:
        print(f"FAIL {cell.profile} / {cell.mode}: {cell.text}", file=sys.stderr)
    return 0 if result.ok else 1
