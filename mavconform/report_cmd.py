"""`mavconform report render RUN.json`: re-render the reports of an earlier run.

With no output option, writes all of them (JSON, JUnit, Markdown, HTML) next to RUN.json's
name in --dir (default: RUN.json's folder). A bad or foreign file gets one line naming it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from reference_impl.errors import UsageError


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


def render(args: argparse.Namespace) -> int:
    from reports import html_report, junit_xml, load_run, markdown_summary, write_reports
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
