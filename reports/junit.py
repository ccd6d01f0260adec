"""JUnit XML: the run as one test suite, so CI systems show each clause as a test case.

CI tools (GitLab, Jenkins, GitHub test-reporter actions) read this dialect of JUnit: one
<testcase> per clause, <failure>/<error>/<skipped> children, counts on <testsuite>. A known
deviation passes (the expectations file accepted it) but says so in <system-out>, so it
stays visible; an interrupted run says so in the suite's <system-err>. Text from the target
is cleaned: XML 1.0 cannot carry control characters.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from mavconform.reports.run_document import (
    ERROR, FAIL, KNOWN_DEVIATION, NOT_APPLICABLE, SKIPPED, outcome_counts,
)
from mavconform.reports.text import clean, exchange_lines, interruption, one_line, value_text

SUITE_NAME = "mavconform"
MESSAGE_LIMIT = 500  # characters in a message attribute (CI tools show it as a headline)


def junit_xml(doc: dict[str, Any]) -> str:
    """The run document as a JUnit XML string (UTF-8 declaration, trailing newline)."""
    counts = outcome_counts(doc["clauses"])
    suite = ET.Element("testsuite", {
        "name": SUITE_NAME,
        "tests": str(len(doc["clauses"])),
        "failures": str(counts[FAIL]),
        "errors": str(counts[ERROR]),
        "skipped": str(counts[SKIPPED] + counts[NOT_APPLICABLE]),
        "time": f"{doc['run']['duration_s']:.3f}",
        "timestamp": clean(doc["run"]["started"]),
    })
    properties = ET.SubElement(suite, "properties")
    for name, value in _properties(doc):
        ET.SubElement(properties, "property", {"name": clean(name), "value": one_line(value)})
    for clause in doc["clauses"]:
        _testcase(suite, clause)
    stopped = interruption(doc)
    if stopped is not None:   # the counts alone would read as a clean run with skips
        ET.SubElement(suite, "system-err").text = stopped + "\n"
    ET.indent(suite)
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            + ET.tostring(suite, encoding="unicode") + "\n")


def _properties(doc: dict[str, Any]) -> list[tuple[str, str]]:
    """Everything about the run that is not a clause, as flat name/value pairs."""
    pairs = [("format", doc["format"]), ("tool.name", doc["tool"]["name"]),
             ("tool.version", doc["tool"]["version"]),
             ("verdict", doc["summary"]["verdict"]),
             ("gating_failures", str(doc["summary"]["gating_failures"]))]
    for section in ("run", "identity"):
        for key, value in sorted((doc[section] or {}).items()):
            pairs.append((f"{section}.{key}", value if isinstance(value, str)
                          else value_text(value)))
    gating = doc["gating"]
    pairs += [("gating.mode", gating["mode"]),
              ("gating.regressions", " ".join(gating["regressions"])),
              ("gating.fixed", " ".join(gating["fixed"])),
              ("restore.status", doc["restore"]["status"]),
              ("restore.detail", doc["restore"]["detail"])]
    if doc["capture"] is not None:
        pairs.append(("capture", doc["capture"]))
    return pairs


def _testcase(suite: ET.Element, clause: dict[str, Any]) -> None:
    case = ET.SubElement(suite, "testcase", {
        "classname": f"{SUITE_NAME}.{one_line(clause['group'])}",
        "name": one_line(f"{clause['id']} {clause['title']}"),
        "time": f"{clause['duration_s']:.3f}",
    })
    outcome = clause["outcome"]
    detail = one_line(clause["detail"], MESSAGE_LIMIT)
    if outcome in (FAIL, ERROR):
        tag = "failure" if outcome == FAIL else "error"
        child = ET.SubElement(case, tag, {"message": detail, "type": clause["level"]})
        child.text = _body(clause)
    elif outcome in (SKIPPED, NOT_APPLICABLE):
        ET.SubElement(case, "skipped", {"message": f"{outcome}: {detail}" if detail else outcome})
    elif outcome == KNOWN_DEVIATION:
        expectation = clause["expectation"]
        out = ET.SubElement(case, "system-out")
        out.text = (f"known deviation: {one_line(expectation)}" if expectation
                    else "known deviation") + "\n\n" + _body(clause)


def _body(clause: dict[str, Any]) -> str:
    """The requirement, why it was not met, and the exchange that decided it, as text."""
    gating = "gating: fails the run" if clause["gating"] else "not gating"
    lines = [f"{clause['level']} ({gating}), role {clause['role']}",
             f"requirement: \"{clause['requirement']}\"",
             f"source: {clause['source']}",
             f"detail: {clause['detail']}"]
    if clause["expectation"]:
        lines.append(f"expectation: {clause['expectation']}")
    lines += ["", "exchange:"] + (exchange_lines(clause["exchange"]) or ["(no messages)"])
    return clean("\n".join(lines)) + "\n"
