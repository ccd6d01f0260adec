"""Which outcomes fail a run: expectations applied, strictness, and baseline regressions.

Default: a run fails on any unexpected `fail` of a MUST clause, or on `error` (undecided
because the target went silent or a precondition broke). SHOULD failures fail the run only
with `--strict`; MAY clauses never do (the behaviour is optional: a failure is reported,
never gated on). A listed clause that fails in a way its expectation does not name stays a
`fail`, with the expected failure beside it. With a baseline,
only regressions fail it: a clause that passed in the baseline and now fails or errs; a
clause is "fixed" only if the baseline saw it fail (a skipped, not-applicable or undecided
clause was never seen failing). An interrupted run is no baseline: the clauses it did not
reach would look as if they had never passed, and hide their regressions.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.errors import UsageError

from .catalogue import BY_ID
from .clause import Level
from .expectations import OTHER_FAILURE_PREFIX, Deviation
from .outcome import ClauseResult, Outcome

NO_LONGER = "deviation no longer observed"
PASS, FAIL, INTERRUPTED = "pass", "fail", "interrupted"   # the run's verdicts
OTHER_FAILURE = OTHER_FAILURE_PREFIX


def apply_expectations(results: list[ClauseResult], expected: dict[str, Deviation]) -> None:
    for r in results:
        dev = expected.get(r.clause_id)
        if dev is None:
            continue
        r.expectation = dev.describe()
        if r.outcome is Outcome.FAIL and dev.excuses(r.detail):
            r.outcome = Outcome.KNOWN_DEVIATION
        elif r.outcome is Outcome.FAIL and not r.detail.startswith(OTHER_FAILURE):
            r.detail = f"{OTHER_FAILURE} (it excuses: {dev.observed}): {r.detail}"
        elif r.outcome is Outcome.PASS:
            r.detail = f"{NO_LONGER} (expected to fail: {dev.describe()})"


def gates(result: ClauseResult, *, strict: bool) -> bool:
    if result.outcome is Outcome.ERROR:
        return True
    if result.outcome is not Outcome.FAIL:
        return False
    level = BY_ID[result.clause_id].level
    return level is Level.MUST or (strict and level is Level.SHOULD)


FIXED_FROM = (Outcome.FAIL.value, Outcome.KNOWN_DEVIATION.value)   # seen failing before


def baseline_outcomes(doc: dict[str, Any], source: str = "the baseline") -> dict[str, str]:
    """Outcome by clause id of a checked run document; an interrupted run is refused."""
    run = doc["run"]
    if run.get("interrupted") or doc["summary"]["verdict"] == INTERRUPTED:
        where = f" during {run['interrupted_at']}" if run.get("interrupted_at") else ""
        raise UsageError(f"--baseline {source}: that run was interrupted{where}, so the clauses "
                         "it did not decide would hide regressions; use a complete run")
    return {c["id"]: c["outcome"] for c in doc["clauses"]}


def gate(results: list[ClauseResult], *, strict: bool,
         baseline: dict[str, str] | None) -> tuple[dict[str, bool], dict[str, Any]]:
    """Per clause: does it fail the run; and the gating summary for the report."""
    if baseline is None:
        flags = {r.clause_id: gates(r, strict=strict) for r in results}
        return flags, {"mode": "strict" if strict else "default", "regressions": [], "fixed": []}
    regressions, fixed, flags = [], [], {}
    for r in results:
        before = baseline.get(r.clause_id)
        regressed = before == "pass" and r.outcome in (Outcome.FAIL, Outcome.ERROR)
        flags[r.clause_id] = regressed
        if regressed:
            regressions.append(r.clause_id)
        elif before in FIXED_FROM and r.outcome is Outcome.PASS:
            fixed.append(r.clause_id)
    return flags, {"mode": "baseline", "regressions": regressions, "fixed": fixed}


def verdict(gating_failures: int, *, interrupted: bool, left_armed: int = 0) -> str:
    """The run's verdict: an interrupted run neither passes nor fails, whatever it decided
    before it stopped (it is not evidence that the rest would pass), unless it left the
    vehicle armed: that fails any run (harness/landing.py)."""
    if left_armed:
        return FAIL
    if interrupted:
        return INTERRUPTED
    return FAIL if gating_failures else PASS
