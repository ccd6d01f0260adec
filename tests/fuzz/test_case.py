"""Saved fuzz cases: canonical, lossless for the values fuzzing produces, strict on load."""

from __future__ import annotations

import json
import math

import pytest

from mavconform.fuzz.campaign import parse_duration
from mavconform.fuzz.case import Case, Violation, dump_case, load_case, save_case
from mavconform.reference_impl.errors import UsageError


def _case(**over) -> Case:
    base = dict(mode="protocol", target="builtin:spec", seed=7,
                steps=({"op": "upload", "x": float("nan"), "z": float("-inf"), "raw": b"\xfd\x00"},
                       {"op": "download", "mission_type": 1}),
                violation=Violation("atomic-upload", "stored plan is a mix", 1),
                found_by={"example": 12})
    base.update(over)
    return Case(**base)


def test_round_trip_keeps_nan_infinity_and_bytes(tmp_path) -> None:
    case = _case()
    path = save_case(case, tmp_path / "found")
    loaded = load_case(path)
    assert loaded.mode == case.mode and loaded.seed == 7 and loaded.target == "builtin:spec"
    assert math.isnan(loaded.steps[0]["x"]) and loaded.steps[0]["z"] == float("-inf")
    assert loaded.steps[0]["raw"] == b"\xfd\x00"
    assert loaded.violation == case.violation
    assert path.name == f"{case.name}.json" and case.name.startswith("protocol-atomic-upload-")
    assert dump_case(loaded) == path.read_text()   # canonical: loads and dumps to the same text


def test_name_depends_on_what_replays_not_on_who_found_it() -> None:
    assert _case().name == _case(found_by={"example": 99}).name
    assert _case().name != _case(seed=8).name


@pytest.mark.parametrize("doc, where", [
    ({"format": "other"}, "$.format"),
    ({"mode": "bytes"}, "$.mode"),
    ({"seed": "7"}, "$.seed"),
    ({"steps": [1, 2]}, "$.steps"),
    ({"violation": {"invariant": 3}}, "$.violation"),
    ({"target": ""}, "$.target"),
])
def test_a_bad_case_file_is_one_line_naming_file_and_key(tmp_path, doc, where) -> None:
    good = json.loads(dump_case(_case()))
    good.update(doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(good))
    with pytest.raises(UsageError) as err:
        load_case(path)
    assert str(path) in str(err.value) and where in str(err.value) and "\n" not in str(err.value)


def test_unreadable_and_non_json_cases(tmp_path) -> None:
    with pytest.raises(UsageError, match="cannot read fuzz case"):
        load_case(tmp_path / "missing.json")
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(UsageError, match="not a JSON fuzz case"):
        load_case(tmp_path / "x.json")


@pytest.mark.parametrize("text, seconds", [("90", 90), ("90s", 90), ("2m", 120), ("1.5m", 90), ("1h", 3600)])
def test_durations(text, seconds) -> None:
    assert parse_duration(text) == seconds


@pytest.mark.parametrize("text", ["", "s", "-5s", "0", "3x", "inf", "nan"])
def test_bad_durations(text) -> None:
    with pytest.raises(UsageError, match="bad duration"):
        parse_duration(text)
