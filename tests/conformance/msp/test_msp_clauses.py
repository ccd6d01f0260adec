"""The MSP clauses prove they can fail: each passes on builtin:msp, fails on every mutant that
breaks it, and no mutant fails a clause it does not claim; each quotes its source.

Virtual time (SimNetwork) here; over real TCP loopback and from the command line in
test_msp_run.py.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from mavconform.conformance import catalogue
from mavconform.conformance.clause import Clause, Role
from mavconform.conformance.msp.checks import MSP_CHECKS
from mavconform.conformance.msp.clauses import INAV, MSP_CLAUSES
from mavconform.conformance.msp.mutants import MSP_MUTANTS
from mavconform.conformance.msp.runner import run_msp_clauses
from mavconform.conformance.msp.session import MspSession
from mavconform.conformance.msp.target import parse_msp_target
from mavconform.conformance.outcome import Outcome

SHARED = Path(__file__).resolve().parents[4] / "shared"
INAV_SOURCE = os.environ.get("MAVCONFORM_INAV_SOURCE")   # an INAV 9.1 tree, to check the INAV quotes


def _run(target: str) -> dict:
    with MspSession(parse_msp_target(target), virtual=True) as session:
        return {r.clause_id: r for r in run_msp_clauses(session, MSP_CLAUSES).results}


def test_every_msp_clause_has_one_check_and_is_its_role() -> None:
    assert {c.id for c in MSP_CLAUSES} == set(MSP_CHECKS)
    assert all(c.role is Role.MSP and c.id.startswith("MSP.") for c in MSP_CLAUSES)
    assert catalogue.select("msp.wp.0[12]", role=Role.MSP)[1].id == "MSP.WP.02"
    assert not set(catalogue.select("MSP.*", role=Role.MSP)) & set(catalogue.CLAUSES)


def _quoted(clause: Clause) -> str:
    found = re.search(r'"([^"]+)"', clause.requirement)
    assert found, f"{clause.id}: the requirement quotes nothing"
    return " ".join(found.group(1).split())


def _window(root: Path, clause: Clause, strip: str = "") -> str:
    path, _, line = clause.source.rpartition(":")
    path = path.removeprefix(strip)
    lines = (root / path).read_text(encoding="utf-8").splitlines()
    return " ".join(" ".join(lines[int(line) - 1:int(line) + 2]).split())


@pytest.mark.skipif(not SHARED.is_dir(), reason="../shared (the seed texts) is not beside the project")
@pytest.mark.parametrize("clause", [c for c in MSP_CLAUSES if c.source.startswith("seeds/")], ids=lambda c: c.id)
def test_a_seed_quote_is_at_its_line(clause: Clause) -> None:
    assert _quoted(clause) in _window(SHARED, clause)


@pytest.mark.skipif(INAV_SOURCE is None, reason="set MAVCONFORM_INAV_SOURCE to an INAV 9.1 tree to check its quotes")
@pytest.mark.parametrize("clause", [c for c in MSP_CLAUSES if c.source.startswith(INAV)], ids=lambda c: c.id)
def test_an_inav_quote_is_at_its_line(clause: Clause) -> None:
    """`inav-9.1/src/...` is `src/...` of the tree MAVCONFORM_INAV_SOURCE names."""
    assert _quoted(clause) in _window(Path(INAV_SOURCE), clause, strip=INAV + "/")


def test_every_msp_clause_passes_on_builtin_msp() -> None:
    bad = {k: (r.outcome.value, r.detail) for k, r in _run("builtin:msp").items() if r.outcome is not Outcome.PASS}
    assert not bad


def test_every_msp_clause_has_a_mutant() -> None:
    covered = set().union(*(m.breaks for m in MSP_MUTANTS.values()))
    assert covered == {c.id for c in MSP_CLAUSES}


@pytest.mark.parametrize("name", sorted(MSP_MUTANTS))
def test_msp_mutant_fails_exactly_the_clauses_it_breaks(name: str) -> None:
    results = _run(f"msp-mutant:{name}")
    failed = {k for k, r in results.items() if r.outcome is Outcome.FAIL}
    others = {k: r.outcome.value for k, r in results.items() if r.outcome not in (Outcome.PASS, Outcome.FAIL)}
    assert failed == set(MSP_MUTANTS[name].breaks), {k: results[k].detail for k in failed ^ MSP_MUTANTS[name].breaks}
    assert not others


def test_a_failure_names_the_waypoint_and_field() -> None:
    detail = _run("msp-mutant:jump-read-as-index")["MSP.WP.01"].detail
    assert detail == "read back with MSP_WP: waypoint 3: p1: sent 1, read back 0"


def test_the_run_repeats_in_virtual_time() -> None:
    a, b = _run("msp-mutant:gap-taken"), _run("msp-mutant:gap-taken")
    assert [(k, r.outcome, r.detail) for k, r in a.items()] == [(k, r.outcome, r.detail) for k, r in b.items()]
