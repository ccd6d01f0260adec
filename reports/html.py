"""The HTML report: one self-contained file to attach to a CI run or mail to a vendor.

Inline CSS, inline SVG, no scripts and no external assets, so it opens anywhere, offline,
years later. What a reader opens it for comes first, in reports/reading_order.py's order:
right under the verdict, what fails the run (a red box only when something does), each
clause with its requirement, its verdict and its exchange, the deciding message highlighted;
then the known deviations, each with what excuses it (folded); then what else did not pass;
then the not-applicable and skipped clauses, one folded line per reason. The run's facts and
the full matrix follow. The "only not passing" filter is CSS (`:has`); where that is
unsupported the page simply shows everything. Every string from the document goes through
`html.escape`: details and fields come from a target on the wire and may contain anything.
Times and durations are read through run_document's accessors, wherever the document keeps them.
"""

from __future__ import annotations

import os
import re
from html import escape
from pathlib import Path
from typing import Any
from urllib.parse import quote

from mavconform.conformance.fidelity.table import unlike
from mavconform.reports import run_document as rd
from mavconform.reports.deciding import deciding_event, recorded_event
from mavconform.reports.fidelity_html import fidelity_sections
from mavconform.reports.reading_order import group_title, reading_order
from mavconform.reports.run_document import OUTCOMES, PASS, outcome_counts
from mavconform.reports.sequence_svg import sequence_diagram
from mavconform.reports.text import (clean, dropped_text, flight_endings, identity_text, interruption, link_text,
                                     one_line, safety_alarm, seconds, value_text, verdict_headline)

OUTCOME_COLOURS = {"pass": "#1a7f37", "fail": "#cf222e", "known-deviation": "#9a6700",
                   "not-applicable": "#6e7781", "skipped": "#57606a", "error": "#8250df"}
INDEX_DETAIL_CHARS = 160   # a verdict in the "What failed" list; its section has all of it

CSS = """
body { font: 15px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1200px;
       padding: 1em 2em; color: #1f2328; }
h1 { margin-bottom: .2em; } h2 { border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
.verdict { font-size: 1.6em; font-weight: 700; margin: .2em 0; }
.verdict.pass { color: #1a7f37; } .verdict.fail { color: #cf222e; }
.verdict.interrupted { color: #9a6700; }
p.interrupted { background: #fff8c5; border: 1px solid #d4a72c; border-radius: 4px;
                padding: .5em 1em; font-weight: 600; }
p.safety { background: #ffebe9; border: 2px solid #cf222e; border-radius: 4px;
           padding: .5em 1em; font-weight: 700; color: #82071e; }
p.tally { color: #57606a; margin-top: 0; }
table { border-collapse: collapse; margin: .5em 0; }
th, td { border: 1px solid #d0d7de; padding: .25em .6em; text-align: left; vertical-align: top; }
table.facts th { background: #f6f8fa; font-weight: 600; }
tr.group th { background: #eaeef2; }
td.n { text-align: right; font-variant-numeric: tabular-nums; }
.badge { display: inline-block; border-radius: 1em; padding: 0 .6em; color: #fff;
         font-size: .85em; font-weight: 600; white-space: nowrap; }
""" + "".join(f".badge.o-{name} {{ background: {colour}; }}\n"
              for name, colour in OUTCOME_COLOURS.items()) + """
.badge.none { background: #8c959f; }
code, .id { font-family: ui-monospace, monospace; }
section#what-failed { border: 2px solid #cf222e; border-radius: 6px; padding: 0 1em 1em;
                      margin: 1em 0 2em; }
section#what-failed.none { border-color: #1a7f37; }
section#deviations { border: 2px solid #d4a72c; border-radius: 6px; padding: 0 1em 1em; margin: 1em 0 2em; }
section#not-gating { border: 1px solid #d0d7de; border-radius: 6px; padding: 0 1em 1em; margin: 1em 0 2em; }
details.fold { margin: .3em 0; } details.fold > summary { cursor: pointer; }
details.fold > summary .why { color: #57606a; font-size: .9em; display: block; margin-left: 1.5em; }
details.group > summary { color: #57606a; }
p.members { font-size: .9em; }
ol.failed-index { padding-left: 1.5em; } ol.failed-index li { margin: .2em 0; }
ol.failed-index .why { color: #57606a; font-size: .9em; display: block; }
blockquote { margin: .5em 0; padding: .3em 1em; border-left: 4px solid #d0d7de;
             background: #f6f8fa; }
blockquote cite { display: block; font-size: .85em; color: #57606a; }
.detail { white-space: pre-wrap; font-family: ui-monospace, monospace; background: #fff8c5;
          padding: .4em .8em; border-radius: 4px; }
section.clause { margin: 1.5em 0 2.5em; border-top: 1px solid #d0d7de; }
.diagram { overflow-x: auto; border: 1px solid #d0d7de; border-radius: 4px; }
svg.sequence { font: 11px ui-monospace, monospace; display: block; }
svg.sequence line.lifeline { stroke: #8c959f; stroke-dasharray: 4 3; }
svg.sequence rect.actor { fill: #eaeef2; stroke: #57606a; }
svg.sequence rect.actor.target { fill: #ddf4ff; stroke: #0969da; }
svg.sequence text.actor { text-anchor: middle; font-weight: 700; }
svg.sequence text.time { text-anchor: end; fill: #57606a; }
svg.sequence tspan.msg { font-weight: 700; }
svg.sequence .arrow.tx line { stroke: #0969da; stroke-width: 1.5; }
svg.sequence .arrow.tx polygon, svg.sequence .arrow.tx text { fill: #0969da; }
svg.sequence .arrow.rx line { stroke: #1a7f37; stroke-width: 1.5; }
svg.sequence .arrow.rx polygon, svg.sequence .arrow.rx text { fill: #1a7f37; }
svg.sequence .arrow.decided line { stroke-width: 3; }
svg.sequence .note rect { fill: #fff8c5; stroke: #d4a72c; }
svg.sequence .note text { fill: #6e5700; }
svg.sequence .note.decided rect { stroke: #cf222e; stroke-width: 2; }
svg.sequence rect.decided-band { fill: #ffebe9; }
svg.sequence text.time.decided-mark { fill: #cf222e; font-weight: 700; }
p.decided-key { font-size: .85em; color: #57606a; margin: .2em 0 0; }
p.decided-key b { color: #cf222e; }
body:has(#only-not-passing:checked) tr.o-pass { display: none; }
"""


def html_report(doc: dict[str, Any], *, folder: str | Path | None = None) -> str:
    """The run document as one HTML page (UTF-8 text, no external references). `folder`:
    where the page will be written, so the capture link is relative to it."""
    summary, clauses = doc["summary"], doc["clauses"]
    verdict = summary["verdict"]
    target = one_line(doc["run"]["target"])
    headline = verdict_headline(verdict)
    fidelity = doc.get("fidelity")
    out = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{escape(headline)}: mavconform against {escape(target)}</title>",
           f"<style>{CSS}</style>", "</head>", "<body>",
           f"<h1>mavconform against <code>{escape(target)}</code></h1>",
           f'<p class="verdict {escape(verdict)}">{headline} <small>({_why_verdict(doc)})</small></p>']
    alarm = safety_alarm(doc)
    if alarm is not None:
        out.append(f'<p class="safety">⚠️ {escape(alarm)}</p>')
    stopped = interruption(doc)
    if stopped is not None:
        out.append(f'<p class="interrupted">{escape(stopped)}</p>')
    if fidelity is None:
        out.append(_tally(clauses))
        out += _what_failed(doc, stopped is not None)
        out += _gating(doc)
    out += ["<h2>Run</h2>", *_facts(doc, folder)]
    if fidelity is None:
        out += [*_counts(clauses), *_matrix(clauses)]
    else:
        out += fidelity_sections(doc)
    passing = [c for c in clauses if c["outcome"] == PASS]
    if passing:
        out.append(f"<h2>Passing clauses ({len(passing)})</h2>")
        for clause in passing:
            out.append(f'<details id="{_anchor(clause)}"><summary>{_badge(PASS)} '
                       f'<span class="id">{escape(one_line(clause["id"]))}</span> '
                       f'{escape(one_line(clause["title"]))}</summary>')
            out += _requirement(clause)
            out.append(_diagram(doc, clause))
            out.append("</details>")
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


def _why_verdict(doc: dict[str, Any]) -> str:
    if "fidelity" in doc:
        n = len(unlike(doc["fidelity"]["cells"]))
        return f"{n} fidelity cell{'' if n == 1 else 's'} unlike the profile's prediction"
    n = doc["summary"]["gating_failures"]
    return f"{n} gating failure{'' if n == 1 else 's'}"


def not_passing(clauses: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The clauses listed above the run's facts, in reading order (reports/reading_order.py)."""
    return reading_order({"clauses": clauses, "volatile": {}}).listed


def _tally(clauses: list[dict[str, Any]]) -> str:
    counts = [f"{n} {outcome}" for outcome, n in outcome_counts(clauses).items() if n]
    return f'<p class="tally">{len(clauses)} clauses: {escape(", ".join(counts) or "none")}</p>'


def _what_failed(doc: dict[str, Any], interrupted: bool) -> list[str]:
    """What fails the run (red, only if anything does), the known deviations, what else did
    not pass, and the not-applicable and skipped clauses folded in groups by reason."""
    order = reading_order(doc)
    if order.failing:
        n = len(order.failing)
        out = ['<section id="what-failed">', f"<h2>Fails the run ({n})</h2>",
               f"<p>{_clauses(n)} fail{'s' if n == 1 else ''} the run.</p>", *_index(doc, order.failing)]
        for clause in order.failing:
            out += _finding(doc, clause)
        out.append("</section>")
    else:
        said = ("Nothing failed before the run was interrupted." if interrupted
                else "Every clause passed." if not order.listed
                else "No clause fails the run; what did not pass is below, each with why it does not.")
        out = ['<section id="what-failed" class="none">', "<h2>Nothing fails the run</h2>",
               f"<p>{said}</p>", "</section>"]
    if order.deviations:
        n = len(order.deviations)
        out += ['<section id="deviations">', f"<h2>Known deviations ({n})</h2>",
                f"<p>{_clauses(n)} behaved as the expectations file says this target does; each "
                "names what excuses it. Open one for its requirement and exchange.</p>"]
        for clause in order.deviations:
            excuse = clean(clause["expectation"]) if clause["expectation"] else "no reason given"
            out.append(f'<details class="fold"><summary>{_badge(clause["outcome"])} '
                       f'<span class="id">{escape(one_line(clause["id"]))}</span> {escape(clause["level"])} '
                       f'{escape(one_line(clause["title"]))}<span class="why">excused: {escape(excuse)}</span>'
                       "</summary>")
            out += _finding(doc, clause)
            out.append("</details>")
        out.append("</section>")
    if order.other:
        n = len(order.other)
        out += ['<section id="not-gating">', f"<h2>Did not pass, does not fail the run ({n})</h2>",
                *_index(doc, order.other)]
        for clause in order.other:
            out += _finding(doc, clause)
        out.append("</section>")
    if order.groups:
        n = sum(len(g.clauses) for g in order.groups)
        out += ['<section id="not-applicable">', f"<h2>Not applicable or skipped ({n})</h2>"]
        for group in order.groups:
            out.append(f'<details class="fold group"><summary>{_badge(group.outcome)} '
                       f"{escape(clean(group_title(group)))}</summary>")
            out.append('<p class="members">' + ", ".join(
                f'<a class="id" href="#{_anchor(c)}">{escape(one_line(c["id"]))}</a>' for c in group.clauses) + "</p>")
            for clause in group.clauses:
                out += _finding(doc, clause)
            out.append("</details>")
        out.append("</section>")
    return out


def _index(doc: dict[str, Any], clauses: list[dict[str, Any]]) -> list[str]:
    """One line per clause, linking to its section: badge, id, level, title and the verdict."""
    out = ['<ol class="failed-index">']
    for clause in clauses:
        why = one_line(rd.clause_detail(doc, clause), INDEX_DETAIL_CHARS)
        out.append(f'<li>{_badge(clause["outcome"])} <a class="id" href="#{_anchor(clause)}">'
                   f'{escape(one_line(clause["id"]))}</a> {escape(clause["level"])} '
                   f'{escape(one_line(clause["title"]))}'
                   + (f'<span class="why">{escape(why)}</span>' if why else "") + "</li>")
    out.append("</ol>")
    return out


def _clauses(n: int, more: str = "") -> str:
    return f"{n} {more}clause{'' if n == 1 else 's'}"


def _facts(doc: dict[str, Any], folder: str | Path | None) -> list[str]:
    rows = [f"<tr><th>{escape(label)}</th><td>{escape(value)}</td></tr>"
            for label, value in _fact_rows(doc)]
    if doc["capture"] is not None:
        capture = one_line(doc["capture"])
        href = _capture_href(capture, folder)
        rows.append(f'<tr><th>capture</th><td><a href="{escape(quote(href))}">'
                    f"{escape(capture)}</a> (MCAP: every datagram, decoded; opens in "
                    f"Foxglove)</td></tr>")
    return ['<table class="facts">', *rows, "</table>"]


# run keys shown by name (the volatile ones come from run_document.run_facts)
_RUN_LABELS = {"seed": "seed", "time_scale": "time scale", "strict": "strict",
               "clauses": "clauses selected", "expectations": "expectations file",
               "baseline": "baseline"}
_SHOWN_APART = {"target", "started", "duration_s", "forced_wait_s", "interrupted",
                "interrupted_at", "interrupted_by", "link"}


def _fact_rows(doc: dict[str, Any]) -> list[tuple[str, str]]:
    run, volatile = doc["run"], rd.run_facts(doc)
    identity = doc.get("identity")
    steady = {k: v for k, v in identity.items() if k != "address"} if identity else None
    missing = "not recorded by a fuzz campaign" if "fuzz" in doc else "no answer from the target"
    facts: list[tuple[str, Any]] = [
        ("tool", f"{doc['tool']['name']} {doc['tool']['version']}"), ("target", run["target"]),
        ("identity", identity_text(steady, missing))]
    if volatile.get("address"):
        facts.append(("address", volatile["address"]))
    if volatile.get("started"):
        facts.append(("started", volatile["started"]))
    if volatile.get("duration_s") is not None:
        facts.append(("duration", seconds(volatile["duration_s"])))
    if volatile.get("forced_wait_s") is not None:
        speed = (run.get("link") or {}).get("clock_speed")
        forced = seconds(volatile["forced_wait_s"])
        facts.append(("forced waits", forced if not speed else
                      f"{forced} of the {speed:g}x clock ({seconds(volatile['forced_wait_s'] / speed)} real)"))
    if link_text(doc) is not None:
        facts.append(("link", link_text(doc)))
    if dropped_text(doc) is not None:
        facts.append(("our receive queues", dropped_text(doc)))
    for line in flight_endings(doc):
        facts.append(("flight", line))
    keys = [k for k in _RUN_LABELS if k in run] + sorted(
        k for k in run if k not in _RUN_LABELS and k not in _SHOWN_APART)
    for key in keys:
        value = run[key]
        shown = "none" if value is None else value if isinstance(value, str) else value_text(value)
        facts.append((_RUN_LABELS.get(key, key), shown))
    for key, label in (("stored_form", "plans compared as"), ("prepared", "target prepared")):
        if rd.identity_fact(doc, key):
            facts.append((label, rd.identity_fact(doc, key)))
    if run.get("interrupted"):
        facts.append(("interrupted", " ".join(
            ["yes"] + ([f"by {run['interrupted_by']}"] if run.get("interrupted_by") else [])
            + ([f"during {run['interrupted_at']}"] if run.get("interrupted_at") else []))))
    facts.append(("gating", doc["gating"]["mode"]))
    restore = doc["restore"]
    facts.append(("plans after the run", f"{restore['status']}: {restore['detail']}"
                  if restore["detail"] else restore["status"]))
    return [(label, one_line(str(value))) for label, value in facts]


def _capture_href(capture: str, folder: str | Path | None) -> str:
    """The capture as a link from `folder`. A conformance run names its capture inside the
    report folder ("run.mcap"); a fuzz campaign names it where --findings put it, relative
    to the working folder or absolute, which --report-dir need not be."""
    if folder is None:
        return capture
    path, base = Path(capture), Path(folder)
    if not path.is_absolute() and (base / path).exists():
        return capture
    if path.is_absolute() or path.exists():
        return Path(os.path.relpath(path.resolve(), base.resolve())).as_posix()
    return capture


def _counts(clauses: list[dict[str, Any]]) -> list[str]:
    counts = outcome_counts(clauses)
    # an outcome no clause had is grey: a red "fail 0" on a passing run reads as a failure
    rows = [f'<tr><td>{_badge(outcome, none=not counts[outcome])}</td><td class="n">{counts[outcome]}</td></tr>'
            for outcome in OUTCOMES]
    return ["<h3>Outcomes</h3>", "<table>", *rows,
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


def _finding(doc: dict[str, Any], clause: dict[str, Any]) -> list[str]:
    gating = "fails the run" if clause["gating"] else "does not fail the run"
    duration = rd.clause_duration(doc, clause)
    took = f", took {duration:.3f} s" if duration else ""
    out = [f'<section class="clause" id="{_anchor(clause)}">',
           f'<h4>{_badge(clause["outcome"])} <span class="id">{escape(one_line(clause["id"]))}'
           f'</span> {escape(clause["level"])} {escape(one_line(clause["title"]))}</h4>',
           f"<p>{escape(clause['level'])}, role {escape(one_line(clause['role']))}, "
           f"{gating}{took}.</p>"]
    out += _requirement(clause)
    detail = rd.clause_detail(doc, clause)
    if detail:
        out.append(f'<p class="detail">{escape(clean(detail))}</p>')
    if clause["expectation"]:
        out.append(f"<p>Expected deviation: {escape(clean(clause['expectation']))}</p>")
    out += [_diagram(doc, clause), "</section>"]
    return out


def _requirement(clause: dict[str, Any]) -> list[str]:
    return [f"<blockquote><p>“{escape(clean(clause['requirement']))}”</p>"
            f"<cite>{escape(one_line(clause['source']))}</cite></blockquote>"]


def _diagram(doc: dict[str, Any], clause: dict[str, Any]) -> str:
    events = rd.clause_events(doc, clause)
    decided = deciding_event(clause, events, rd.clause_detail(doc, clause))
    svg = sequence_diagram(events, decided=decided, target=_target_lane(clause))
    out = f'<div class="diagram">{svg}</div>'
    if decided is not None:
        how = ("as the check recorded it" if recorded_event(clause, events) == decided
               else "as read from the verdict")
        out += (f'<p class="decided-key"><b>▶</b> on a red band: the event that decided the '
                f"verdict ({how}).</p>")
    return out


def _target_lane(clause: dict[str, Any]) -> str:
    """The target's lane is named for the role the clause tests it in ("vehicle", "gcs")."""
    role = one_line(clause.get("role") or "")
    return role if role in ("vehicle", "gcs") else "target"


def _badge(outcome: str, *, none: bool = False) -> str:
    extra = " none" if none else ""
    return f'<span class="badge o-{escape(outcome)}{extra}">{escape(outcome)}</span>'


def _anchor(clause: dict[str, Any]) -> str:
    """A fragment id from the clause id (letters, digits, . _ - kept; each id is unique)."""
    return "clause-" + re.sub(r"[^A-Za-z0-9._-]", "_", clause["id"])
