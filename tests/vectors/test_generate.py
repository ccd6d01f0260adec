"""Generating vectors: the same bytes every time, the committed set current, every message of
the dialect covered by the documented rule (also one added to it), files matching their schemas."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mavconform.vectors import messages, store
from mavconform.vectors.dialect_info import load_dialect
from mavconform.vectors.schemas import EXCHANGE, MESSAGE_VECTOR

from .schema_check import problem


def _files(directory: Path) -> dict[str, bytes]:
    return {p.relative_to(directory).as_posix(): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


def test_generating_twice_gives_the_same_bytes(tmp_path: Path, dialect) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    store.generate(a, dialect)
    store.generate(b, dialect)
    first, second = _files(a), _files(b)
    assert first.keys() == second.keys()
    assert [name for name in first if first[name] != second[name]] == []
    assert any(name.endswith(".mcap") for name in first) and "messages.jsonl" in first


def test_the_committed_vectors_equal_a_regeneration(dialect) -> None:
    assert store.check(store.DATA_DIR, dialect) == [], \
        "the committed vectors are stale: run `mavconform vectors generate` and commit vectors/"


def test_another_seed_gives_other_values(dialect) -> None:
    one = {v["id"]: v["hex"] for v in messages.generate(dialect, 0)}
    two = {v["id"]: v["hex"] for v in messages.generate(dialect, 1)}
    assert one.keys() == two.keys()
    assert one["MISSION_ITEM_INT/v2-ext-set"] != two["MISSION_ITEM_INT/v2-ext-set"]


def test_every_message_of_the_dialect_has_its_vectors(committed, dialect) -> None:
    ids = [v["id"] for v in committed.messages]
    assert len(ids) == len(set(ids))
    have = set(ids)
    for m in dialect.messages:
        floats = any(f.is_float for f in m.fields)
        want = {"v2-zero", "v2-max", "v2-signed", "bad-crc", "length-over", "length-under", "wrong-key",
                "bad-signature", "v2-ext-zero" if m.has_extensions else "v2-typical"}
        if m.has_extensions:
            want.add("v2-ext-set")
        if floats:
            want |= {"v2-nan", "v2-inf", "v2-ninf", "v2-subnormal", "v2-negzero", "v2-min"}
        if m.fits_v1:
            want |= {"v1", "v1-short-payload"} if m.base_length > 1 else {"v1"}
        mine = {i.split("/", 1)[1] for i in have if i.split("/", 1)[0] == m.name}
        assert want <= mine, f"{m.name} lacks {sorted(want - mine)}"
        assert m.fits_v1 == ("v1" in mine)
    assert {"unknown-msgid/v1", "unknown-msgid/v2", "unknown-incompat-flag/v2"} <= have
    # positions: MISSION_ITEM_INT's x/y and GLOBAL_POSITION_INT's lat/lon at the poles and the antimeridian
    by_id = {v["id"]: v for v in committed.messages}
    assert by_id["MISSION_ITEM_INT/v2-latlon-max"]["fields"]["x"] == 900_000_000
    assert by_id["GLOBAL_POSITION_INT/v2-latlon-min"]["fields"]["lon"] == -1_800_000_000
    assert by_id["HEARTBEAT/v2-max"]["fields"]["mavlink_version"] == 3   # the encoder's, never edged


def test_vectors_say_what_the_issue_asks(committed) -> None:
    by_id = {v["id"]: v for v in committed.messages}
    zero = by_id["MISSION_ACK/v2-zero"]
    assert bytes.fromhex(zero["hex"])[1] == 1            # truncated to one payload byte
    ext_zero, ext_set = by_id["MISSION_ACK/v2-ext-zero"], by_id["MISSION_ACK/v2-ext-set"]
    assert ext_zero["fields"]["opaque_id"] == 0 and ext_set["fields"]["opaque_id"] != 0
    assert bytes.fromhex(ext_zero["hex"])[1] <= 3 < bytes.fromhex(ext_set["hex"])[1]
    v1 = by_id["MISSION_ITEM_INT/v1"]
    assert v1["version"] == 1 and bytes.fromhex(v1["hex"])[0] == 0xFE
    signed = by_id["MISSION_ITEM_INT/v2-signed"]
    assert signed["signed"] and signed["signature"]["link_id"] == messages.LINK_ID
    assert bytes.fromhex(signed["hex"])[2] == 0x01
    assert by_id["MISSION_ITEM_INT/v2-nan"]["fields"]["param1"] == "NaN"
    assert by_id["MISSION_ITEM_INT/v2-ninf"]["fields"]["z"] == "-Infinity"
    errors = {v["expected_error"] for v in committed.messages}
    assert errors == {None, "bad_crc", "bad_length", "unknown_msgid", "bad_signature", "unknown_incompat_flags"}
    timestamps = [v["signature"]["timestamp"] for v in committed.messages if v["signed"]]
    assert timestamps == sorted(timestamps) and len(set(timestamps)) == len(timestamps)


def test_every_file_matches_its_schema(committed) -> None:
    for vec in committed.messages:
        assert problem(vec, MESSAGE_VECTOR) is None, (vec["id"], problem(vec, MESSAGE_VECTOR))
    assert len(committed.exchanges) == 53     # 17 x 3 profiles + 2 handover
    for ex_id, path in committed.exchanges.items():
        transcript = json.loads(path.read_text())
        assert problem(transcript, EXCHANGE) is None, (ex_id, problem(transcript, EXCHANGE))
    written = {p.name: json.loads(p.read_text()) for p in (store.DATA_DIR / store.SCHEMA_DIR).glob("*.json")}
    assert written == {"message-vector.schema.json": MESSAGE_VECTOR, "exchange.schema.json": EXCHANGE}


def test_a_message_added_to_the_dialect_gets_vectors(tmp_path: Path, added_xml: Path) -> None:
    user = load_dialect(added_xml)
    done = store.generate(tmp_path, user)
    assert done.exchanges == 0 and not (tmp_path / "exchanges").exists()   # exchanges: our dialect only
    vset = store.load(tmp_path)
    added = {v["id"].split("/", 1)[1]: v for v in vset.messages if v["message"] == "VECTORS_TEST_ADDED"}
    assert {"v2-ext-zero", "v2-ext-set", "v2-latlon-max", "v2-nan", "v2-signed", "bad-crc"} <= added.keys()
    assert "v1" not in added                                # id 600 does not fit MAVLink 1
    assert added["v2-latlon-max"]["fields"]["lat"] == 900_000_000
    assert len(added["v2-max"]["fields"]["label"]) == 10 and added["v2-min"]["fields"]["triple"] == [-32768] * 3
    assert vset.index["dialect"]["file"] == "vectors_test_dialect.xml"


def test_a_bad_dialect_is_a_usage_error(tmp_path: Path) -> None:
    from mavconform.reference_impl.errors import UsageError
    with pytest.raises(UsageError, match="no such file"):
        load_dialect(tmp_path / "missing.xml")
    broken = tmp_path / "broken.xml"
    broken.write_text("<mavlink><messages><message")
    with pytest.raises(UsageError, match="broken.xml"):
        load_dialect(broken)
