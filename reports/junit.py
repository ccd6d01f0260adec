"""JUnit XML: the run as one test suite, so CI systems show each clause as a test case.

CI tools (GitLab, Jenkins, GitHub test-reporter actions) read this dialect of JUnit: one
<testcase> per clause, <failure>/<error>/<skipped> children, counts on <testsuite>. They
colour a job by its <failure> and <error> cases, so only what fails the run is one (the
clauses counted in summary.gating_failures), and the tests a CI view shows red are the
reasons the job's exit code is 1:

    pass                                  a plain <testcase>
    fail that fails the run               <failure message=DETAIL type=LEVEL>
    error that fails the run              <error message=DETAIL type="error">
    fail or error that does not           <skipped message="not gating (WHY): DETAIL">
      (a SHOULD failure without --strict, a MAY clause, a baseline run's non-regression)
    known deviation                       <skipped message="known deviation (REASON): DETAIL">
    not-applicable, skipped               <skipped message="OUTCOME: DETAIL">

<skipped> is what every one of those viewers lists with its message and leaves out of the
red count (pytest writes an xfail the same way), so a known deviation's reason and a SHOULD
failure stay in sight on a green job. Every case that did not pass also carries
<properties> (outcome, level, gating, expectation) for tools that read them, and the
requirement, detail and exchange in its <system-out> (or its <failure>/<error> text).
An interrupted run says so in the suite's <system-err>. Text from the target is cleaned:
XML 1.0 cannot carry control characters.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from mavconform.reports.run_document import (
    ERROR, FAIL, KNOWN_DEVIATION, PASS, clause_detail, clause_duration, clause_events, receive_queue,
    run_facts,
)
from mavconform.reports.text import clean, exchange_lines, interruption, one_line, safety_alarm, value_text

SUITE_NAME = "mavconform"
MESSAGE_LIMIT = 500  # characters in a message attribute (CI tools show it as a headline)


def junit_xml(doc: dict[str, Any]) -> str:
    """The run document as a JUnit XML string (UTF-8 declaration, trailing newline)."""
    clauses = doc["clauses"]
    timing = run_facts(doc)
    suite = ET.Element("testsuite", {
        "name": SUITE_NAME,
        "tests": str(len(clauses) + (safety_alarm(doc) is not None)),
        "failures": str(sum(_element(doc, c)[0] == "failure" for c in clauses) + (safety_alarm(doc) is not None)),
        "errors": str(sum(_element(doc, c)[0] == "error" for c in clauses)),
        "skipped": str(sum(_element(doc, c)[0] == "skipped" for c in clauses)),
        "time": f"{timing['duration_s'] or 0.0:.3f}",
    })
    if timing["started"]:
        suite.set("timestamp", clean(timing["started"]))
    properties = ET.SubElement(suite, "properties")
    for name, value in _properties(doc):
        ET.SubElement(properties, "property", {"name": clean(name), "value": one_line(value)})
    for clause in clauses:
        _testcase(suite, doc, clause)
    alarm = safety_alarm(doc)
    if alarm is not None:   # a CI view must show it red, whatever the clauses say
        case = ET.SubElement(suite, "testcase", {"classname": f"{SUITE_NAME}.safety",
                                                 "name": "the vehicle is disarmed after every flight", "time": "0.000"})
        ET.SubElement(case, "failure", {"message": alarm, "type": "left-armed"}).text = alarm + "\n"
    stopped = interruption(doc)
    if stopped is not None:   # the counts alone would read as a clean run with skips
        ET.SubElement(suite, "system-err").text = stopped + "\n"
    ET.indent(suite)
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            + ET.tostring(suite, encoding="unicode") + "\n")


def _element(doc: dict[str, Any], clause: dict[str, Any]) -> tuple[str | None, str]:
    """The child element a clause gets ("failure", "error", "skipped" or None for a plain
    pass) and, for a skipped one, what its message starts with."""
    outcome = clause["outcome"]
    if outcome == PASS:
        return None, ""
    if outcome in (FAIL, ERROR):
        if clause["gating"]:
            return ("failure" if outcome == FAIL else "error"), ""
        return "skipped", f"not gating ({_why_not_gating(doc, clause)})"
    if outcome == KNOWN_DEVIATION:
        reason = clause["expectation"]
        return "skipped", f"known deviation ({reason})" if reason else "known deviation"
    return "skipped", outcome   # not-applicable, skipped


def _why_not_gating(doc: dict[str, Any], clause: dict[str, Any]) -> str:
    if doc["gating"]["mode"] == "baseline":
        return "not a regression: it did not pass in the baseline"
    if clause["level"] == "MAY":
        return "a MAY clause is optional: its failure never fails the run"
    return f"a {clause['level']} failure fails the run only with --strict"


def _properties(doc: dict[str, Any]) -> list[tuple[str, str]]:
    """Everything about the run that is not a clause, as flat name/value pairs."""
    pairs = [("format", doc["format"]), ("tool.name", doc["tool"]["name"]),
             ("tool.version", doc["tool"]["version"]),
             ("verdict", doc["summary"]["verdict"]),
             ("gating_failures", str(doc["summary"]["gating_failures"]))]
    for section in ("run", "identity"):
        for key, value in sorted((doc[section] or {}).items()):
            for name, item in (sorted(value.items()) if isinstance(value, dict) else [("", value)]):
                pairs.append((f"{section}.{key}" + (f".{name}" if name else ""),
                              item if isinstance(item, str) else value_text(item)))
    for key, value in sorted(run_facts(doc).items()):
        if value is not None:
            pairs.append((f"volatile.{key}", value if isinstance(value, str) else value_text(value)))
    for key, value in sorted((receive_queue(doc) or {}).items()):   # null: not known
        pairs.append((f"volatile.receive_queue.{key}", value_text(value)))
    gating = doc["gating"]
    pairs += [("gating.mode", gating["mode"]),
              ("gating.regressions", " ".join(gating["regressions"])),
              ("gating.fixed", " ".join(gating["fixed"])),
              ("restore.status", doc["restore"]["status"]),
              ("restore.detail", doc["restore"]["detail"])]
    if doc["capture"] is not None:
        pairs.append(("capture", doc["capture"]))
    return pairs


def _testcase(suite: ET.Element, doc: dict[str, Any], clause: dict[str, Any]) -> None:
    duration = clause_duration(doc, clause)
    case = ET.SubElement(suite, "testcase", {
        "classname": f"{SUITE_NAME}.{one_line(clause['group'])}",
        "name": one_line(f"{clause['id']} {clause['title']}"),
        "time": f"{duration or 0.0:.3f}",
    })
    tag, headline = _element(doc, clause)
    if tag is None:   # a pass; one with a detail ("deviation no longer observed") shows it
        if clause["detail"]:
            ET.SubElement(case, "system-out").text = clean(clause_detail(doc, clause)) + "\n"
        return
    properties = ET.SubElement(case, "properties")
    for name, value in (("outcome", clause["outcome"]), ("level", clause["level"]),
                        ("gating", "fails the run" if clause["gating"] else "does not fail the run"),
                        ("expectation", clause["expectation"])):
        if value:
            ET.SubElement(properties, "property", {"name": name, "value": one_line(value)})
    detail = one_line(clause_detail(doc, clause))
    if tag in ("failure", "error"):
        child = ET.SubElement(case, tag, {"message": one_line(detail, MESSAGE_LIMIT),
                                          "type": clause["level"] if tag == "failure" else "error"})
        child.text = _body(doc, clause)
        return
    message = f"{headline}: {detail}" if detail else headline
    ET.SubElement(case, "skipped", {"message": one_line(message, MESSAGE_LIMIT)})
    ET.SubElement(case, "system-out").text = _body(doc, clause)


def _body(doc: dict[str, Any], clause: dict[str, Any]) -> str:
    """The requirement, why it was not met, and the exchange that decided it, as text."""
    gating = "gating: fails the run" if clause["gating"] else "not gating"
    lines = [f"{clause['outcome']}: {clause['level']} ({gating}), role {clause['role']}",
             f"requirement: \"{clause['requirement']}\"",
             f"source: {clause['source']}",
             f"detail: {clause_detail(doc, clause)}"]
    if clause["expectation"]:
        lines.append(f"expectation: {clause['expectation']}")
    events = clause_events(doc, clause)
    lines += ["", "exchange:"] + (exchange_lines(events) or ["(no messages)"])
    return clean("\n".join(lines)) + "\n"
