import enum
import json

import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reports.run_document import FORMAT, OUTCOMES, check_run, dump_run, load_run


def write(tmp_path, text, name="run.json"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_dump_is_canonical_and_round_trips(doc, tmp_path):
    text = dump_run(doc)
    assert text.endswith("}\n") and not text.endswith("\n\n")
    plain = json.dumps(doc, sort_keys=True, indent=2, ensure_ascii=False, allow_nan=False)
    assert text == plain.replace("\ud800", "\\ud800") + "\n"  # (see the surrogate test)
    loaded = load_run(write(tmp_path, text))
    assert loaded == doc
    assert dump_run(loaded) == text
    # key order of the input does not matter
    shuffled = dict(reversed(list(doc.items())))
    shuffled["run"] = dict(reversed(list(doc["run"].items())))
    assert dump_run(shuffled) == text


def test_dump_keeps_unicode_and_escapes_a_lone_surrogate(doc):
    text = dump_run(doc)
    assert "\u202e" in text and "\\ud800" in text
    text.encode("utf-8")  # writable as UTF-8
    assert json.loads(text) == doc


def test_dump_refuses_nan(doc):
    doc["volatile"]["duration_s"] = float("nan")
    with pytest.raises(ValueError):
        dump_run(doc)


def test_a_clause_may_say_which_event_decided_it(doc, tmp_path):
    """`decided_by` is optional (older documents lack it), an index or null, and stable: it
    is kept outside `volatile`, in the same format."""
    doc["clauses"][1]["decided_by"] = 6
    doc["clauses"][0]["decided_by"] = None
    assert load_run(write(tmp_path, dump_run(doc)))["clauses"][1]["decided_by"] == 6
    assert doc["format"] == FORMAT == "mavconform-run/2"


def test_load_accepts_a_null_identity_and_capture(doc, tmp_path):
    doc["identity"] = None
    doc["capture"] = None
    assert load_run(write(tmp_path, dump_run(doc))) == doc


def test_outcome_names():
    assert OUTCOMES == ("pass", "fail", "known-deviation", "not-applicable", "skipped", "error")
    assert FORMAT == "mavconform-run/2"


def bad(doc, path, value):
    """`doc` with the value at `path` (keys and indices) replaced, or deleted if DELETE."""
    *parents, last = path
    node = doc
    for key in parents:
        node = node[key]
    if value is DELETE:
        del node[last]
    else:
        node[last] = value
    return doc


DELETE = object()

BAD_DOCUMENTS = [
    # (path to change, new value, expected message after "run.json: ")
    (("format",), "mavconform-run/3",
     "format: expected 'mavconform-run/2', found 'mavconform-run/3'"),
    (("format",), DELETE, "missing 'format'"),
    (("summary",), DELETE, "missing 'summary'"),
    (("clauses", 3, "outcome"), DELETE, "clauses[3]: missing 'outcome'"),
    (("clauses", 3, "outcome"), "passed", "clauses[3].outcome: expected one of 'pass',"),
    (("clauses", 1, "level"), "MUST NOT", "clauses[1].level: expected one of 'MUST',"),
    (("clauses", 0, "gating"), "yes", "clauses[0].gating: expected a bool, found the string 'yes'"),
    (("volatile", "clauses", "MIS.UP.01", "duration_s"), True,
     "volatile.clauses.MIS.UP.01.duration_s: expected a number, found a bool"),
    (("clauses", 0, "expectation"), 3, "clauses[0].expectation: expected a string or null"),
    (("clauses", 0, "exchange"), {}, "clauses[0].exchange: expected an array, found an object"),
    (("clauses", 1, "exchange", 2, "dir"), "in", "clauses[1].exchange[2].dir: expected one of"),
    (("volatile", "clauses", "MIS.UP.07", "events", 2), "0.1",
     "volatile.clauses.MIS.UP.07.events[2]: expected a number"),
    (("clauses", 1, "exchange", 2, "fields"), DELETE, "clauses[1].exchange[2]: missing 'fields'"),
    (("clauses", 1, "exchange", 2, "fields", "seq"), {"a": 1},
     "clauses[1].exchange[2].fields.seq: expected a string or a number or a bool or null"),
    (("clauses", 2, "id"), "MIS.UP.01", "clauses[2].id: 'MIS.UP.01' is already clauses[0]"),
    (("clauses", 1, "decided_by"), "3", "clauses[1].decided_by: expected an integer or null"),
    (("clauses", 1, "decided_by"), True, "clauses[1].decided_by: expected an integer or null"),
    (("clauses", 1, "decided_by"), 7, "clauses[1].decided_by: 7 is not the index of an event in "
                                      "the exchange (7 events)"),
    (("clauses", 1, "decided_by"), -1, "clauses[1].decided_by: -1 is not the index of an event"),
    (("clauses", 4), "MIS.CLR.03", "clauses[4]: expected an object, found the string"),
    (("clauses",), {}, "clauses: expected an array, found an object"),
    (("tool", "version"), 1, "tool.version: expected a string, found the number 1"),
    (("run", "target"), DELETE, "run: missing 'target'"),
    (("run", "seed"), 1.5, "run.seed: expected an integer or null, found the number 1.5"),
    (("run", "extra"), [1], "run.extra: expected a string or a number or a bool or null"),
    (("identity",), "1/1", "identity: expected an object or null, found the string '1/1'"),
    (("identity", "system"), DELETE, "identity: missing 'system'"),
    (("gating", "mode"), "lenient", "gating.mode: expected one of 'strict', 'default', 'baseline'"),
    (("gating", "regressions", 0), 7, "gating.regressions[0]: expected a string"),
    (("restore", "status"), "ok", "restore.status: expected one of"),
    (("capture",), 0, "capture: expected a string or null, found the number 0"),
    (("summary", "total"), 7, "summary.total: 7, but there are 6 clauses"),
    (("summary", "fail"), 0, "summary.fail: 0, but 1 clauses have outcome 'fail'"),
    (("summary", "error"), -1, "summary.error: expected a count, found -1"),
    (("summary", "gating_failures"), 1, "summary.gating_failures: 1, but 2 clauses are gating"),
    (("summary", "verdict"), "FAIL", "summary.verdict: expected one of 'pass', 'fail'"),
    # format 2: what differs run to run lives in `volatile`, and only there
    (("run", "started"), "2026-11-22T10:00:00Z",
     "run.started: belongs in the volatile section, not here (mavconform-run/2)"),
    (("run", "forced_wait_s"), 9.1, "run.forced_wait_s: belongs in the volatile section"),
    (("identity", "address"), "127.0.0.1:40001", "identity.address: belongs in the volatile"),
    (("clauses", 0, "duration_s"), 0.31, "clauses[0].duration_s: belongs in the volatile"),
    (("clauses", 1, "exchange", 2, "t"), 0.1, "clauses[1].exchange[2].t: belongs in the volatile"),
    (("volatile",), DELETE, "missing 'volatile'"),
    (("volatile", "started"), DELETE, "volatile: missing 'started'"),
    (("volatile", "duration_s"), -1, "volatile.duration_s: negative duration -1"),
    (("volatile", "address"), 40001, "volatile.address: expected a string or null"),
    (("volatile", "clauses", "MIS.UP.01"), DELETE, "volatile.clauses: missing 'MIS.UP.01'"),
    (("volatile", "clauses", "MIS.GONE.01"), {"duration_s": 0, "events": []},
     "volatile.clauses.MIS.GONE.01: no clause has this id"),
    (("volatile", "clauses", "MIS.UP.01", "events"), [0.0],
     "volatile.clauses.MIS.UP.01.events: 1 times for 4 exchange events"),
    (("volatile", "clauses", "MIS.CUR.04", "detail", "delay"), 0.253,
     "volatile.clauses.MIS.CUR.04.detail.delay: expected a string, found the number 0.253"),
    (("volatile", "clauses", "MIS.UP.07", "notes"), {"0": {"waited": "1.5"}},
     "volatile.clauses.MIS.UP.07.notes.0: not the index of a note in the exchange"),
    (("volatile", "receive_queue"), 12, "volatile.receive_queue: expected an object, found the number 12"),
    (("volatile", "receive_queue"), {"buffer_bytes": None}, "volatile.receive_queue: missing 'dropped'"),
    (("volatile", "receive_queue"), {"dropped": -1, "buffer_bytes": None},
     "volatile.receive_queue.dropped: expected a count, found -1"),
    (("volatile", "receive_queue"), {"dropped": 0, "buffer_bytes": "8 MiB"},
     "volatile.receive_queue.buffer_bytes: expected an integer or null, found the string '8 MiB'"),
]


@pytest.mark.parametrize("path, value, message", BAD_DOCUMENTS,
                         ids=[".".join(map(str, p)) for p, _, _ in BAD_DOCUMENTS])
def test_load_rejects_a_bad_shape_in_one_line_naming_file_and_path(doc, tmp_path, path, value,
                                                                    message):
    file = write(tmp_path, json.dumps(bad(doc, path, value)))
    with pytest.raises(UsageError) as caught:
        load_run(file)
    text = str(caught.value)
    assert text.startswith(f"{file}: {message}"), text
    assert "\n" not in text


@pytest.mark.parametrize("text, message", [
    ("", "line 1 column 1: invalid JSON: Expecting value"),
    ('{"format": ', "line 1 column 12: invalid JSON"),
    ("[1, 2]", "expected a JSON object, found an array"),
    ('{"format": 1}', "format: expected 'mavconform-run/2', found the number 1"),
    ("[" * 100_000, "invalid JSON: nested too deeply"),
])
def test_load_rejects_what_is_not_a_run_document(tmp_path, text, message):
    file = write(tmp_path, text)
    with pytest.raises(UsageError) as caught:
        load_run(file)
    assert str(caught.value).startswith(f"{file}: {message}"), str(caught.value)


def test_load_rejects_nan_literals_with_their_path(doc, tmp_path):
    text = dump_run(doc).replace('"x": 473977418', '"x": NaN')
    with pytest.raises(UsageError) as caught:
        load_run(write(tmp_path, text))
    assert str(caught.value) == (f"{tmp_path / 'run.json'}: clauses[0].exchange[2].fields.x: "
                                 "NaN is not a JSON number (write it as a string)")


def test_load_reports_a_missing_or_unreadable_file_in_one_line(tmp_path):
    missing = tmp_path / "nope.json"
    with pytest.raises(UsageError, match=r"nope\.json: cannot read: No such file"):
        load_run(missing)
    latin = tmp_path / "latin.json"
    latin.write_bytes(b'{"format": "\xe9"}')
    with pytest.raises(UsageError, match=r"latin\.json: cannot read: not UTF-8 text"):
        load_run(latin)
    with pytest.raises(UsageError, match=r"cannot read: Is a directory"):
        load_run(tmp_path)


def test_messages_stay_on_one_line_whatever_the_value(doc, tmp_path):
    doc["clauses"][0]["level"] = "MUST\nNOT\r\x00"
    with pytest.raises(UsageError) as caught:
        load_run(write(tmp_path, json.dumps(doc)))
    assert "\n" not in str(caught.value) and "\r" not in str(caught.value)
    assert "clauses[0].level" in str(caught.value)


def test_check_run_names_an_in_memory_document(doc):
    doc["clauses"][0]["exchange"][0]["fields"]["x"] = float("inf")
    with pytest.raises(UsageError, match=r"^run document: clauses\[0\]\.exchange\[0\]\.fields\.x: "
                                         "inf is not a JSON number"):
        check_run(doc)


def test_check_run_wants_plain_strings_not_enum_members(doc):
    class Outcome(str, enum.Enum):
        PASS = "pass"

    doc["clauses"][0]["outcome"] = Outcome.PASS
    with pytest.raises(UsageError, match=r"^run document: clauses\[0\]\.outcome: expected a "
                                         r"string, found Outcome 'pass' \(write its \.value\)$"):
        check_run(doc)


def test_check_run_refuses_the_older_format_in_one_line_saying_what_to_do():
    from .sample import run_document_1
    with pytest.raises(UsageError) as caught:
        check_run(run_document_1())
    assert str(caught.value) == ("run document: format: 'mavconform-run/1' is the older layout, "
                                 "with its times in place: read it with load_run, which upgrades it")


def test_load_upgrades_the_older_format_without_losing_a_value(tmp_path):
    """An old run.json still serves as --baseline and for `report render`: its times move
    into `volatile`, where the accessors find them as they found them in place."""
    from mavconform.reports.run_document import clause_duration, clause_events, run_facts
    from .sample import run_document_1
    old = run_document_1()
    loaded = load_run(write(tmp_path, json.dumps(old)))
    assert loaded["format"] == FORMAT and check_run(loaded) is loaded
    assert "started" not in loaded["run"] and "address" not in loaded["identity"]
    assert run_facts(loaded) == {"started": "2026-11-22T10:00:00Z", "duration_s": 12.5,
                                 "forced_wait_s": 9.1, "address": "127.0.0.1:40001"}
    for before, after in zip(old["clauses"], loaded["clauses"]):
        assert clause_events(loaded, after) == before["exchange"]
        assert clause_duration(loaded, after) == before["duration_s"]
        assert {k: v for k, v in after.items()} == {k: v for k, v in before.items()
                                                    if k not in ("duration_s", "exchange")} | {
            "exchange": [{k: v for k, v in e.items() if k != "t"} for e in before["exchange"]]}
    assert load_run(write(tmp_path, dump_run(loaded), "again.json")) == loaded   # and stays so


def test_an_older_document_is_checked_as_what_it_was(tmp_path):
    from .sample import run_document_1
    old = run_document_1()
    del old["clauses"][1]["exchange"][2]["t"]
    with pytest.raises(UsageError, match=r"clauses\[1\]\.exchange\[2\]: missing 't'"):
        load_run(write(tmp_path, json.dumps(old)))


def test_the_accessors_put_back_times_and_measured_numbers(doc):
    from mavconform.reports.run_document import (clause_detail, clause_duration, clause_events,
                                                 run_facts)
    failed, error = doc["clauses"][1], doc["clauses"][5]
    events = clause_events(doc, failed)
    assert [e["t"] for e in events] == [10.0, 10.0012, 10.002, 10.1, 10.101, 10.2, 11.5]
    assert events[6]["msg"] == "expect MISSION_REQUEST_INT seq=1 within 1.5 s: nothing in 1.5002 s"
    assert failed["exchange"][6]["msg"].endswith("nothing in <waited> s")   # the document's own
    assert "t" not in failed["exchange"][0]                                 # left as it was
    assert clause_detail(doc, error) == "got MISSION_REQUEST_INT{seq=0} after 0.253 s; expected none"
    assert clause_detail(doc, failed) == failed["detail"]                   # nothing measured
    assert clause_duration(doc, error) == 0.31
    assert run_facts(doc) == {"started": "2026-11-22T10:00:00Z", "duration_s": 12.5,
                              "forced_wait_s": 9.1, "address": "127.0.0.1:40001"}
