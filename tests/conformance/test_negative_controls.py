"""The suite proves it can fail: every clause passes on the spec vehicle, fails on every
mutant that breaks it, and no mutant fails a clause it does not claim to break.

Run in virtual time (SimNetwork): the same checks and vehicles as over UDP, milliseconds
per clause. The UDP run of the whole suite is the README's main job, in `.ci/run`.
"""

from __future__ import annotations

import pytest

from mavconform.conformance.catalogue import CLAUSES
from mavconform.conformance.mutants import MUTANTS
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target


def _run(uri: str) -> dict[str, object]:
    with Session(parse_target(uri), virtual=True) as session:
        return {r.clause_id: r for r in run_clauses(session, CLAUSES).results}


@pytest.fixture(scope="module")
def spec_results():
    return _run("builtin:spec")


def test_every_clause_passes_on_the_spec_vehicle(spec_results) -> None:
    bad = {k: (r.outcome.value, r.detail) for k, r in spec_results.items() if r.outcome is not Outcome.PASS}
    assert not bad


def test_every_clause_has_a_mutant_that_breaks_it() -> None:
    covered = set().union(*(m.breaks for m in MUTANTS.values()))
    unbroken = sorted(c.id for c in CLAUSES if c.id not in covered)
    assert unbroken == [], f"clauses no mutant breaks: {unbroken}"
    assert covered <= {c.id for c in CLAUSES}, "a mutant claims to break an unknown clause"


@pytest.mark.parametrize("name", sorted(MUTANTS))
def test_mutant_fails_exactly_the_clauses_it_breaks(name: str) -> None:
    results = _run(f"mutant:{name}")
    failed = {k for k, r in results.items() if r.outcome is Outcome.FAIL}
    expected = set(MUTANTS[name].breaks)
    detail = {k: results[k].detail for k in failed ^ expected}
    assert failed == expected, f"unexpected: {sorted(failed - expected)}; missed: {sorted(expected - failed)}; {detail}"


def test_the_run_is_deterministic_in_virtual_time() -> None:
    a, b = _run("mutant:non-atomic-upload"), _run("mutant:non-atomic-upload")
    assert [(k, r.outcome, r.detail) for k, r in a.items()] == [(k, r.outcome, r.detail) for k, r in b.items()]
