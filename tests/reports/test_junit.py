import xml.etree.ElementTree as ET

from mavconform.reports.junit import junit_xml

from .sample import HOSTILE


def parse(doc):
    text = junit_xml(doc)
    assert text.startswith('<?xml version="1.0" encoding="UTF-8"?>\n') and text.endswith("\n")
    return ET.fromstring(text.encode("utf-8"))


def cases_by_id(suite):
    return {case.get("name").split()[0]: case for case in suite.iter("testcase")}


def test_one_suite_with_counts(doc):
    suite = parse(doc)
    assert suite.tag == "testsuite" and suite.get("name") == "mavconform"
    assert {k: suite.get(k) for k in ("tests", "failures", "errors", "skipped", "time")} == {
        "tests": "6", "failures": "1", "errors": "1", "skipped": "3", "time": "12.500"}
    assert len(suite.findall("testcase")) == 6
    properties = {p.get("name"): p.get("value") for p in suite.find("properties")}
    assert properties["tool.version"] == "0.1.0"
    assert properties["run.target"] == "udp:127.0.0.1:14550 <b>|"
    assert properties["capture"] == "run 1.mcap"
    assert properties["gating.regressions"] == "MIS.UP.07"
    assert properties["volatile.address"] == "127.0.0.1:40001"
    assert suite.get("timestamp") == "2026-11-22T10:00:00Z"


def test_each_outcome_has_its_element(doc):
    cases = cases_by_id(parse(doc))
    assert cases["MIS.UP.01"].get("classname") == "mavconform.UP"
    assert cases["MIS.UP.01"].get("name") == "MIS.UP.01 MIS.UP.01 in our words"
    assert cases["MIS.UP.01"].get("time") == "0.310"
    assert list(cases["MIS.UP.01"]) == []

    failure = cases["MIS.UP.07"].find("failure")
    assert [child.tag for child in cases["MIS.UP.07"]] == ["properties", "failure"]
    assert failure.get("message").startswith("expected MISSION_REQUEST_INT seq=1 within 1.5 s")
    assert failure.get("type") == "MUST"
    body = failure.text
    assert 'requirement: "The vehicle responds with MISSION_REQUEST_INT' in body
    assert "source: seeds/000_e382b17b02933558.txt:535" in body
    assert "+0.000 s  tester → target  MISSION_COUNT count=3 type=0" in body
    assert "+0.001 s  target → tester  MISSION_REQUEST_INT seq=0 type=0" in body
    assert "+0.100 s  tester2 → target  MISSION_COUNT count=2 type=0" in body
    assert "+1.500 s  note  expect MISSION_REQUEST_INT seq=1 within 1.5 s: nothing in 1.5002 s" in body

    error = cases["MIS.CUR.04"].find("error")
    assert error.get("message") == "got MISSION_REQUEST_INT{seq=0} after 0.253 s; expected none"
    assert cases["MIS.FENCE.01"].find("skipped").get("message") == (
        "not-applicable: target does not support fences")
    assert cases["MIS.CLR.03"].find("skipped").get("message") == "skipped: --clauses excluded it"

    deviation = cases["MIS.DL.02"]
    assert [child.tag for child in deviation] == ["properties", "skipped", "system-out"]
    assert deviation.find("skipped").get("message") == (
        "known deviation (PX4 answers an empty download with an error <ack>): "
        "MISSION_ACK came with type=MAV_MISSION_ERROR")
    assert "expectation: PX4 answers an empty download" in deviation.find("system-out").text


def test_hostile_text_survives_as_text_without_control_characters(doc):
    doc["clauses"][1]["title"] = HOSTILE
    doc["clauses"][1]["group"] = "U\x00P"
    text = junit_xml(doc)
    assert not any(ch in text for ch in "\x00\x07\x1b\u202e\ud800")
    suite = ET.fromstring(text.encode("utf-8"))  # well-formed
    case = suite.findall("testcase")[1]
    assert case.get("classname") == "mavconform.UP"
    assert '<script>alert("x")</script> | pipe new line' in case.get("name")
    assert "]]> `code`" in case.find("failure").get("message")
    assert '<script>alert(\\"x\\")</script>' in case.find("failure").text  # STATUSTEXT field


def test_an_empty_run_is_an_empty_suite(doc):
    doc["clauses"] = []
    suite = parse(doc)
    assert suite.get("tests") == "0" and suite.findall("testcase") == []


# --- the CI view matches the exit code: <failure>/<error> only for what fails the run ---------

def case_of(doc, clause_id):
    return cases_by_id(parse(doc))[clause_id]


def properties_of(case):
    return {p.get("name"): p.get("value") for p in case.find("properties")}


def should_failure(doc, *, strict):
    """The sample as a default (or --strict) run whose one failure is a SHOULD clause's."""
    doc["gating"] = {"mode": "strict" if strict else "default", "regressions": [], "fixed": []}
    failed = doc["clauses"][1]
    failed["level"], failed["gating"] = "SHOULD", strict
    doc["summary"]["gating_failures"] = 1 + strict   # and the error
    return doc


def test_a_should_failure_that_does_not_fail_the_run_is_not_a_failure(doc):
    suite = parse(should_failure(doc, strict=False))
    assert suite.get("failures") == "0" and suite.get("errors") == "1"
    case = cases_by_id(suite)["MIS.UP.07"]
    assert case.find("failure") is None
    message = case.find("skipped").get("message")
    assert message.startswith("not gating (a SHOULD failure fails the run only with --strict): "
                              "expected MISSION_REQUEST_INT seq=1 within 1.5 s")
    assert properties_of(case) == {"outcome": "fail", "level": "SHOULD",
                                   "gating": "does not fail the run"}
    assert "requirement:" in case.find("system-out").text


def test_the_same_should_failure_with_strict_is_a_failure(doc):
    suite = parse(should_failure(doc, strict=True))
    assert suite.get("failures") == "1"
    case = cases_by_id(suite)["MIS.UP.07"]
    assert case.find("skipped") is None and case.find("failure").get("type") == "SHOULD"
    assert properties_of(case)["gating"] == "fails the run"


def test_a_baseline_runs_non_regression_is_neither_failure_nor_error(doc):
    doc["clauses"][1]["gating"] = False     # it failed in the baseline too
    doc["clauses"][5]["gating"] = False     # an error where the baseline had one
    doc["gating"]["regressions"] = []
    doc["summary"]["gating_failures"] = 0
    doc["summary"]["verdict"] = "pass"
    suite = parse(doc)
    assert (suite.get("failures"), suite.get("errors"), suite.get("skipped")) == ("0", "0", "5")
    for clause_id in ("MIS.UP.07", "MIS.CUR.04"):
        message = cases_by_id(suite)[clause_id].find("skipped").get("message")
        assert message.startswith("not gating (not a regression: it did not pass in the baseline)")


def test_a_may_failure_says_it_is_optional(doc):
    doc = should_failure(doc, strict=False)
    doc["clauses"][1]["level"] = "MAY"
    message = case_of(doc, "MIS.UP.07").find("skipped").get("message")
    assert message.startswith("not gating (a MAY clause is optional: its failure never fails the run)")


def test_a_known_deviation_shows_its_reason_where_ci_shows_a_message(doc):
    case = case_of(doc, "MIS.DL.02")
    assert "PX4 answers an empty download with an error <ack>" in case.find("skipped").get("message")
    assert properties_of(case) == {"outcome": "known-deviation", "level": "SHOULD",
                                   "gating": "does not fail the run",
                                   "expectation": "PX4 answers an empty download with an error <ack>"}


def test_failure_and_error_counts_are_the_gating_failures(doc):
    suite = parse(doc)
    assert int(suite.get("failures")) + int(suite.get("errors")) == doc["summary"]["gating_failures"]


def test_a_pass_that_says_something_shows_it(doc):
    doc["clauses"][0]["detail"] = "deviation no longer observed (expected to fail: P3: retries)"
    case = case_of(doc, "MIS.UP.01")
    assert [child.tag for child in case] == ["system-out"]
    assert case.find("system-out").text.startswith("deviation no longer observed")
