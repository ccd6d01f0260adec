"""`mavconform report render RUN.json`: re-render the reports of an earlier run.
`mavconform report expectations RUN.json`: draft an expectations file from a run.
`mavconform report diff A.json B.json`: what differs between two runs.

render: with no output option, writes all of them (JSON, JUnit, Markdown, HTML) next to
RUN.json's name in --dir (default: RUN.json's folder).
expectations: one [[deviation]] per clause that failed (or was a known deviation), naming
the failure it excuses (`observed`, the detail with its numbers as `*`), the run's verdict
as `evidence`, and `seen_on`. Reason and variant are taken from --base where it lists the
clause; any other entry says it is unconfirmed: read each against the autopilot's source
before you keep it. A bad or foreign file gets one line naming it.
diff: one line per clause whose outcome changed and per fidelity cell whose class changed (or
that one run lacks), details and timings left out; exit 0 when nothing differs, 1 otherwise.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from mavconform.reference_impl.errors import UsageError


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="work with the reports of an earlier run",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    rsub = p.add_subparsers(dest="report_command", metavar="ACTION", required=True,
                            parser_class=type(p))
    r = rsub.add_parser("render", help="re-render reports from a run.json", description=__doc__,
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    r.add_argument("run_json", metavar="RUN.json")
    r.add_argument("--html", metavar="OUT", help="write the HTML report to OUT")
    r.add_argument("--junit", metavar="OUT", help="write the JUnit XML to OUT")
    r.add_argument("--markdown", metavar="OUT", help="write the Markdown summary to OUT")
    r.add_argument("--dir", metavar="DIR", help="write every report into DIR")
    r.set_defaults(run=render)
    e = rsub.add_parser("expectations", help="draft an expectations file from a run.json",
                        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("run_json", metavar="RUN.json")
    e.add_argument("--base", metavar="NAME|FILE",
                   help="an expectations file (or bundled name) to take reasons and variants from")
    e.add_argument("--seen-on", metavar="TEXT", default="",
                   help="the target the run was made on, e.g. 'PX4 v1.16.0 SITL (SIH), 2026-11-23'")
    e.add_argument("--output", metavar="FILE", help="write it to FILE (default: standard output)")
    e.set_defaults(run=draft_expectations)
    d = rsub.add_parser("diff", help="what differs between two run.json files (clauses, fidelity cells)",
                        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    d.add_argument("a", metavar="A.json")
    d.add_argument("b", metavar="B.json")
    d.set_defaults(run=diff)


def diff(args: argparse.Namespace) -> int:
    from mavconform.reports import load_run
    from mavconform.reports.diff import differences
    lines = differences(load_run(args.a), load_run(args.b))
    for line in lines:
        print(line)
    print(f"{len(lines)} difference(s) between {args.a} and {args.b}")
    return 1 if lines else 0


def render(args: argparse.Namespace) -> int:
    from mavconform.reports import html_report, junit_xml, load_run, markdown_summary, write_reports
    doc = load_run(args.run_json)
    singles = [(args.html, html_report), (args.junit, junit_xml), (args.markdown, markdown_summary)]
    if not any(path for path, _ in singles) or args.dir:
        out = Path(args.dir) if args.dir else Path(args.run_json).parent
        written = write_reports(doc, out, basename=Path(args.run_json).stem)
        for path in written.values():
            print(path)
    for path, render_fn in singles:
        if path:
            try:
                Path(path).write_text(render_fn(doc), encoding="utf-8")
            except OSError as exc:
                raise UsageError(f"cannot write {path!r}: {exc.strerror}") from None
            print(path)
    return 0


UNCONFIRMED = "unconfirmed: read this failure against the autopilot's source before keeping it"


def draft_expectations(args: argparse.Namespace) -> int:
    import json

    from mavconform.conformance import expectations
    from mavconform.reports import load_run
    from mavconform.reports.run_document import clause_detail, run_facts
    doc = load_run(args.run_json)
    base = expectations.load(args.base) if args.base else expectations.Expectations()
    base.identify(doc["identity"])   # the base's entries for the run's vehicle type
    seen_on = args.seen_on.strip() or f"{doc['run']['target']}, {run_facts(doc)['started'][:10]}"
    out = [f"description = {json.dumps(f'Clauses {seen_on} fails, drafted from {Path(args.run_json).name}')}"]
    for clause in doc["clauses"]:
        if clause["outcome"] not in ("fail", "known-deviation"):
            continue
        known = base.get(clause["id"])
        detail = clause_detail(doc, clause)   # as the run printed it: with its measured numbers
        if detail.startswith(expectations.OTHER_FAILURE_PREFIX):
            detail = detail.split("): ", 1)[-1]
        entry = {"clause": clause["id"], "variant": known.variant if known else "",
                 "reason": known.reason if known else UNCONFIRMED,
                 "observed": expectations.observed_pattern(detail), "evidence": detail, "seen_on": seen_on,
                 "vehicles": list(known.vehicles) if known else []}
        out.append("[[deviation]]\n" + "\n".join(f"{k} = {json.dumps(v)}" for k, v in entry.items() if v))
    text = "\n\n".join(out) + "\n"
    if not args.output:
        print(text, end="")
        return 0
    try:
        Path(args.output).write_text(text, encoding="utf-8")
    except OSError as exc:
        raise UsageError(f"cannot write {args.output!r}: {exc.strerror}") from None
    print(args.output)
    return 0
