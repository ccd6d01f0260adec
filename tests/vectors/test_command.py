"""`mavconform vectors generate`: writing elsewhere, --check naming what differs, usage mistakes."""

from __future__ import annotations

import json
from pathlib import Path

from mavconform.cli import main


def test_generate_then_check(tmp_path: Path, capsys) -> None:
    out = tmp_path / "v"
    assert main(["vectors", "generate", "--out", str(out)]) == 0
    said = capsys.readouterr().out
    assert "wrote 337 message vectors and 53 exchanges" in said and "message vectors/s" in said
    assert main(["vectors", "generate", "--out", str(out), "--check"]) == 0
    assert "identical to a regeneration" in capsys.readouterr().out
    mcap = out / "exchanges" / "px4" / "error-ack.mcap"
    mcap.write_bytes(mcap.read_bytes() + b"\0")
    (out / "exchanges" / "px4" / "left-over.json").write_text("{}")
    (out / "schema" / "exchange.schema.json").unlink()
    assert main(["vectors", "generate", "--out", str(out), "--check"]) == 1
    said = capsys.readouterr().out
    assert "DIFF exchanges/px4/error-ack.mcap: differs from a regeneration" in said
    assert "DIFF exchanges/px4/left-over.json: stale" in said
    assert "DIFF schema/exchange.schema.json: missing" in said
    assert main(["vectors", "generate", "--out", str(out)]) == 0      # regenerating removes what it no longer writes
    assert not (out / "exchanges" / "px4" / "left-over.json").exists()


def test_generate_for_a_users_dialect(tmp_path: Path, added_xml: Path, capsys) -> None:
    assert main(["vectors", "generate", "--out", str(tmp_path), "--dialect", str(added_xml)]) == 0
    assert "and 0 exchanges" in capsys.readouterr().out
    assert main(["vectors", "verify", str(tmp_path), "--dialect", str(added_xml)]) == 0
    assert main(["vectors", "verify", str(tmp_path)]) == 2     # made from another dialect
    assert "pass --dialect" in capsys.readouterr().err


def test_usage_mistakes_are_one_line_and_exit_2(tmp_path: Path, capsys) -> None:
    for argv, words in ((["vectors"], "vectors: the following arguments are required"),
                        (["vectors", "generate", "--dialect", str(tmp_path / "no.xml")], "no such file"),
                        (["vectors", "generate", "--seed", "x"], "vectors generate: argument --seed"),
                        (["vectors", "replay", "spec/upload-mission"], "the following arguments are required: --target")):
        try:
            code = main(argv)
        except SystemExit as exc:      # argparse's own complaints exit from inside parse_args
            code = exc.code
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2, argv
        assert len(err) == 1 and err[0].startswith("mavconform: error: ") and words in err[0], (argv, err)


def test_a_hand_edited_transcript_or_vector_line_is_one_line_not_a_traceback(tmp_path, capsys) -> None:
    """verify and replay read the files' keys: a missing one names the file and the key."""
    import shutil
    from mavconform.vectors import store
    copy = tmp_path / "v"
    shutil.copytree(store.DATA_DIR, copy, ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    transcript = copy / "exchanges" / "spec" / "upload-mission.json"
    doc = json.loads(transcript.read_text())
    del doc["events"][0]["hex"]
    transcript.write_text(json.dumps(doc))
    assert main(["vectors", "verify", str(copy)]) == 2
    assert capsys.readouterr().err.strip().endswith("upload-mission.json: events[0]: expected an object with hex, msg, from, to and t")
    (copy / "messages.jsonl").write_text('["not", "a", "vector"]\n')
    assert main(["vectors", "verify", str(copy)]) == 2
    assert capsys.readouterr().err.strip().endswith("messages.jsonl:1: expected a vector object with an id and hex")
