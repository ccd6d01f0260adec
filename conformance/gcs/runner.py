"""Run GCS clauses against a GCS and decide each one, as conformance/runner.py does for vehicles.

Each clause gets its own exchange; each operation a fresh scripted vehicle, so a clause can
only fail for what the GCS did in it. A GCS that sends nothing at all for an operation is
`error` (not a verdict on the clause); after three such operations in a row the remaining
clauses are not run: the GCS (or its adapter) is not working, and waiting out every bound
would only cost time. An interrupt stops the run at the current clause, like the vehicle's.
"""

from __future__ import annotations

import time
from typing import Iterable

from ..clause import Clause
from ..harness.exchange import Exchange
from ..outcome import ClauseResult, Outcome
from ..runner import DecidedResult, InterruptGuard, OnResult, RunOutcome, _measured, call_check, skip_undecided
from .checks import GCS_CHECKS
from .harness import GcsHarness

DEAD_AFTER = 3   # operations in a row in which the GCS sent nothing


def run_gcs_clauses(h: GcsHarness, clauses: Iterable[Clause], *, on_result: OnResult | None = None,
                    guard: InterruptGuard | None = None) -> RunOutcome:
    clauses = list(clauses)
    started = time.monotonic()
    results: list[ClauseResult] = []
    silent, dead, interrupted, phase = 0, None, False, "starting"

    def record(clause: Clause, result: ClauseResult) -> None:
        results.append(result)
        if on_result:
            on_result(clause, result)

    try:
        for clause in clauses:
            if dead is not None:
                record(clause, ClauseResult(clause.id, Outcome.ERROR, f"not run: {dead}"))
                continue
            phase = clause.id
            result = run_one(h, clause)
            silent = silent + 1 if result.detail.startswith("target unresponsive") else 0
            if silent >= DEAD_AFTER:
                dead = f"the GCS sent nothing in {DEAD_AFTER} operations in a row"
            record(clause, result)
    except KeyboardInterrupt:
        if guard is not None:
            guard.hold()
        interrupted = True
        skip_undecided(clauses, results, phase, guard.first if guard is not None else None, record)
    first = next((op for op in h.operations if op.gcs is not None), None)
    identity = None if first is None else {"system": first.gcs[0], "component": first.gcs[1],
                                           "gcs": h.adapter.describe()}
    return RunOutcome(results, identity, {"status": "skipped", "detail": "a GCS under test holds no plan of "
                                          "the suite's: each operation had a vehicle of its own"},
                      time.monotonic() - started, 0.0, unresponsive=dead, interrupted=interrupted,
                      interrupted_at=phase if interrupted else None,
                      interrupted_by=guard.first if interrupted and guard is not None else None)


def run_one(h: GcsHarness, clause: Clause) -> ClauseResult:
    fn = GCS_CHECKS.get(clause.id)
    if fn is None:
        return ClauseResult(clause.id, Outcome.ERROR, "no check is registered for this clause")
    begin = h.now()
    exchange = h.exchange = Exchange(begin)
    outcome, detail, caught = call_check(fn, h)
    decided_by = exchange.decided_by if outcome in (Outcome.PASS, Outcome.FAIL) else None
    end = h.now()
    h.exchange = None
    return DecidedResult(clause.id, outcome, detail, round(end - begin, 6), exchange.finish(end),
                         decided_by=decided_by, measured=_measured(*caught))
