"""How each flight ended: the run document's `flights`, and a vehicle left armed said first
and loudly by every view, failing the run."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reports.html import html_report
from mavconform.reports.junit import junit_xml
from mavconform.reports.markdown import markdown_summary
from mavconform.reports.run_document import check_run
from mavconform.reports.text import flight_endings, safety_alarm

LANDED = {"clause": "MIS.PRG.01", "style": "ArduCopter", "plan": "take off to 10 m, ...", "disarmed": True,
          "detail": "it landed and disarmed itself"}
ARMED = {"clause": "MIS.PRG.01", "style": "ArduPlane", "plan": "take off north, ...", "disarmed": False,
         "detail": "the vehicle would not disarm (HEARTBEAT custom_mode 10, armed): IT MAY STILL BE ARMED"}
UNKNOWN = {"clause": "HO.SEQ.01", "style": "generic MAVLink", "plan": "the handover flight", "disarmed": None,
           "detail": "disarmed (HEARTBEAT); its HEARTBEAT never showed it armed"}


def _with(doc: dict, *flights: dict) -> dict:
    doc["flights"] = [dict(f) for f in flights]
    doc["summary"]["left_armed"] = sum(f["disarmed"] is False for f in flights)
    if doc["summary"]["left_armed"]:
        doc["summary"]["verdict"] = "fail"
    return doc


def test_flights_that_ended_disarmed_are_listed_without_alarm(doc):
    check_run(_with(doc, LANDED, UNKNOWN))
    assert safety_alarm(doc) is None
    lines = flight_endings(doc)
    assert lines == ["MIS.PRG.01 (ArduCopter): disarmed: it landed and disarmed itself",
                     "HO.SEQ.01 (generic MAVLink): arming state unknown: disarmed (HEARTBEAT); its HEARTBEAT "
                     "never showed it armed"]
    assert "Flight: MIS.PRG.01 (ArduCopter): disarmed" in markdown_summary(doc)
    page = html_report(doc)
    assert 'class="safety"' not in page and "<th>flight</th>" in page
    assert "safety" not in junit_xml(doc)


def test_a_vehicle_left_armed_is_said_first_and_fails_every_view(doc):
    check_run(_with(doc, LANDED, ARMED))
    alarm = safety_alarm(doc)
    assert alarm.startswith("THE VEHICLE MAY STILL BE ARMED") and "MIS.PRG.01 (ArduPlane)" in alarm
    md = markdown_summary(doc)
    assert md.index("THE VEHICLE MAY STILL BE ARMED") < md.index("| Outcome |")
    page = html_report(doc)
    assert page.index('class="safety"') < page.index("<h2>Run</h2>")
    suite = ET.fromstring(junit_xml(doc))
    failures = [case for case in suite.iter("testcase") if case.find("failure") is not None
                and case.get("classname", "").endswith(".safety")]
    assert len(failures) == 1 and failures[0].find("failure").get("message") == alarm
    assert int(suite.get("failures")) >= 1 and int(suite.get("tests")) == len(doc["clauses"]) + 1


@pytest.mark.parametrize("break_it, said", [
    (lambda d: d["summary"].update(left_armed=0), "summary.left_armed: 0, but 1 flights ended not disarmed"),
    (lambda d: d["summary"].update(verdict="pass"), "a flight left the vehicle armed"),
    (lambda d: d["flights"][0].update(disarmed="yes"), "flights[0].disarmed"),
    (lambda d: d["flights"][0].pop("style"), "flights[0]: missing 'style'"),
    (lambda d: d.pop("flights"), "summary.left_armed: counted, but there is no flights section"),
])
def test_a_flights_section_that_does_not_add_up_is_refused(doc, break_it, said):
    _with(doc, ARMED)
    break_it(doc)
    with pytest.raises(UsageError, match=re.escape(said)):
        check_run(doc)
