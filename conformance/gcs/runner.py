"""Run GCS clauses against a GCS and decide each one, as conformance/runner.py does for vehicles.

Each clause gets its own exchange; each operation a fresh scripted vehicle, so a clause can
only fail for what the GCS did in it. A GCS that sends nothing at all for an operation is
`error` (not a verdict on the clause); after three such operations in a row the remaining
clauses are not run: the GCS (or its adapter) is not working, and waiting out every bound
would only cost time. An interrupt stops the run at the current clause, like the vehicle's;
and a clause that did not pass while the host lagged is run again, as there (host_lag.py).
"""

from __future__ import annotations

import time
from typing import Iterable

from ..clause import Clause
from ..harness.exchange import Exchange
from ..outcome import ClauseResult, Outcome
from ..clause_loop import ClauseLoop
from ..host_lag import judged_on_time
from ..runner import DecidedResult, InterruptGuard, OnResult, RunOutcome, _measured, call_check
from .checks import GCS_CHECKS
from .harness import GcsHarness

DEAD_AFTER = 3   # operations in a row in which the GCS sent nothing


def run_gcs_clauses(h: GcsHarness, clauses: Iterable[Clause], *, on_result: OnResult | None = None,
                    guard: InterruptGuard | None = None) -> RunOutcome:
    loop = ClauseLoop(clauses, on_result, guard, phase="starting")
    started = time.monotonic()
    silent = 0

    def dead_after(clause: Clause, result: ClauseResult) -> str | None:
        nonlocal silent
        silent = silent + 1 if result.detail.startswith("target unresponsive") else 0
        return f"the GCS sent nothing in {DEAD_AFTER} operations in a row" if silent >= DEAD_AFTER else None

    with loop.interruptible():
        loop.run(lambda clause: judged_on_time(h, clause, run_one), dead_after)
    dead, interrupted, phase = loop.dead, loop.interrupted, loop.phase
    first = next((op for op in h.operations if op.gcs is not None), None)
    identity = None if first is None else {"system": first.gcs[0], "component": first.gcs[1],
                                           "gcs": h.adapter.describe()}
    return RunOutcome(loop.results, identity, {"status": "skipped", "detail": "a GCS under test holds no plan "
                                               "of the suite's: each operation had a vehicle of its own"},
                      time.monotonic() - started, 0.0, unresponsive=dead, interrupted=interrupted,
                      interrupted_at=phase if interrupted else None,
                      interrupted_by=loop.interrupted_by if interrupted else None, link=h.link())


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
