"""Issue 13 for fuzz.json: two campaigns with the same seed and budget differ only in the
document's `volatile` section (when each started, how long it took, event times)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from mavconform.reports.run_document import clause_duration, clause_events, load_run, run_facts


def _campaign(folder: Path, findings: Path, *args: str) -> tuple[int, dict]:
    """One campaign, as a user runs it: its own process (Hypothesis keeps state across
    campaigns in one process, which changes what a second one draws)."""
    done = subprocess.run([sys.executable, "-m", "mavconform", "fuzz", "--seed", "1", "--database", "none",
                           "--findings", str(findings), "--report-dir", str(folder), "-q", *args],
                          capture_output=True, text=True, timeout=300)
    return done.returncode, load_run(folder / "fuzz.json")


def _stable(doc: dict) -> dict:
    return {key: value for key, value in doc.items() if key != "volatile"}


def test_two_seeded_campaigns_differ_only_in_the_volatile_section(tmp_path) -> None:
    runs = [_campaign(tmp_path / str(i), tmp_path / f"found{i}", "--target", "builtin:spec",
                      "--examples", "50") for i in (1, 2)]
    (code1, first), (code2, second) = runs
    assert code1 == code2 == 0
    assert _stable(first) == _stable(second)
    for doc in (first, second):
        facts = run_facts(doc)
        assert facts["started"] and facts["duration_s"] > 0
        assert "started" not in doc["run"] and "duration_s" not in doc["run"]
        assert {c["id"] for c in doc["clauses"]} == set(doc["volatile"]["clauses"])


def test_a_finding_keeps_its_exchange_times_in_the_volatile_section(tmp_path) -> None:
    """A finding's replayed exchange is drawn with its times: they come from `volatile`."""
    found = tmp_path / "found"   # the same folder: the saved case's name and path are its own
    runs = [_campaign(tmp_path / str(i), found, "--target", "mutant:raises-on-truncated-frame",
                      "--mode", "frames", "--examples", "200") for i in (1, 2)]
    (code1, first), (code2, second) = runs
    assert code1 == code2 == 1
    assert _stable(first) == _stable(second)
    row = next(c for c in first["clauses"] if c["outcome"] == "fail")
    events = clause_events(first, row)
    assert events and all("t" not in e for e in row["exchange"])
    assert [e["t"] for e in events] == first["volatile"]["clauses"][row["id"]]["events"]
    assert clause_duration(first, row) == 0.0
