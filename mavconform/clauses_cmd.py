"""`mavconform clauses`: list the clauses the suite decides (and the mutants that break them).

Each line: id, level, role, title, and where the requirement comes from. Filter with
--clauses (comma-separated globs) and --level. --role gcs lists the GCS side (MIS.G.*,
`mavconform run --role gcs`) instead of the vehicle's; --role msp an MSP flight controller's
waypoint store (MSP.*, `mavconform run --target builtin:msp|msp:...`). --mutants lists the
negative controls: reference vehicles with one behaviour broken, usable as targets
(`mutant:NAME`), or with --role gcs reference GCSs with one (`gcs-mutant:NAME`), with --role
msp MSP flight controllers with one (`msp-mutant:NAME`).
--coverage prints the spec-coverage map instead (docs/spec-coverage.md): every requirement
sentence of seed 000 and the clauses that check it, or why none does.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mavconform.conformance import catalogue
from mavconform.conformance.clause import Role
from mavconform.reference_impl.errors import UsageError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("clauses", help="list the clauses (or the mutant vehicles)",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--clauses", metavar="GLOB", help="comma-separated id globs, e.g. 'MIS.UP.*'")
    p.add_argument("--level", metavar="LEVELS", help="only these levels, e.g. MUST or SHOULD,MAY")
    p.add_argument("--role", choices=("vehicle", "gcs", "msp"), default="vehicle",
                   help="which side's clauses: vehicle (default), gcs (MIS.G.*) or msp (MSP.*: an MSP "
                        "flight controller)")
    p.add_argument("--requirement", action="store_true", help="print each requirement sentence too")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.add_argument("--mutants", action="store_true", help="list the mutant vehicles instead")
    p.add_argument("--coverage", action="store_true",
                   help="print the spec-coverage map (Markdown): each requirement sentence of seed 000 "
                        "and the clauses that check it, or why none does")
    p.add_argument("--output", metavar="FILE", help="with --coverage: write it here instead of stdout")
    p.set_defaults(run=run)


def _coverage(args: argparse.Namespace) -> int:
    from mavconform.conformance.spec_coverage import render_markdown
    if args.clauses or args.level or args.mutants or args.json or args.requirement or args.role != "vehicle":
        raise UsageError("--coverage: covers every clause; it takes no other option but --output")
    text = render_markdown()
    if not args.output:
        sys.stdout.write(text)
        return 0
    out = Path(args.output)
    if not out.parent.is_dir():
        raise UsageError(f"--output {args.output}: no such directory {str(out.parent)!r}")
    try:
        out.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UsageError(f"--output {args.output}: {exc.strerror or exc}") from None
    print(f"wrote {out}")
    return 0


def run(args: argparse.Namespace) -> int:
    if args.coverage:
        return _coverage(args)
    if args.output:
        raise UsageError("--output: only with --coverage")
    role = Role(args.role)
    chosen = catalogue.select(args.clauses, args.level, role=role)
    if args.mutants and role is not Role.VEHICLE:
        return _other_mutants(args, role, {c.id for c in chosen})
    if args.mutants:
        from mavconform.conformance.mutants import MUTANTS
        wanted = {c.id for c in chosen}
        # with no clause filter, also the mutants no clause catches (planted for the fuzzers)
        everything = args.clauses in (None, "*") and not args.level
        rows = [mu for mu in MUTANTS.values() if mu.breaks & wanted or (everything and not mu.breaks)]
        if args.json:
            print(json.dumps([{"name": mu.name, "description": mu.description,
                               "breaks": sorted(mu.breaks)} for mu in rows], indent=2))
            return 0
        for mu in rows:
            broken = ", ".join(sorted(mu.breaks)) or "no clause (a bug for the fuzzers or the fidelity survey to find)"
            print(f"mutant:{mu.name:<28} {mu.description}\n{'':<36} breaks {broken}")
        return 0
    if args.json:
        print(json.dumps([{"id": c.id, "level": c.level.value, "role": c.role.value, "title": c.title,
                           "source": c.source, "requirement": c.requirement} for c in chosen], indent=2))
        return 0
    for c in chosen:
        print(f"{c.id:<11} {c.level.value:<6} {c.role.value:<7} {c.title}  [{c.source}]")
        if args.requirement:
            print(f"{'':<27}\"{c.requirement}\"")
    print(f"{len(chosen)} clauses")
    return 0


def _other_mutants(args: argparse.Namespace, role: Role, wanted: set[str]) -> int:
    if role is Role.GCS:
        from mavconform.conformance.gcs.mutants import GCS_MUTANTS as mutants
        prefix = "gcs-mutant:"
    else:
        from mavconform.conformance.msp.mutants import MSP_MUTANTS as mutants
        prefix = "msp-mutant:"
    rows = [mu for mu in mutants.values() if mu.breaks & wanted]
    if args.json:
        print(json.dumps([{"name": mu.name, "description": mu.description,
                           "breaks": sorted(mu.breaks)} for mu in rows], indent=2))
        return 0
    for mu in rows:
        print(f"{prefix}{mu.name:<24} {mu.description}\n{'':<36} breaks {', '.join(sorted(mu.breaks))}")
    return 0
