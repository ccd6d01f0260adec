"""Each clause records the exchange event its check judged last (`decided_by`), the run
document keeps it, and run.html highlights exactly that event.

In virtual time, on the spec vehicle and on mutants that break a clause in each way a
verdict can be decided: a frame consumed, an expectation timed out, a silence broken, a
request left unanswered, a frame a check names, a reply to the second GCS.
"""

from __future__ import annotations

import datetime as dt
import re

from mavconform.conformance import document, gating
from mavconform.conformance.catalogue import BY_ID
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reports.html import html_report
from mavconform.reports.deciding import recorded_event
from mavconform.reports.run_document import check_run, clause_events

REQUESTS = ("MISSION_REQUEST", "MISSION_REQUEST_INT")


def _run(uri: str, *clause_ids: str) -> dict:
    with Session(parse_target(uri), virtual=True) as session:
        outcome = run_clauses(session, [BY_ID[c] for c in clause_ids])
    return {r.clause_id: r for r in outcome.results}


def _decider(result) -> dict:
    assert result.decided_by is not None, (result.clause_id, result.detail)
    return result.exchange[result.decided_by]


def _highlighted(text: str, clause_id: str) -> list[int]:
    """The exchange indices drawn "decided" in the clause's section of run.html."""
    body = re.search(rf'id="clause-{re.escape(clause_id)}">(.*?)</(?:section|details)>', text, re.S)
    drawn = re.findall(r'<g class="(?:arrow (?:tx|rx)|note)( decided)?">', body.group(1))
    return [index for index, decided in enumerate(drawn) if decided]


def test_a_pass_is_decided_by_the_last_frame_the_check_consumed() -> None:
    result = _run("builtin:spec", "MIS.UP.03")["MIS.UP.03"]
    assert result.outcome is Outcome.PASS
    event = _decider(result)
    assert (event["dir"], event["msg"], event["fields"]["type"]) == ("rx", "MISSION_ACK", 0)
    assert result.decided_by == max(i for i, e in enumerate(result.exchange) if e["msg"] == "MISSION_ACK")


def test_an_expectation_that_timed_out_is_decided_by_its_note() -> None:
    result = _run("mutant:no-final-ack", "MIS.UP.03")["MIS.UP.03"]
    assert result.outcome is Outcome.FAIL
    event = _decider(result)
    assert event["dir"] == "note" and event["msg"].startswith("expected MISSION_ACK{mission_type=0} within")
    assert result.detail.startswith(event["msg"].split(": nothing")[0])


def test_a_broken_silence_is_decided_by_the_frame_that_broke_it() -> None:
    result = _run("mutant:ignores-gcs-error-ack", "MIS.UP.12")["MIS.UP.12"]
    assert result.outcome is Outcome.FAIL and "expected no MISSION_REQUEST" in str(result.detail)
    event = _decider(result)
    assert event["dir"] == "rx" and event["msg"] in REQUESTS and event["fields"]["seq"] == 2
    # the first request after the GCS's error ACK, not a later one
    error_ack = max(i for i, e in enumerate(result.exchange)
                    if e["dir"] == "tx" and e["msg"] == "MISSION_ACK" and e["fields"]["type"] == 1)
    assert result.decided_by == next(i for i, e in enumerate(result.exchange)
                                     if i > error_ack and e["dir"] == "rx" and e["msg"] in REQUESTS)


def test_a_wait_that_got_nothing_is_decided_by_what_went_unanswered() -> None:
    result = _run("mutant:clear-without-ack", "MIS.CLR.01")["MIS.CLR.01"]
    assert result.outcome is Outcome.FAIL and "was not answered" in result.detail
    event = _decider(result)
    assert (event["dir"], event["msg"]) == ("tx", "MISSION_CLEAR_ALL")
    assert result.decided_by == max(i for i, e in enumerate(result.exchange) if e["dir"] == "tx")


def test_a_check_names_the_frame_its_verdict_is_about_even_from_a_shared_observation() -> None:
    """MIS.CAN.01 judges the first request after the cancel, though the observation read
    the plan back after it; run after MIS.CAN.02 its events are copies, and still found."""
    for order in (("MIS.CAN.01",), ("MIS.CAN.02", "MIS.CAN.01")):
        result = _run("mutant:upload-ignores-cancel", *order)["MIS.CAN.01"]
        assert result.outcome is Outcome.FAIL
        events = result.exchange
        cancel = next(i for i, e in enumerate(events) if e["msg"].startswith(
            "the GCS answers the request for item 2 with MISSION_ACK OPERATION_CANCELLED")) + 1
        assert (events[cancel]["msg"], events[cancel]["fields"]["type"]) == ("MISSION_ACK", 15)
        first_late = next(i for i, e in enumerate(events) if i > cancel and e["msg"] in REQUESTS)
        assert result.decided_by == first_late, order


def test_the_second_gcs_records_into_the_same_exchange() -> None:
    result = _run("mutant:busy-refusal-not-denied", "MIS.GCS.01")["MIS.GCS.01"]
    assert result.outcome is Outcome.FAIL
    event = _decider(result)
    assert (event["peer"], event["dir"], event["msg"], event["fields"]["type"]) == \
        ("tester2", "rx", "MISSION_ACK", 1)
    assert {e["peer"] for e in result.exchange} == {"tester", "tester2"}


def test_the_run_document_keeps_it_and_run_html_highlights_exactly_that_event() -> None:
    results = list(_run("mutant:no-final-ack", "MIS.UP.01", "MIS.UP.03").values())
    assert [r.outcome for r in results] == [Outcome.PASS, Outcome.FAIL]
    flags, summary = gating.gate(results, strict=False, baseline=None)
    run = document.RunOutcome(results, None, {"status": "skipped", "detail": ""}, 1.0, 0.0)
    doc = check_run(document.build(document.RunOptions("mutant:no-final-ack"), run,
                                   started=dt.datetime(2026, 1, 1), gating_flags=flags,
                                   gating=summary, capture=None))
    clauses = {c["id"]: c for c in doc["clauses"]}
    # decided_by counts the kept events; with the ambient ones merged back (clause_events)
    # it is where the check's own event was
    shown = {c["id"]: recorded_event(c, clause_events(doc, c)) for c in doc["clauses"]}
    assert [shown[r.clause_id] for r in results] == [r.decided_by for r in results]
    assert all(isinstance(c["decided_by"], int) for c in clauses.values())
    assert "decided_by" not in doc["volatile"]["clauses"]["MIS.UP.03"]
    text = html_report(doc)
    for clause_id, clause in clauses.items():
        assert _highlighted(text, clause_id) == [shown[clause_id]], clause_id
    assert "(as the check recorded it)" in text and "(as read from the verdict)" not in text


def test_a_clause_that_reuses_a_shared_observation_is_decided_where_the_observation_was() -> None:
    results = _run("builtin:spec", "MIS.UP.06", "MIS.UP.09")
    reused = _decider(results["MIS.UP.09"])   # UP.09 waits for nothing itself
    assert any(e is reused for e in results["MIS.UP.06"].exchange)   # the observation's own event
    assert reused["dir"] == "rx"
