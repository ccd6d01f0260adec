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
        "tests": "6", "failures": "1", "errors": "1", "skipped": "2", "time": "12.500"}
    assert len(suite.findall("testcase")) == 6
    properties = {p.get("name"): p.get("value") for p in suite.find("properties")}
    assert properties["tool.version"] == "0.1.0"
    assert properties["run.target"] == "udp:127.0.0.1:14550 <b>|"
    assert properties["capture"] == "run 1.mcap"
    assert properties["gating.regressions"] == "MIS.UP.07"


def test_each_outcome_has_its_element(doc):
    cases = cases_by_id(parse(doc))
    assert cases["MIS.UP.01"].get("classname") == "mavconform.UP"
    assert cases["MIS.UP.01"].get("name") == "MIS.UP.01 MIS.UP.01 in our words"
    assert cases["MIS.UP.01"].get("time") == "0.310"
    assert list(cases["MIS.UP.01"]) == []

    failure = cases["MIS.UP.07"].find("failure")
    assert [child.tag for child in cases["MIS.UP.07"]] == ["failure"]
    assert failure.get("message").startswith("expected MISSION_REQUEST_INT seq=1 within 1.5 s")
    assert failure.get("type") == "MUST"
    body = failure.text
    assert 'requirement: "The vehicle responds with MISSION_REQUEST_INT' in body
    assert "source: seeds/000_e382b17b02933558.txt:535" in body
    assert "+0.000 s  tester → target  MISSION_COUNT count=3 type=0" in body
    assert "+0.001 s  target → tester  MISSION_REQUEST_INT seq=0 type=0" in body
    assert "+0.100 s  tester2 → target  MISSION_COUNT count=2 type=0" in body
    assert "+1.500 s  note  expect MISSION_REQUEST_INT seq=1 within 1.5 s" in body

    error = cases["MIS.CUR.04"].find("error")
    assert error.get("message") == "runner: socket closed Traceback line"
    assert cases["MIS.FENCE.01"].find("skipped").get("message") == (
        "not-applicable: target does not support fences")
    assert cases["MIS.CLR.03"].find("skipped").get("message") == "skipped: --clauses excluded it"

    deviation = cases["MIS.DL.02"]
    assert [child.tag for child in deviation] == ["system-out"]
    assert deviation.find("system-out").text.startswith(
        "known deviation: PX4 answers an empty download with an error <ack>\n")


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
