"""Issue 13: two runs of the same target diff only in run.json's `volatile` section, and the
JUnit XML shows red only what fails the run (so a CI view agrees with the exit code)."""

from __future__ import annotations

import datetime as dt
import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.conformance import document, gating, readiness
from mavconform.conformance.expectations import Deviation
from mavconform.conformance.harness.measured import Measured
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import DecidedResult, RunOutcome
from mavconform.reports.deciding import deciding_event
from mavconform.reports.write import write_reports
from mavconform.reports.run_document import (check_run, clause_detail, clause_duration,
                                             clause_events, identity_fact, load_run,
                                             run_facts)

pytestmark = pytest.mark.udp

# Every upload and download clause: long exchanges, and windows that follow the target's own
# timers.
SPEC_CLAUSES = "MIS.UP.*,MIS.DN.*"
# Clauses whose windows follow the target's streams (its HEARTBEAT, its 1 Hz MISSION_CURRENT):
# whether a MISSION_CURRENT falls inside one is the stream's phase, so the unused ones are
# ambient (volatile).
STREAM_CLAUSES = "MIS.FRM.*,MIS.CUR.*,MIS.PRG.*"


def _run(capsys, folder: Path, *argv: str) -> tuple[int, str, dict]:
    code = main(["run", "--report-dir", str(folder), *argv])
    out = capsys.readouterr().out
    return code, out, load_run(folder / "run.json")


def _stable(doc: dict) -> dict:
    return {key: value for key, value in doc.items() if key != "volatile"}


def _assert_same_outside_volatile(first: dict, second: dict) -> None:
    a, b = _stable(first), _stable(second)
    if a != b:   # name the first clause and event that differ, not two 10,000-line dicts
        for x, y in zip(a["clauses"], b["clauses"]):
            if x != y:
                events = [(i, e, f) for i, (e, f) in enumerate(zip(x["exchange"], y["exchange"])) if e != f]
                assert x == y, (x["id"], len(x["exchange"]), len(y["exchange"]), events[:2])
    assert a == b


def test_two_runs_of_the_spec_differ_only_in_the_volatile_section(tmp_path, capsys) -> None:
    """Over real UDP loopback, as `mavconform run` does by default: the times, the ephemeral
    port and the measured numbers all differ between the two, and all are in `volatile`."""
    code1, _, first = _run(capsys, tmp_path / "1", "--clauses", SPEC_CLAUSES)
    code2, _, second = _run(capsys, tmp_path / "2", "--clauses", SPEC_CLAUSES)
    assert code1 == code2 == 0
    _assert_same_outside_volatile(first, second)
    assert first["volatile"] != second["volatile"]
    text = (tmp_path / "1" / "run.json").read_text()
    assert '"t":' not in json.dumps(_stable(first)) and '"started"' in text and text.count(
        '"duration_s"') == len(first["clauses"]) + 1   # one per clause, one for the run: all under volatile


def test_clauses_that_span_the_targets_streams_differ_only_in_the_volatile_section(tmp_path, capsys) -> None:
    code1, _, first = _run(capsys, tmp_path / "1", "--clauses", STREAM_CLAUSES)
    code2, _, second = _run(capsys, tmp_path / "2", "--clauses", STREAM_CLAUSES)
    assert code1 == code2 == 0
    _assert_same_outside_volatile(first, second)
    ambient = [e for c in first["volatile"]["clauses"].values() for e in c.get("ambient", [])]
    assert ambient and {e["msg"] for e in ambient} == {"MISSION_CURRENT"}


def test_the_volatile_section_holds_what_the_renderers_need(tmp_path, capsys) -> None:
    _, _, doc = _run(capsys, tmp_path, "--clauses", "MIS.UP.01,MIS.FRM.0[45]")
    facts = run_facts(doc)
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ", facts["started"])
    assert facts["duration_s"] > 0 and facts["forced_wait_s"] >= 0
    assert re.fullmatch(r"127\.0\.0\.1:\d+", facts["address"])
    for clause in doc["clauses"]:
        events = clause_events(doc, clause)
        ambient = doc["volatile"]["clauses"][clause["id"]].get("ambient", [])
        assert len(events) == len(clause["exchange"]) + len(ambient) > 0
        assert all(isinstance(e["t"], float) and e["t"] >= 0 for e in events)
        assert clause_duration(doc, clause) >= max(e["t"] for e in events) - 0.01
        assert [{k: v for k, v in e.items() if k != "t"} for e in events
                if e["dir"] != "note" and not e.get("ambient")] \
            == [e for e in clause["exchange"] if e["dir"] != "note"]   # order, peer, fields kept
    heartbeats = next(c for c in doc["clauses"] if c["id"] == "MIS.FRM.04")
    index = next(i for i, e in enumerate(heartbeats["exchange"]) if e["msg"].startswith("HEARTBEATs"))
    assert heartbeats["exchange"][index]["msg"] == "HEARTBEATs at <at> s into a 2.5 s window"
    shown = next(e["msg"] for e in clause_events(doc, heartbeats) if e["msg"].startswith("HEARTBEATs"))
    assert re.fullmatch(r"HEARTBEATs at \[\d\.\d+, \d\.\d+.*\] s into a 2\.5 s window", shown)
    # the reports show the measured values, never a placeholder
    for name in ("run.md", "run.html", "run.junit.xml"):
        shown = (tmp_path / name).read_text()
        assert "<at>" not in shown and "&lt;at&gt;" not in shown and r"\<at\>" not in shown, name
    assert facts["address"] in (tmp_path / "run.html").read_text()


def test_a_timing_based_failure_keeps_its_measured_number_apart(tmp_path, capsys) -> None:
    """The mutant keeps requesting after a cancel and after a GCS's error ack: both details
    say after how long, which differs run to run; the document keeps it in `volatile`, the
    console, run.md and the JUnit message show it."""
    argv = ("--target", "mutant:ignores-gcs-error-ack", "--clauses", "MIS.CAN.01,MIS.UP.12")
    code1, out, first = _run(capsys, tmp_path / "1", *argv)
    code2, _, second = _run(capsys, tmp_path / "2", *argv)
    assert code1 == code2 == 1
    _assert_same_outside_volatile(first, second)
    by_id = {c["id"]: c for c in first["clauses"]}
    assert by_id["MIS.CAN.01"]["detail"] == (
        "after MISSION_ACK OPERATION_CANCELLED the vehicle kept requesting: 5 request(s) in <window> "
        "s, the first for item 2 after <after> s; expected none")
    assert by_id["MIS.UP.12"]["detail"].endswith("after <after> s")
    measured = first["volatile"]["clauses"]["MIS.CAN.01"]["detail"]
    assert measured["window"] == "1.5" and re.fullmatch(r"0\.2\d\d", measured["after"])
    full = clause_detail(first, by_id["MIS.CAN.01"])
    assert full.endswith(f"after {measured['after']} s; expected none")
    assert " ".join(full.split()) in " ".join(out.split())      # the console line, wrapped
    assert f"after {measured['after']} s; expected none" in (tmp_path / "1" / "run.md").read_text()
    junit = ET.parse(tmp_path / "1" / "run.junit.xml").getroot()
    messages = {c.get("name").split()[0]: (c.find("failure") if c.find("failure") is not None
                                           else c.find("skipped")).get("message")
                for c in junit.iter("testcase")}
    assert messages["MIS.CAN.01"].endswith(f"(a SHOULD failure fails the run only with --strict): {full}")
    assert re.search(r"got MISSION_REQUEST_INT\{seq=2, mission_type=0\} after 0\.2\d\d s$",
                     messages["MIS.UP.12"])


def test_an_expectation_that_rewords_a_detail_leaves_its_numbers_apart() -> None:
    """A failure other than the one an expectation names gets a prefix: the measured part is
    still found in it, and the document's detail stays stable."""
    detail = Measured("expected no X for <window> s; got Y after <after> s", window="0.75", after="0.251")
    result = DecidedResult("MIS.UP.12", Outcome.FAIL, detail, 1.2, [], measured=[detail])
    gating.apply_expectations([result], {"MIS.UP.12": Deviation("MIS.UP.12", "why", observed="other *")})
    assert result.detail.startswith("fails otherwise") and "after 0.251 s" in result.detail
    flags, summary = gating.gate([result], strict=False, baseline=None)
    doc = document.build(document.RunOptions("mutant:x"), RunOutcome([result], None, {
        "status": "skipped", "detail": ""}, 1.5, 0.0), started=dt.datetime(2026, 1, 1),
        gating_flags=flags, gating=summary, capture=None)
    check_run(doc)
    clause = doc["clauses"][0]
    assert clause["detail"].endswith("expected no X for <window> s; got Y after <after> s")
    assert clause_detail(doc, clause) == result.detail


def _event(t: float, direction: str, name: str, **fields) -> dict:
    return {"t": t, "dir": direction, "peer": "tester", "msg": name, "fields": fields}


def test_a_streamed_message_no_check_used_is_kept_apart_where_it_arrived(tmp_path) -> None:
    """A 1 Hz MISSION_CURRENT lands inside a clause when the stream's phase says: one run
    has it, the next does not. Unused, it goes to volatile (`ambient`, with its place in the
    exchange); the report merges it back, and decided_by still names the deciding event."""
    def result(with_stream: bool) -> DecidedResult:
        exchange = [_event(0.0, "tx", "MISSION_COUNT", count=1)]
        if with_stream:
            exchange.append({**_event(0.3, "rx", "MISSION_CURRENT", seq=0), "ambient": True})
        exchange += [_event(0.4, "rx", "MISSION_REQUEST_INT", seq=0),
                     _event(0.5, "rx", "MISSION_CURRENT", seq=0)]   # used by the check: evidence
        return DecidedResult("MIS.UP.01", Outcome.FAIL, "wrong", 0.6, exchange,
                             decided_by=len(exchange) - 2)
    docs = []
    for with_stream in (True, False):
        r = result(with_stream)
        flags, summary = gating.gate([r], strict=False, baseline=None)
        docs.append(check_run(document.build(document.RunOptions("builtin:spec"), RunOutcome(
            [r], None, {"status": "skipped", "detail": ""}, 1.0, 0.0), started=dt.datetime(2026, 1, 1),
            gating_flags=flags, gating=summary, capture=None)))
    assert _stable(docs[0]) == _stable(docs[1])
    clause = docs[0]["clauses"][0]
    assert [e["msg"] for e in clause["exchange"]] == ["MISSION_COUNT", "MISSION_REQUEST_INT", "MISSION_CURRENT"]
    assert clause["decided_by"] == 1
    assert docs[0]["volatile"]["clauses"]["MIS.UP.01"]["ambient"] == [
        {"at": 1, "t": 0.3, "dir": "rx", "peer": "tester", "msg": "MISSION_CURRENT", "fields": {"seq": 0}}]
    events = clause_events(docs[0], clause)
    assert [(e["msg"], e["t"], e.get("ambient", False)) for e in events] == [
        ("MISSION_COUNT", 0.0, False), ("MISSION_CURRENT", 0.3, True),
        ("MISSION_REQUEST_INT", 0.4, False), ("MISSION_CURRENT", 0.5, False)]
    assert deciding_event(clause, events) == 2
    write_reports(docs[0], tmp_path)
    write_reports(docs[1], tmp_path / "without")
    drawn = [(folder / "run.html").read_text().count("MISSION_CURRENT seq=0") for folder in (tmp_path, tmp_path / "without")]
    assert drawn[0] == 2 * drawn[1] > 0   # the ambient one is drawn too
    broken = json.loads(json.dumps(docs[0]))
    broken["volatile"]["clauses"]["MIS.UP.01"]["ambient"][0]["at"] = 9
    with pytest.raises(Exception, match=r"volatile\.clauses\.MIS\.UP\.01\.ambient\[0\]\.at: 9 is not an index"):
        check_run(broken)


def test_a_check_that_consumes_a_streamed_message_keeps_it_as_evidence() -> None:
    """The tester clears the mark when a check takes the frame (or it decides the clause)."""
    from mavconform.conformance.harness.exchange import Exchange, used
    ex = Exchange(0.0)
    index = ex.add(0.1, "rx", "tester", "MISSION_CURRENT", {"seq": 0})
    assert ex.events[index]["ambient"] is True
    used(ex.events[index])
    assert "ambient" not in ex.events[index]
    other = ex.add(0.2, "rx", "tester", "MISSION_CURRENT", {"seq": 1})
    ex.decide(other)
    assert "ambient" not in ex.events[other]
    assert "ambient" not in ex.events[ex.add(0.3, "rx", "tester", "MISSION_ACK", {"type": 0})]


def test_how_long_the_target_took_to_boot_is_volatile(tmp_path) -> None:
    """A SITL that answers NO_SPACE while it boots makes the readiness line say how long it
    waited ("... after 3 NO_SPACE refusal(s) in 3.2 s"): the identity keeps the stable text,
    volatile.identity the numbers, and run.html shows them put back."""
    ready = Measured("upload probe: MAV_MISSION_ACCEPTED after <boot_refusals> NO_SPACE refusal(s) "
                     "in <boot_wait>", boot_refusals="3", boot_wait="3.2 s")
    forms = "forms probe: MISSION_REQUEST_INT answered"
    line = readiness.Readiness(["MISSION_CURRENT at 1 Hz: accepted"], forms, ready).line()
    assert line == ("MISSION_CURRENT at 1 Hz: accepted; forms probe: MISSION_REQUEST_INT answered; upload "
                    "probe: MAV_MISSION_ACCEPTED after 3 NO_SPACE refusal(s) in 3.2 s")
    result = DecidedResult("MIS.UP.01", Outcome.PASS, "ok", 0.5, [])
    flags, summary = gating.gate([result], strict=False, baseline=None)
    docs = [document.build(document.RunOptions("udp:127.0.0.1:1"), RunOutcome(
        [result], {"system": 1, "component": 1, "prepared": readiness.Readiness(
            ["MISSION_CURRENT at 1 Hz: accepted"], forms, Measured(ready.stable, boot_refusals=n,
                                                                   boot_wait=w)).line()},
        {"status": "skipped", "detail": ""}, 1.5, 0.0), started=dt.datetime(2026, 1, 1),
        gating_flags=flags, gating=summary, capture=None) for n, w in (("3", "3.2 s"), ("1", "1.1 s"))]
    for doc in docs:
        check_run(doc)
    assert _stable(docs[0]) == _stable(docs[1])
    assert docs[0]["identity"]["prepared"].endswith("after <boot_refusals> NO_SPACE refusal(s) in <boot_wait>")
    assert docs[0]["volatile"]["identity"] == {"prepared": {"boot_refusals": "3", "boot_wait": "3.2 s"}}
    assert identity_fact(docs[0], "prepared") == line
    write_reports(docs[0], tmp_path)
    html = (tmp_path / "run.html").read_text()
    assert "refusal(s) in 3.2 s" in html and "boot_wait" not in html


# --- JUnit: <failure> only for what fails the run -------------------------------------------

def _junit_case(folder: Path, clause_id: str) -> ET.Element:
    suite = ET.parse(folder / "run.junit.xml").getroot()
    return next(c for c in suite.iter("testcase") if c.get("name").split()[0] == clause_id)


def test_a_should_failure_is_a_junit_failure_only_with_strict(tmp_path, capsys) -> None:
    argv = ("--target", "mutant:float-requests", "--clauses", "MIS.UP.15")
    code, _, _ = _run(capsys, tmp_path / "default", *argv)
    assert code == 0
    case = _junit_case(tmp_path / "default", "MIS.UP.15")
    assert case.find("failure") is None and case.find("error") is None
    assert case.find("skipped").get("message").startswith(
        "not gating (a SHOULD failure fails the run only with --strict): the vehicle requested item 0")
    suite = ET.parse(tmp_path / "default" / "run.junit.xml").getroot()
    assert suite.get("failures") == "0" and suite.get("errors") == "0"

    code, _, _ = _run(capsys, tmp_path / "strict", *argv, "--strict")
    assert code == 1
    failure = _junit_case(tmp_path / "strict", "MIS.UP.15").find("failure")
    assert failure is not None and failure.get("type") == "SHOULD"


def test_a_known_deviation_carries_its_reason_where_ci_shows_it(tmp_path, capsys) -> None:
    exp = tmp_path / "fork.toml"
    exp.write_text('[[deviation]]\nclause = "MIS.UP.16"\nvariant = "X1"\nreason = "keeps the plan on count 0"\n')
    code, _, _ = _run(capsys, tmp_path / "r", "--target", "mutant:count-zero-keeps-plan",
                      "--clauses", "MIS.UP.16", "--expect", str(exp))
    assert code == 0
    case = _junit_case(tmp_path / "r", "MIS.UP.16")
    assert case.find("failure") is None
    assert case.find("skipped").get("message").startswith("known deviation (X1: keeps the plan on count 0): ")
    properties = {p.get("name"): p.get("value") for p in case.find("properties")}
    assert properties["outcome"] == "known-deviation"
    assert properties["expectation"] == "X1: keeps the plan on count 0"


def test_a_baseline_runs_old_failure_is_not_a_junit_failure(tmp_path, capsys) -> None:
    argv = ("--target", "mutant:count-zero-keeps-plan", "--clauses", "MIS.UP.1[56]")
    assert _run(capsys, tmp_path / "base", *argv)[0] == 1
    assert _junit_case(tmp_path / "base", "MIS.UP.16").find("failure") is not None
    code, _, doc = _run(capsys, tmp_path / "again", *argv, "--baseline", str(tmp_path / "base" / "run.json"))
    assert code == 0 and doc["summary"]["gating_failures"] == 0
    case = _junit_case(tmp_path / "again", "MIS.UP.16")
    assert case.find("failure") is None and case.find("skipped").get("message").startswith(
        "not gating (not a regression: it did not pass in the baseline): ")


def test_an_older_run_json_still_serves_as_baseline_and_renders(tmp_path, capsys) -> None:
    """A run.json of format 1 (times in place) is read and upgraded, not refused."""
    assert _run(capsys, tmp_path / "new", "--clauses", "MIS.UP.01")[0] == 0
    doc = json.loads((tmp_path / "new" / "run.json").read_text())
    old = _stable(doc) | {"format": "mavconform-run/1"}
    volatile = doc["volatile"]
    old["run"] = {**doc["run"], "started": volatile["started"], "duration_s": volatile["duration_s"],
                  "forced_wait_s": volatile["forced_wait_s"]}
    old["identity"] = {**doc["identity"], "address": volatile["address"]}
    old["clauses"] = [{**c, "duration_s": clause_duration(doc, c), "exchange": clause_events(doc, c)}
                      for c in doc["clauses"]]
    (tmp_path / "old.json").write_text(json.dumps(old))
    assert _run(capsys, tmp_path / "b", "--clauses", "MIS.UP.01", "--baseline", str(tmp_path / "old.json"))[0] == 0
    assert main(["report", "render", str(tmp_path / "old.json"), "--dir", str(tmp_path / "re")]) == 0
    # format 1 had no place for our receive queues (volatile.receive_queue came later)
    volatile = {k: v for k, v in doc["volatile"].items() if k != "receive_queue"}
    assert load_run(tmp_path / "re" / "old.json") == doc | {"volatile": volatile}
