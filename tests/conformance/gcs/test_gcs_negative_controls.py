"""The GCS checks prove they can fail: every GCS clause passes on the reference GCS, each
mutant GCS (conformance/gcs/mutants.py) fails exactly the clauses it claims to break and
passes every other one, and every GCS clause is broken by some mutant.

In virtual time (SimStage): a whole run of the 37 clauses takes milliseconds.
"""

from __future__ import annotations

import re

import pytest

from mavconform.conformance.gcs.adapters import NodeAdapter
from mavconform.conformance.gcs.clauses import GCS_CLAUSES
from mavconform.conformance.gcs.harness import GcsHarness
from mavconform.conformance.gcs.mutants import GCS_MUTANTS
from mavconform.conformance.gcs.runner import run_gcs_clauses
from mavconform.conformance.outcome import ClauseResult, Outcome


def _run(adapter: NodeAdapter) -> dict[str, ClauseResult]:
    h = GcsHarness(adapter, real_time=False, timeout_s=30)
    return {r.clause_id: r for r in run_gcs_clauses(h, GCS_CLAUSES).results}


def test_every_gcs_clause_passes_on_the_reference_gcs() -> None:
    results = _run(NodeAdapter())
    assert set(results) == {c.id for c in GCS_CLAUSES}
    bad = {k: (r.outcome.value, r.detail) for k, r in results.items() if r.outcome is not Outcome.PASS}
    assert not bad


def test_every_gcs_clause_has_a_mutant_that_breaks_it() -> None:
    ids = {c.id for c in GCS_CLAUSES}
    covered = set().union(*(mu.breaks for mu in GCS_MUTANTS.values()))
    assert sorted(ids - covered) == [], "GCS clauses no mutant breaks"
    assert sorted(covered - ids) == [], "mutants claim to break unknown clauses"


def test_gcs_mutants_are_named_and_described() -> None:
    for name, mu in GCS_MUTANTS.items():
        assert mu.name == name and re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", name), name
        assert mu.breaks and mu.description and "\n" not in mu.description, name


@pytest.mark.parametrize("name", sorted(GCS_MUTANTS))
def test_gcs_mutant_fails_exactly_the_clauses_it_breaks(name: str) -> None:
    mutant = GCS_MUTANTS[name]
    results = _run(NodeAdapter(name, build=mutant.build))
    unexpected = {k: (r.outcome.value, r.detail) for k, r in results.items()
                  if k not in mutant.breaks and r.outcome is not Outcome.PASS}
    missed = {k: (results[k].outcome.value, results[k].detail) for k in sorted(mutant.breaks)
              if results[k].outcome is not Outcome.FAIL}
    assert not unexpected and not missed, f"not passed though not broken: {unexpected}; not failed: {missed}"
