"""The spec-coverage map: every requirement sentence of seed 000 is listed with the clauses
that check it or why none does, and docs/spec-coverage.md is the map as it stands."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.conformance import catalogue, spec_coverage
from mavconform.conformance.clause import SEED_000, Role
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
    # both roles: the vehicle's clauses and the GCS's (MIS.G.*)
    missing = [(c.id, e.id) for c in catalogue.CLAUSES + catalogue.GCS_CLAUSES for e in spec_coverage.COVERAGE
               if spec_coverage.quotes(c, e) and c.id not in e.clauses
               and (c.id, e.id) not in spec_coverage.QUOTED_NOT_CHECKED]
    assert not missing


def test_each_quoted_but_unchecked_sentence_is_quoted_unmapped_and_says_why() -> None:
    for (clause, sentence), why in spec_coverage.QUOTED_NOT_CHECKED.items():
        entry = spec_coverage.BY_SENTENCE[sentence]
        assert spec_coverage.quotes(catalogue.BY_ID[clause], entry), (clause, sentence)
        assert clause not in entry.clauses, (clause, sentence)
        assert why, (clause, sentence)


def test_every_clause_of_both_roles_is_in_the_map() -> None:
    """Each clause is listed with a requirement sentence, or quotes a seed 000 sentence the rule
    does not find ("Other seed 000 sentences"), or comes from another source."""
    mapped = {c for e in spec_coverage.COVERAGE for c in e.clauses}
    elsewhere = {c.id for c in spec_coverage.unlisted_seed_clauses() + spec_coverage.other_source_clauses()}
    absent = [c.id for c in catalogue.BY_ID.values() if c.id not in mapped | elsewhere]
    assert not absent
    doc = spec_coverage.render_markdown()
    assert all(f"| {c.id} " in doc or f"{c.id} (" in doc for c in catalogue.BY_ID.values())


def test_every_gcs_clause_from_seed_000_is_accounted_for() -> None:
    """A GCS clause citing seed 000 is mapped to a requirement sentence or quotes one the rule
    does not find; one from another source is listed with those."""
    mapped = {c for e in spec_coverage.COVERAGE for c in e.clauses}
    unlisted = {c.id for c in spec_coverage.unlisted_seed_clauses()}
    others = {c.id for c in spec_coverage.other_source_clauses()}
    for clause in catalogue.GCS_CLAUSES:
        if clause.source.startswith(SEED_000 + ":"):
            assert clause.id in mapped or clause.id in unlisted, clause.id
        else:
            assert clause.id in others, clause.id


def test_a_gcs_side_sentence_no_clause_checks_says_so_and_checked_ones_do_not() -> None:
    for entry in spec_coverage.COVERAGE:
        gcs = [c for c in entry.clauses if catalogue.BY_ID[c].role is Role.GCS]
        if gcs:
            assert not entry.why.startswith(spec_coverage.GCS_SIDE), entry.id
    assert "the suite checks vehicles" not in spec_coverage.render_markdown()


def test_the_map_names_clauses_by_role() -> None:
    doc = spec_coverage.render_markdown()
    assert "MIS.G.DN.07 (SHOULD)" in doc and "on both sides" in doc


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
