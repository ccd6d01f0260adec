"""The spec-coverage map: every requirement sentence of seed 000 is listed with the clauses
that check it or why none does, and docs/spec-coverage.md is the map as it stands."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.conformance import catalogue, spec_coverage
from mavconform.conformance.clause import SEED_000
from mavconform.cli import main

ROOT = Path(__file__).resolve().parents[2]
SHARED = ROOT.parent / "shared"
DOC = ROOT / "docs" / "spec-coverage.md"


def test_the_committed_doc_is_the_map_as_it_stands() -> None:
    assert DOC.read_text(encoding="utf-8") == spec_coverage.render_markdown(), (
        "docs/spec-coverage.md is stale: run `mavconform clauses --coverage --output docs/spec-coverage.md`")


def test_the_command_writes_the_doc(tmp_path, capsys) -> None:
    out = tmp_path / "coverage.md"
    assert main(["clauses", "--coverage", "--output", str(out)]) == 0
    assert out.read_text(encoding="utf-8") == spec_coverage.render_markdown()
    assert main(["clauses", "--coverage"]) == 0
    assert capsys.readouterr().out.endswith(spec_coverage.render_markdown())


@pytest.mark.parametrize("argv,message", [
    (["clauses", "--output", "x.md"], "only with --coverage"),
    (["clauses", "--coverage", "--level", "MUST"], "no other option"),
    (["clauses", "--coverage", "--output", "/nonexistent-dir/x.md"], "no such directory"),
])
def test_coverage_usage_mistakes(argv, message, capsys) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_every_entry_names_existing_clauses_or_says_why_none() -> None:
    for entry in spec_coverage.COVERAGE:
        assert entry.clauses or entry.why, entry.id
        unknown = [c for c in entry.clauses if c not in catalogue.BY_ID]
        assert not unknown, (entry.id, unknown)
        assert len(set(entry.clauses)) == len(entry.clauses), entry.id


def test_a_clause_that_quotes_a_listed_sentence_is_mapped_to_it() -> None:
    missing = [(c.id, e.id) for c in catalogue.CLAUSES for e in spec_coverage.COVERAGE
               if spec_coverage.quotes(c, e) and c.id not in e.clauses]
    assert not missing


def test_the_sentence_splitter_keeps_abbreviations() -> None:
    split = spec_coverage.split_sentences
    assert split("Send it (e.g. MISSION_COUNT). Then  wait!  Done") == [
        "Send it (e.g. MISSION_COUNT).", "Then wait!", "Done"]


@pytest.mark.skipif(not (SHARED / "seeds").is_dir(), reason="../shared/seeds is not beside the project")
def test_the_rule_finds_exactly_the_listed_sentences() -> None:
    text = (SHARED / SEED_000).read_text(encoding="utf-8")
    found = [(s.id, s.text) for s in spec_coverage.requirement_sentences(text)]
    listed = [(e.id, e.text) for e in spec_coverage.COVERAGE]
    assert [f for f in found if f not in listed] == [], "requirement sentences not in the map"
    assert [x for x in listed if x not in found] == [], "mapped sentences the rule does not find"
    assert found == listed, "the map lists the sentences out of order"
