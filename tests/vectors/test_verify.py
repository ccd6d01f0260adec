"""Our codec against the vectors: every vector agrees but the listed known deviations, and the
checker itself notices a wrong field, a wrong byte, a wrong expected error (negative controls)."""

from __future__ import annotations

import copy
import json
import shutil
from pathlib import Path

from mavconform.cli import main
from mavconform.vectors import deviations, store, verify


def _ours(committed, dialect) -> verify.Report:
    results = {v["id"]: verify.ours(v, dialect) for v in committed.messages}
    return verify.check("ours", committed.messages, results, dialect)


def test_our_codec_agrees_with_every_vector_but_the_known_deviations(committed, dialect) -> None:
    sorted_ = deviations.sort(_ours(committed, dialect), deviations.load())
    assert [str(m) for m in sorted_.unexpected] == []
    assert sorted_.unused == []             # the list is exact: nothing listed that no longer happens
    assert {m.vector.split("/")[1] for m, _ in sorted_.known} == {"v1-short-payload"}


def test_every_exchange_frame_decodes_and_reencodes_to_its_bytes(committed, dialect) -> None:
    for ex_id, path in committed.exchanges.items():
        assert verify.exchange_frames(store.read_transcript(path), dialect) == [], ex_id


def test_the_checker_notices_a_wrong_field_byte_or_error(committed, dialect) -> None:
    by_id = {v["id"]: v for v in committed.messages}
    vec = by_id["MISSION_ITEM_INT/v2-ext-set"]
    good = verify.ours(vec, dialect)
    assert verify.judge(vec, good, dialect) == []
    wrong_field = copy.deepcopy(vec)
    wrong_field["fields"]["z"] = 1.5
    assert any(line.startswith("z: expected 1.5") for line in verify.judge(wrong_field, good, dialect))
    negzero = by_id["MISSION_ITEM_INT/v2-negzero"]
    as_zero = dict(verify.ours(negzero, dialect), fields=dict(negzero["fields"], param1=0.0))
    assert any(line.startswith("param1:") for line in verify.judge(negzero, as_zero, dialect))   # -0.0 != 0.0
    flipped = copy.deepcopy(vec)
    raw = bytearray.fromhex(vec["hex"])
    raw[12] ^= 0x01
    flipped["hex"] = raw.hex()
    assert verify.judge(flipped, verify.ours(flipped, dialect), dialect) == \
        ["refused as bad_crc (" + verify.ours(flipped, dialect)["detail"] + ")"]
    bad = by_id["MISSION_ITEM_INT/bad-crc"]
    relabelled = dict(bad, expected_error="bad_length")
    assert verify.judge(relabelled, verify.ours(bad, dialect), dialect)[0].startswith("refused as bad_crc")
    assert verify.judge(bad, {"id": bad["id"], "ok": True, "msgid": 73}, dialect)[0].startswith("accepted")
    assert verify.judge(vec, None, dialect) == ["no result for this vector"]


def test_verify_command(tmp_path: Path, capsys) -> None:
    assert main(["vectors", "verify"]) == 0
    out = capsys.readouterr().out
    assert "0 unexpected" in out and "53 exchanges" in out
    copy_dir = tmp_path / "v"
    shutil.copytree(store.DATA_DIR, copy_dir, ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    lines = (copy_dir / store.MESSAGES).read_text().splitlines()
    vec = json.loads(lines[1])
    vec["fields"]["custom_mode"] = 7
    lines[1] = store.dumps(vec)
    (copy_dir / store.MESSAGES).write_text("\n".join(lines) + "\n")
    assert main(["vectors", "verify", str(copy_dir)]) == 1
    assert f"FAIL {vec['id']}: custom_mode: expected 7" in capsys.readouterr().out


def test_verify_usage_mistakes_are_one_line(tmp_path: Path, capsys) -> None:
    assert main(["vectors", "verify", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mavconform: error: cannot read") and "index.json" in err[0]
