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
    doc["run"]["duration_s"] = float("nan")
    with pytest.raises(ValueError):
        dump_run(doc)


def test_load_accepts_a_null_identity_and_capture(doc, tmp_path):
    doc["identity"] = None
    doc["capture"] = None
    assert load_run(write(tmp_path, dump_run(doc))) == doc


def test_outcome_names():
    assert OUTCOMES == ("pass", "fail", "known-deviation", "not-applicable", "skipped", "error")
    assert FORMAT == "mavconform-run/1"


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
    (("format",), "mavconform-run/2",
     "format: expected 'mavconform-run/1', found 'mavconform-run/2'"),
    (("format",), DELETE, "missing 'format'"),
    (("summary",), DELETE, "missing 'summary'"),
    (("clauses", 3, "outcome"), DELETE, "clauses[3]: missing 'outcome'"),
    (("clauses", 3, "outcome"), "passed", "clauses[3].outcome: expected one of 'pass',"),
    (("clauses", 1, "level"), "MUST NOT", "clauses[1].level: expected one of 'MUST',"),
    (("clauses", 0, "gating"), "yes", "clauses[0].gating: expected a bool, found the string 'yes'"),
    (("clauses", 0, "duration_s"), True, "clauses[0].duration_s: expected a number, found a bool"),
    (("clauses", 0, "expectation"), 3, "clauses[0].expectation: expected a string or null"),
    (("clauses", 0, "exchange"), {}, "clauses[0].exchange: expected an array, found an object"),
    (("clauses", 1, "exchange", 2, "dir"), "in", "clauses[1].exchange[2].dir: expected one of"),
    (("clauses", 1, "exchange", 2, "t"), "0.1", "clauses[1].exchange[2].t: expected a number"),
    (("clauses", 1, "exchange", 2, "fields"), DELETE, "clauses[1].exchange[2]: missing 'fields'"),
    (("clauses", 1, "exchange", 2, "fields", "seq"), {"a": 1},
     "clauses[1].exchange[2].fields.seq: expected a string or a number or a bool or null"),
    (("clauses", 2, "id"), "MIS.UP.01", "clauses[2].id: 'MIS.UP.01' is already clauses[0]"),
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
    ('{"format": 1}', "format: expected 'mavconform-run/1', found the number 1"),
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
