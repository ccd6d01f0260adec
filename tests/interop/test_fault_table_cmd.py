"""`mavconform fault-table`: output forms, exit codes, usage mistakes."""

from __future__ import annotations

import json

import pytest

from mavconform.cli import main


def test_json_for_one_profile(capsys):
    assert main(["fault-table", "--profile", "px4", "--format", "json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    cells = doc["fault_table"]["cells"]
    assert {c["profile"] for c in cells} == {"px4"} and len(cells) == len(doc["fault_table"]["modes"])
    assert all(c["text"].startswith(("recovers", "fails cleanly")) for c in cells)
    assert doc["round_trips"][0]["ok"]


def test_markdown_to_a_file(tmp_path, capsys):
    out = tmp_path / "ft.md"
    assert main(["fault-table", "--profile", "spec", "--output", str(out)]) == 0
    text = out.read_text()
    assert "| failure mode | QGC expects | spec |" in text and "`FailWriteFinalAckErrorAck`" in text
    assert f"wrote {out}" in capsys.readouterr().out


def test_the_help_explains():
    with pytest.raises(SystemExit) as exc:
        main(["fault-table", "--help"])
    assert exc.value.code == 0


@pytest.mark.parametrize("argv, needle", [
    (["fault-table", "--profile", "nope"], "no such profile"),
    (["fault-table", "--profile", "px4", "--profile", "px4"], "named twice"),
    (["fault-table", "--output", "/nonexistent-dir/x.md"], "no such directory"),
    (["fault-table", "--format", "xml"], "invalid choice"),
])
def test_usage_mistakes_exit_2_with_one_line(argv, needle, capsys):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert needle in err and len(err.splitlines()) == 1
