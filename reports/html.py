"""The HTML report: one self-contained file to attach to a CI run or mail to a vendor.

Inline CSS, inline SVG, no scripts and no external assets, so it opens anywhere, offline,
years later. The "only not passing" filter is CSS (`:has`); where that is unsupported the
page simply shows everything. Every string from the document goes through `html.escape`:
details and fields come from a target on the wire and may contain anything.
"""

from __future__ import annotations

import re
from html import escape
from typing import Any
from urllib.parse import quote

from mavconform.reports.run_document import PASS, outcome_counts
from mavconform.reports.sequence_svg import sequence_diagram
from mavconform.reports.text import clean, interruption, one_line, run_facts, verdict_headline

OUTCOME_COLOURS = {"pass": "#1a7f37", "fail": "#cf222e", "known-deviation": "#9a6700",
                   "not-applicable": "#6e7781", "skipped": "#57606a", "error": "#8250df"}

CSS = """
body { font: 15px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1200px;
       padding: 1em 2em; color: #1f2328; }
h1 { margin-bottom: .2em; } h2 { border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
.verdict { font-size: 1.6em; font-weight: 700; }
.verdict.pass { color: #1a7f37; } .verdict.fail { color: #cf222e; }
.verdict.interrupted { color: #9a6700; }
p.interrupted { background: #fff8c5; border: 1px solid #d4a72c; border-radius: 4px;
                padding: .5em 1em; font-weight: 600; }
table { border-collapse: collapse; margin: .5em 0; }
th, td { border: 1px solid #d0d7de; padding: .25em .6em; text-align: left; vertical-align: top; }
table.facts th { background: #f6f8fa; font-weight: 600; }
tr.group th { background: #eaeef2; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
.badge { display: inline-block; border-radius: 1em; padding: 0 .6em; color: #fff;
         font-size: .85em; font-weight: 600; white-space: nowrap; }
""" + "".join(f".badge.o-{name} {{ background: {colour}; }}\n"
              for name, colour in OUTCOME_COLOURS.items()) + """
code, .id { font-family: ui-monospace, monospace; }
blockquote { margin: .5em 0; padding: .3em 1em; border-left: 4px solid #d0d7de;
             background: #f6f8fa; }
blockquote cite { display: block; font-size: .85em; color: #57606a; }
.detail { white-space: pre-wrap; font-family: ui-monospace, monospace; background: #fff8c5;
          padding: .4em .8em; border-radius: 4px; }
section.clause { margin: 1.5em 0 2.5em; }
.diagram { overflow-x: auto; border: 1px solid #d0d7de; border-radius: 4px; }
svg.sequence { font: 11px ui-monospace, monospace; }
svg.sequence line.lifeline { stroke: #8c959f; stroke-dasharray: 4 3; }
svg.sequence rect.actor { fill: #eaeef2; stroke: #57606a; }
svg.sequence text.actor { text-anchor: middle; font-weight: 700; }
svg.sequence text.time { text-anchor: end; fill: #57606a; }
svg.sequence .arrow text { text-anchor: middle; }
svg.sequence .arrow.tx line { stroke: #0969da; stroke-width: 1.5; }
svg.sequence .arrow.tx polygon, svg.sequence .arrow.tx text { fill: #0969da; }
svg.sequence .arrow.rx line { stroke: #1a7f37; stroke-width: 1.5; }
svg.sequence .arrow.rx polygon, svg.sequence .arrow.rx text { fill: #1a7f37; }
svg.sequence .note rect { fill: #fff8c5; stroke: #d4a72c; }
svg.sequence .note text { text-anchor: middle; fill: #6e5700; }
body:has(#only-not-passing:checked) tr.o-pass { display: none; }
"""


def html_report(doc: dict[str, Any]) -> str:
    """The run document as one HTML page (UTF-8 text, no external references)."""
    summary, clauses = doc["summary"], doc["clauses"]
    verdict = summary["verdict"]
    target = one_line(doc["run"]["target"])
    headline = verdict_headline(verdict)
    out = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{escape(headline)}: mavconform against {escape(target)}</title>",
           f"<style>{CSS}</style>", "</head>", "<body>",
           f"<h1>mavconform against <code>{escape(target)}</code></h1>",
           f'<p class="verdict {escape(verdict)}">{headline} '
           f'<small>({summary["gating_failures"]} gating failure'
           f'{"" if summary["gating_failures"] == 1 else "s"})</small></p>']
    stopped = interruption(doc)
    if stopped is not None:
        out.append(f'<p class="interrupted">{escape(stopped)}</p>')
    out += _facts(doc)
    out += _counts(clauses)
    out += _gating(doc)
    out += _matrix(clauses)
    not_passing = [c for c in clauses if c["outcome"] != PASS]
    out.append(f"<h2>Clauses not passing ({len(not_passing)})</h2>")
    if not not_passing:
        out.append("<p>Every clause passed.</p>")
    for clause in not_passing:
        out += _finding(clause)
    passing = [c for c in clauses if c["outcome"] == PASS]
    if passing:
        out.append(f"<h2>Passing clauses ({len(passing)})</h2>")
        for clause in passing:
            out.append(f'<details id="{_anchor(clause)}"><summary>{_badge(PASS)} '
                       f'<span class="id">{escape(one_line(clause["id"]))}</span> '
                       f'{escape(one_line(clause["title"]))}</summary>')
            out += _requirement(clause)
            out.append(_diagram(clause))
            out.append("</details>")
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


def _facts(doc: dict[str, Any]) -> list[str]:
    rows = [f"<tr><th>{escape(label)}</th><td>{escape(value)}</td></tr>"
            for label, value in run_facts(doc)]
    if doc["capture"] is not None:
        capture = one_line(doc["capture"])
        rows.append(f'<tr><th>capture</th><td><a href="{escape(quote(capture))}">'
                    f"{escape(capture)}</a> (MCAP: every datagram, decoded; opens in "
                    f"Foxglove)</td></tr>")
    return ['<table class="facts">', *rows, "</table>"]


def _counts(clauses: list[dict[str, Any]]) -> list[str]:
    rows = [f'<tr><td>{_badge(outcome)}</td><td class="n">{count}</td></tr>'
            for outcome, count in outcome_counts(clauses).items()]
    return ["<h2>Outcomes</h2>", "<table>", *rows,
            f'<tr><th>total</th><td class="n">{len(clauses)}</td></tr>', "</table>"]


def _gating(doc: dict[str, Any]) -> list[str]:
    out = []
    titles = {c["id"]: c for c in doc["clauses"]}
    for key, heading in (("regressions", "Regressions against the baseline"),
                         ("fixed", "Fixed since the baseline")):
        ids = doc["gating"][key]
        if ids:
            out += [f"<h2>{heading} ({len(ids)})</h2>", "<ul>"]
            for clause_id in ids:
                clause = titles.get(clause_id)
                text = escape(one_line(clause_id))
                if clause is not None:
                    text = (f'<a href="#{_anchor(clause)}">{text}</a> '
                            f'{escape(one_line(clause["title"]))}')
                out.append(f"<li>{text}</li>")
            out.append("</ul>")
    return out


def _matrix(clauses: list[dict[str, Any]]) -> list[str]:
    groups: dict[str, list[dict[str, Any]]] = {}
    for clause in clauses:
        groups.setdefault(clause["group"], []).append(clause)
    out = ["<h2>Compliance matrix</h2>",
           '<p><label><input type="checkbox" id="only-not-passing"> '
           "show only clauses that did not pass</label></p>",
           '<table class="matrix">',
           "<thead><tr><th>clause</th><th>level</th><th>outcome</th><th>title</th></tr></thead>"]
    for group, members in groups.items():
        out.append(f'<tbody><tr class="group"><th colspan="4">{escape(one_line(group))} '
                   f"({len(members)})</th></tr>")
        for clause in members:
            out.append(f'<tr class="o-{escape(clause["outcome"])}">'
                       f'<td class="id"><a href="#{_anchor(clause)}">'
                       f'{escape(one_line(clause["id"]))}</a></td>'
                       f"<td>{escape(clause['level'])}</td><td>{_badge(clause['outcome'])}</td>"
                       f"<td>{escape(one_line(clause['title']))}</td></tr>")
        out.append("</tbody>")
    out.append("</table>")
    return out


def _finding(clause: dict[str, Any]) -> list[str]:
    gating = "fails the run" if clause["gating"] else "does not fail the run"
    out = [f'<section class="clause" id="{_anchor(clause)}">',
           f'<h3>{_badge(clause["outcome"])} <span class="id">{escape(one_line(clause["id"]))}'
           f'</span> {escape(one_line(clause["title"]))}</h3>',
           f"<p>{escape(clause['level'])}, role {escape(one_line(clause['role']))}, "
           f"{gating}, took {clause['duration_s']:.3f} s.</p>"]
    out += _requirement(clause)
    if clause["detail"]:
        out.append(f'<p class="detail">{escape(clean(clause["detail"]))}</p>')
    if clause["expectation"]:
        out.append(f"<p>Expected deviation: {escape(clean(clause['expectation']))}</p>")
    out += [_diagram(clause), "</section>"]
    return out


def _requirement(clause: dict[str, Any]) -> list[str]:
    return [f"<blockquote><p>“{escape(clean(clause['requirement']))}”</p>"
            f"<cite>{escape(one_line(clause['source']))}</cite></blockquote>"]


def _diagram(clause: dict[str, Any]) -> str:
    return f'<div class="diagram">{sequence_diagram(clause["exchange"])}</div>'


def _badge(outcome: str) -> str:
    return f'<span class="badge o-{escape(outcome)}">{escape(outcome)}</span>'


def _anchor(clause: dict[str, Any]) -> str:
    """A fragment id from the clause id (letters, digits, . _ - kept; each id is unique)."""
    return "clause-" + re.sub(r"[^A-Za-z0-9._-]", "_", clause["id"])

