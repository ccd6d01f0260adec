"""`mavconform fidelity`: what a vehicle keeps of what it is sent, cell by cell (issue 26)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from mavconform.conformance.fidelity.run import SCOPES, survey
from mavconform.conformance.fidelity.table import short, unlike
from mavconform.conformance.target_uri import FORMS, parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reports.write import write_reports

DESCRIPTION = """\
Upload each cell of the fidelity matrix, download it, and say what came back. The frame matrix:
every MAV_FRAME × each plan type's item kinds (mission waypoint; fence polygon vertex, circle,
return point; rally point). The command matrix: every mission command of upstream common.xml,
its nominal item and then, for a command the target takes, each param probed with values from
its definition (bounds and one step past them, enum values, NaN where upstream says what it
means, INT32_MAX where it means "no location", reserved params, a float's precision).
Each cell's class is judged by the rules alone: `refused:<MISSION_ACK result>`, `exact`,
`int_twin` (only the frame came back as its INT-encoding twin, 0<->5, 3<->6, 10<->11, as
upstream allows), or `changed:<field from->to>` with `(rule: ...)` when a documented rule
explains it (upstream's reserved params, or the profile's storage form, named by its id).
Beside it, `predicted`: what the target's profile (--profile, or the one its HEARTBEAT names)
says from its declared rules; a cell unlike its prediction is marked and fails the run (exit
1): either the vehicle changes something no rule says, or the profile lacks a rule. Cells of
one kind (or one command) go up in one upload where the target takes them all; a refused cell
is taken out and the rest go up again. The target's plans are read first and put back after.
Writes the usual reports to --report-dir: run.json (the matrix under `fidelity`, docs/fidelity.md
says the format), run.html (the matrices in colour, each cell linked to its exchange), run.md
(the matrices as Markdown tables to paste into an issue) and run.junit.xml.
"""


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fidelity", help="what a vehicle keeps of each frame and plan type it is sent",
                       description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--target", default="builtin:spec", metavar="URI", help=f"what to survey: {FORMS} "
                   "(default %(default)s)")
    p.add_argument("--profile", metavar="NAME|FILE",
                   help="what an external target is, when its HEARTBEAT cannot say: the profile whose rules predict "
                        "each cell (default: chosen from the HEARTBEAT)")
    p.add_argument("--matrix-scope", choices=SCOPES, default="frames",
                   help="which matrix: frames (every MAV_FRAME × plan type, 110 cells), commands (every mission "
                        "command × its params' probes, about 1,300 cells where every command is taken) or all "
                        "(default %(default)s)")
    p.add_argument("--report-dir", default="reports/fidelity", metavar="DIR",
                   help="where run.json, run.html, run.md and run.junit.xml go (default %(default)s)")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the summary")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    uri = parse_target(args.target).with_profile(args.profile)
    out = Path(args.report_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"cannot create report folder {str(out)!r}: {exc.strerror}") from None
    print(f"mavconform fidelity: {args.matrix_scope} matrix of {uri}", flush=True)

    def show(entry: dict) -> None:
        if not args.quiet:
            mark = "" if entry.get("as_predicted") is not False else f"   <- profile: {short(entry['predicted'])}"
            probe = f" {entry['probe']:<18}" if entry.get("probe") else ""
            print(f"  {entry['plan_type']:<8} frame {entry['frame']:>2} command {entry['command']:>5}{probe}  "
                  f"{short(entry['class'])}{mark}", flush=True)
    result = survey(uri, scope=args.matrix_scope, on_cell=show)
    doc = result.doc
    fid = doc["fidelity"]
    differ = unlike(fid["cells"])
    if differ or result.unresponsive:
        doc["summary"]["verdict"] = "fail"
    write_reports(doc, out)
    if result.unresponsive:
        print(f"mavconform fidelity: target unresponsive: {result.unresponsive}", file=sys.stderr)
        return 1
    counts: dict[str, int] = {}
    for e in fid["cells"]:
        kind = e["class"].split(":")[0]
        counts[kind] = counts.get(kind, 0) + 1
    print(f"\n{len(fid['cells'])} cells in {fid['uploads']} uploads: "
          + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
          + f"; profile {fid['profile']}: {len(differ)} unlike its prediction; restore: {doc['restore']['status']}")
    print(f"reports in {out}/ (run.json, run.html, run.md, run.junit.xml)")
    return 1 if differ else 0
