"""Markdown summary, sized for a GitHub job summary or a pull-request comment.

Verdict first (for an interrupted run, that it was cut short), then what a reviewer acts on,
in reports/reading_order.py's order: what fails the run, the known deviations with what
excuses each, what else did not pass, and the not-applicable and skipped clauses as one
folded line per reason; the full clause matrix is folded away in <details>. GitHub
renders inline HTML, so text from the target is escaped for Markdown *and* HTML: it cannot
open a tag, break a table or a line.
"""

from __future__ import annotations

import re
from typing import Any
from urllib.parse import quote

from mavconform.conformance.fidelity.table import markdown as survey_markdown
from mavconform.reports.reading_order import group_title, reading_order
from mavconform.reports.run_document import clause_detail, outcome_counts, run_facts
from mavconform.reports.text import (document_identity, dropped_text, flight_endings, interruption, link_text,
                                     one_line, safety_alarm, seconds, verdict_headline)

DETAIL_LIMIT = 200  # characters of detail per table cell

OUTCOME_ICONS = {"pass": "✅", "fail": "❌", "known-deviation": "⚠️", "not-applicable": "➖",
                 "skipped": "⏭️", "error": "💥"}

# Backslash-escaping every ASCII punctuation mark is valid CommonMark; these are the ones
# that can start emphasis, code, links, HTML, entities or end a table cell.
_SPECIAL = re.compile(r"([\\`*_\[\]<>|&~#!])")


def md(text: str, limit: int | None = None) -> str:
    """`text` as literal Markdown on one line: safe in a table cell or a heading."""
    return _SPECIAL.sub(r"\\\1", one_line(text, limit))


def _reading_order(doc: dict[str, Any]) -> list[str]:
    """What fails the run, the known deviations (with what excuses each), what else did not
    pass, then the not-applicable and skipped clauses folded by reason (reading_order.py)."""
    order, out = reading_order(doc), []
    head = ["| Clause | Level | Outcome | Title | Detail |", "|---|---|---|---|---|"]
    if order.failing:
        out += ["", f"### Fails the run ({len(order.failing)})", "", *head]
        out += [_row(doc, c) for c in order.failing]
    if order.deviations:
        out += ["", f"### Known deviations ({len(order.deviations)})", "",
                "| Clause | Level | Title | Excused by | Detail |", "|---|---|---|---|---|"]
        out += [f"| {md(c['id'])} | {md(c['level'])} | {md(c['title'])} | "
                f"{md(c['expectation'] or 'no reason given', DETAIL_LIMIT)} | "
                f"{md(clause_detail(doc, c), DETAIL_LIMIT)} |" for c in order.deviations]
    if order.other:
        out += ["", f"### Did not pass, does not fail the run ({len(order.other)})", "", *head]
        out += [_row(doc, c) for c in order.other]
    for group in order.groups:
        out += ["", f"<details><summary>{OUTCOME_ICONS[group.outcome]} {md(group_title(group), DETAIL_LIMIT)}"
                    "</summary>", "", ", ".join(md(c["id"]) for c in group.clauses), "", "</details>"]
    return out


def _row(doc: dict[str, Any], clause: dict[str, Any]) -> str:
    gating = " (gating)" if clause["gating"] else ""
    return (f"| {md(clause['id'])} | {md(clause['level'])} | "
            f"{OUTCOME_ICONS[clause['outcome']]} {clause['outcome']}{gating} | "
            f"{md(clause['title'])} | {md(clause_detail(doc, clause), DETAIL_LIMIT)} |")


def markdown_summary(doc: dict[str, Any]) -> str:
    """The run as a Markdown document (GitHub flavour), ending with a newline."""
    summary, clauses, timing = doc["summary"], doc["clauses"], run_facts(doc)
    out = [f"## {verdict_headline(summary['verdict'])}: {md(doc['run']['target'])} "
           f"({md(document_identity(doc))}), "
           f"{md(doc['tool']['name'])} {md(doc['tool']['version'])}",
           "",
           f"Started {md(timing['started'] or 'at a time not recorded')}, took "
           f"{'?' if timing['duration_s'] is None else seconds(timing['duration_s'])}; "
           f"gating mode {md(doc['gating']['mode'])}: {summary['gating_failures']} gating "
           f"failure{'' if summary['gating_failures'] == 1 else 's'}.",
           ""]
    alarm = safety_alarm(doc)
    if alarm is not None:
        out += [f"> **⚠️ {md(alarm)}**", ""]
    stopped = interruption(doc)
    if stopped is not None:
        out += [f"> **{md(stopped)}**", ""]
    restore = doc["restore"]
    restore_line = f"Target plans after the run: **{md(restore['status'])}**"
    if restore["detail"]:
        restore_line += f" ({md(restore['detail'], DETAIL_LIMIT)})"
    out.append(restore_line + ".")
    link = link_text(doc)
    if link is not None:
        out += ["", f"Link: {md(link)}."]
    dropped = dropped_text(doc)
    if dropped is not None:
        out += ["", f"Our sockets' receive queues: {md(dropped)}."]
    for line in flight_endings(doc):
        out += ["", f"Flight: {md(line)}."]
    if doc["capture"] is not None:
        out += ["", f"Capture: [{md(doc['capture'])}]({quote(one_line(doc['capture']))}) "
                   "(MCAP, opens in Foxglove)."]
    if "fidelity" in doc:      # a fidelity survey: its matrices instead of clauses
        return "\n".join(out + ["", survey_markdown(doc["fidelity"])]).rstrip("\n") + "\n"
    out += ["", "| Outcome | Clauses |", "|---|--:|"]
    for outcome, count in outcome_counts(clauses).items():   # no red cross beside "fail 0"
        out.append(f"| {OUTCOME_ICONS[outcome] + ' ' if count else ''}{outcome} | {count} |")
    out.append(f"| **total** | **{len(clauses)}** |")

    out += _reading_order(doc)

    gating = doc["gating"]
    titles = {c["id"]: c["title"] for c in clauses}
    for key, heading in (("regressions", "Regressions against the baseline"),
                         ("fixed", "Fixed since the baseline")):
        if gating[key]:
            out += ["", f"### {heading} ({len(gating[key])})", ""]
            out += [f"- {md(clause_id)}" + (f": {md(titles[clause_id])}"
                                           if clause_id in titles else "")
                    for clause_id in gating[key]]

    out += ["", f"<details><summary>All {len(clauses)} clauses</summary>", "",
            "| Clause | Level | Outcome | Title |", "|---|---|---|---|"]
    for clause in clauses:
        out.append(f"| {md(clause['id'])} | {md(clause['level'])} | "
                   f"{OUTCOME_ICONS[clause['outcome']]} {clause['outcome']} | "
                   f"{md(clause['title'])} |")
    out += ["", "</details>"]
    return "\n".join(out) + "\n"
