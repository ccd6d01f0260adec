"""run.html opens on what matters (issue 29): what fails the run, in red only when anything
does; the known deviations, each with what excuses it; what else did not pass; then the
not-applicable and skipped clauses folded in groups by reason; all before the matrix."""

import re

from mavconform.reports.html import html_report, not_passing
from mavconform.reports.markdown import markdown_summary

from .sample import clause, event

GATING_FIRST = ["MIS.UP.07", "MIS.CUR.04", "MIS.DL.02", "MIS.FENCE.01", "MIS.CLR.03"]


def what_failed(text):
    """The sections' HTML: from the first to the run facts, which follow them."""
    return text[text.index('<section id="what-failed"'):text.index('<table class="facts">')]


def section(text, name):
    """One of those sections: to the next (their ids; a clause's section has a class first)."""
    start = text.index(f'<section id="{name}"')
    ends = [i for i in (text.find('<section id="', start + 1), text.index("<h2>Run</h2>", start)) if i >= 0]
    return text[start:min(ends)]


def test_what_failed_comes_right_under_the_headline_and_before_the_matrix(doc):
    text = html_report(doc)
    verdict = text.index('<p class="verdict fail">')
    section = text.index('<section id="what-failed">')
    assert verdict < section < text.index('<table class="facts">') < text.index('class="matrix"')
    assert "<h2>" not in text[verdict:section]   # nothing else comes between


def test_it_lists_exactly_the_clauses_not_passing_those_failing_the_run_first(doc):
    text = html_report(doc)
    body = what_failed(text)
    failing = section(text, "what-failed")
    index = re.findall(r'<li><span class="badge o-[\w-]+">[\w-]+</span> '
                       r'<a class="id" href="#clause-([\w.]+)">', failing)
    assert index == ["MIS.UP.07", "MIS.CUR.04"]
    assert "<h2>Fails the run (2)</h2>" in failing and "2 clauses fail the run." in failing
    assert re.findall(r'<section class="clause" id="clause-([\w.]+)">', body) == GATING_FIRST
    assert [c["id"] for c in not_passing(doc["clauses"])] == GATING_FIRST
    assert re.findall(r"<h2>([^<]*)</h2>", body)[:3] == ["Fails the run (2)", "Known deviations (1)",
                                                         "Not applicable or skipped (2)"]
    assert "MIS.UP.01" not in body


def test_a_known_deviation_is_folded_with_what_excuses_it_and_never_red(doc):
    body = section(html_report(doc), "deviations")
    summary = re.search(r'<details class="fold"><summary>(.*?)</summary>', body, re.S).group(1)
    assert "MIS.DL.02" in summary and 'class="why">excused: ' in summary
    assert '<section class="clause" id="clause-MIS.DL.02">' in body


def test_not_applicable_and_skipped_clauses_are_one_folded_line_per_reason(doc):
    for n in range(2, 23):   # 21 more clauses that do not apply, for one reason
        doc["clauses"].append(clause(f"HO.CTL.{n:02d}", "not-applicable", [],
                                     detail="the target sent no CONTROL_STATUS: no system manager"))
    body = section(html_report(doc), "not-applicable")
    lines = re.findall(r'<details class="fold group"><summary><span class="badge o-([\w-]+)">[\w-]+</span> '
                       r'([^<]*)</summary>', body)
    assert [(o, t.split(":")[0]) for o, t in lines] == [
        ("not-applicable", "1 clause not applicable"), ("not-applicable", "21 clauses not applicable"),
        ("skipped", "1 clause skipped")]
    assert "21 clauses not applicable: the target sent no CONTROL_STATUS: no system manager" in body
    assert body.count('<a class="id" href="#clause-HO.CTL.') == 21


def test_each_entry_has_id_level_title_requirement_verdict_and_a_diagram(doc):
    body = what_failed(html_report(doc))
    sections = dict(re.findall(r'<section class="clause" id="clause-([\w.]+)">(.*?)</section>',
                               body, re.S))
    for item in doc["clauses"][1:]:
        section = sections[item["id"]]
        assert f'<span class="id">{item["id"]}</span> {item["level"]} {item["id"]} in our words' \
            in section
        assert "“The vehicle responds with MISSION_REQUEST_INT for each item.”" in section
        assert "<cite>seeds/000_e382b17b02933558.txt:535</cite>" in section
        assert section.count('<svg class="sequence"') == 1
    # the verdict as a person reads it: the measured number put back
    assert '<p class="detail">got MISSION_REQUEST_INT{seq=0} after 0.253 s; expected none</p>' \
        in sections["MIS.CUR.04"]
    assert "MISSION_ACK came with type=MAV_MISSION_ERROR" in sections["MIS.DL.02"]


def test_a_should_failure_that_does_not_gate_is_listed_after_the_deviations(doc):
    doc["clauses"].append(clause("MIS.UP.09", "fail", [], level="SHOULD", detail="8 resends"))
    doc["volatile"]["clauses"]["MIS.UP.09"] = {"duration_s": 1.0, "events": []}
    doc["summary"]["fail"] += 1
    doc["summary"]["total"] += 1
    ids = [c["id"] for c in not_passing(doc["clauses"])]
    assert ids == ["MIS.UP.07", "MIS.CUR.04", "MIS.DL.02", "MIS.UP.09", "MIS.FENCE.01",
                   "MIS.CLR.03"]
    body = section(html_report(doc), "not-gating")
    assert "<h2>Did not pass, does not fail the run (1)</h2>" in body
    assert "SHOULD" in body.split('href="#clause-MIS.UP.09">')[1][:40]


def test_an_interrupted_run_keeps_its_banner_on_top(doc):
    doc["run"].update(interrupted=True, interrupted_at="MIS.UP.07", interrupted_by="SIGTERM")
    doc["summary"]["verdict"] = "interrupted"
    text = html_report(doc)
    banner = text.index('<p class="interrupted">The run was interrupted by SIGTERM during MIS.UP.07')
    assert text.index('<p class="verdict interrupted">') < banner
    assert banner < text.index('<section id="what-failed">')


def test_a_passing_run_says_so_where_failures_would_be(doc):
    for item in doc["clauses"]:
        item["outcome"], item["gating"] = "pass", False
    doc["summary"].update({"pass": 6, "fail": 0, "known-deviation": 0, "not-applicable": 0,
                           "skipped": 0, "error": 0, "gating_failures": 0, "verdict": "pass"})
    text = html_report(doc)
    assert '<section id="what-failed" class="none">' in text
    assert "<h2>Nothing fails the run</h2>" in text and "<p>Every clause passed.</p>" in text


def test_a_passing_run_with_deviations_shows_no_red(doc):
    """A passing run against a real autopilot: deviations and clauses that do not apply,
    nothing failing: no red box, no red badge above the run's facts."""
    for item in doc["clauses"]:
        if item["gating"]:
            item["outcome"], item["gating"] = "pass", False
    doc["summary"].update({"fail": 0, "error": 0, "gating_failures": 0, "verdict": "pass"})
    body = what_failed(html_report(doc))
    assert '<section id="what-failed" class="none">' in body
    assert "No clause fails the run" in body
    assert "o-fail" not in body and "o-error" not in body and "<h2>Fails the run" not in body
    # below it too: the outcome counts show "fail 0" and "error 0" in grey, not red
    text = html_report(doc)
    assert re.findall(r'class="badge o-(?:fail|error)[^"]*"', text) == [
        'class="badge o-fail none"', 'class="badge o-error none"']
    assert ".badge.none {" in text and text.index(".badge.o-fail {") < text.index(".badge.none {")
    summary = markdown_summary(doc)   # run.md: no red cross beside a count of none
    assert "| fail | 0 |" in summary and "| error | 0 |" in summary and "\u274c" not in summary


def test_the_failed_clause_marks_the_message_that_decided_it(doc):
    exchange = [event(0.0, "tx", "MISSION_COUNT", count=3, mission_type=0),
                event(0.001, "rx", "MISSION_REQUEST_INT", seq=0, mission_type=0),
                event(0.002, "tx", "MISSION_ITEM_INT", seq=0, mission_type=0),
                event(0.003, "rx", "MISSION_REQUEST_INT", seq=2, mission_type=0),
                event(0.004, "rx", "MISSION_CURRENT", seq=0, total=3)]
    failed = doc["clauses"][1]
    failed["exchange"] = [{k: v for k, v in e.items() if k != "t"} for e in exchange]
    failed["detail"] = "during the upload the vehicle sent MISSION_REQUEST_INT{seq=2, mission_type=0}"
    doc["volatile"]["clauses"][failed["id"]] = {"duration_s": 0.1,
                                               "events": [e["t"] for e in exchange]}
    section = re.search(r'<section class="clause" id="clause-MIS.UP.07">(.*?)</section>',
                        html_report(doc), re.S).group(1)
    marked = re.findall(r'<g class="arrow (\w+) decided"><title>([^<]*)</title>', section)
    assert marked == [("rx", "MISSION_REQUEST_INT seq=2 mission_type=0 (MAV_MISSION_TYPE_MISSION)")]
    assert section.count('class="decided-band"') == 1
    assert re.findall(r'<text class="time decided-mark"[^>]*>([^<]*)</text>', section) == ["▶ +0.003 s"]
    assert "the event that decided the verdict (as read from the verdict)" in section
