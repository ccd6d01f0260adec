"""The clause loop every run shares (conformance/clause_loop.py): results in order, a dead
target's remaining clauses not run, an interrupt that skips what it left undecided and holds
the guard; and each runner (vehicle, MSP, GCS) stopping the same way on an interrupt."""

from __future__ import annotations

import pytest

from mavconform.conformance.catalogue import select
from mavconform.conformance.clause import Role
from mavconform.conformance.clause_loop import ClauseLoop
from mavconform.conformance.gcs.adapters import NodeAdapter
from mavconform.conformance.gcs.harness import GcsHarness
from mavconform.conformance.gcs.runner import run_gcs_clauses
from mavconform.conformance.msp.clauses import MSP_CLAUSES
from mavconform.conformance.msp.runner import run_msp_clauses
from mavconform.conformance.msp.session import MspSession
from mavconform.conformance.msp.target import parse_msp_target
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target

CLAUSES = select("MIS.CLR.*")


class Guard:
    """What the loop uses of an InterruptGuard: `hold()` and the first signal's name."""

    def __init__(self, first: str | None = None) -> None:
        self.first, self.holds = first, 0

    def hold(self) -> None:
        self.holds += 1


def passing(clause) -> ClauseResult:
    return ClauseResult(clause.id, Outcome.PASS, "ok")


def never_dead(clause, result) -> None:
    return None


def test_every_clause_is_decided_in_order_and_told_as_it_comes() -> None:
    told: list[str] = []
    loop = ClauseLoop(CLAUSES, lambda c, r: told.append(c.id), Guard())
    with loop.interruptible():
        loop.run(passing, never_dead)
    assert [r.clause_id for r in loop.results] == told == [c.id for c in CLAUSES]
    assert not loop.interrupted and loop.dead is None and loop.guard.holds == 1


def test_after_the_target_dies_the_rest_are_errors_not_run() -> None:
    def dead_after(clause, result):
        return f"it died during {clause.id}" if clause is CLAUSES[1] else None

    loop = ClauseLoop(CLAUSES, None, None)
    loop.run(passing, dead_after)
    assert [r.outcome for r in loop.results[:2]] == [Outcome.PASS, Outcome.PASS]
    assert {(r.outcome, r.detail) for r in loop.results[2:]} == {
        (Outcome.ERROR, f"not run: it died during {CLAUSES[1].id}")}
    loop = ClauseLoop(CLAUSES, None, None)
    loop.give_up("gone")
    assert [r.detail for r in loop.results] == ["not run: gone"] * len(CLAUSES)


def test_an_interrupt_skips_the_clause_it_cut_short_and_every_later_one() -> None:
    def decide(clause):
        if clause is CLAUSES[1]:
            raise KeyboardInterrupt
        return passing(clause)

    loop = ClauseLoop(CLAUSES, None, Guard("SIGTERM"))
    with loop.interruptible():
        loop.run(decide, never_dead)
    assert loop.interrupted and loop.interrupted_by == "SIGTERM" and loop.guard.holds == 1
    assert loop.results[0].outcome is Outcome.PASS
    assert (loop.results[1].outcome, loop.results[1].detail) == (
        Outcome.SKIPPED, "interrupted (SIGTERM) while it ran: not decided")
    assert {r.detail for r in loop.results[2:]} == {
        f"not run: the run was interrupted (SIGTERM) during {CLAUSES[1].id}"}
    assert len(loop.results) == len(CLAUSES)


def test_another_exception_is_not_an_interrupt_but_the_guard_still_holds() -> None:
    loop = ClauseLoop(CLAUSES, None, Guard())
    with pytest.raises(ValueError):
        with loop.interruptible():
            raise ValueError("ours")
    assert not loop.interrupted and loop.guard.holds == 1 and loop.results == []


class _InterruptAfterFirst:
    """An `on_result` that raises KeyboardInterrupt once, after the first result: as the
    guard's first signal would (later ones it only notes)."""

    def __init__(self) -> None:
        self.raised = False

    def __call__(self, clause, result) -> None:
        if not self.raised:
            self.raised = True
            raise KeyboardInterrupt


def _stopped_after_one(run) -> None:
    assert run.interrupted and run.interrupted_at is not None
    first, *rest = run.results
    assert first.outcome is not Outcome.SKIPPED and rest
    assert all(r.outcome is Outcome.SKIPPED and "interrupted" in r.detail for r in rest)


def test_the_vehicle_run_stops_there() -> None:
    with Session(parse_target("builtin:spec"), virtual=True) as session:
        _stopped_after_one(run_clauses(session, CLAUSES, on_result=_InterruptAfterFirst()))


def test_the_msp_run_stops_there() -> None:
    with MspSession(parse_msp_target("builtin:msp"), virtual=True) as session:
        _stopped_after_one(run_msp_clauses(session, MSP_CLAUSES, on_result=_InterruptAfterFirst()))


def test_the_gcs_run_stops_there() -> None:
    h = GcsHarness(NodeAdapter(), real_time=False, timeout_s=30)
    _stopped_after_one(run_gcs_clauses(h, select("MIS.G.UP.0[1-4]", role=Role.GCS), on_result=_InterruptAfterFirst()))
