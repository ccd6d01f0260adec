"""Making a finding small: Hypothesis's shrinking, bounded in time, then a pass of our own
that drops every step the violation does not need, judged by replaying it."""

from __future__ import annotations

import contextlib
import time
from types import ModuleType
from typing import Iterator

from mavconform.reference_impl.errors import UsageError

from .case import MALFORMED, Case


MINIMISE_REPLAYS = 400       # bound on the replays the step-removal pass may spend per finding


def _shrink_engine() -> ModuleType | None:
    """Hypothesis's engine module, whose MAX_SHRINKING_SECONDS is the only handle it offers
    on shrinking time; None if a later version drops it (shrinking keeps its own cap)."""
    try:
        from hypothesis.internal.conjecture import engine
    except ImportError:      # pragma: no cover - a Hypothesis without that module
        return None
    return engine if hasattr(engine, "MAX_SHRINKING_SECONDS") else None


def set_shrink_time_limit(seconds: float) -> None:
    """Change the bound while a search runs (Hypothesis reads it when shrinking begins)."""
    engine = _shrink_engine()
    if engine is not None:
        engine.MAX_SHRINKING_SECONDS = max(0.5, seconds)


@contextlib.contextmanager
def shrink_time_limit(seconds: float) -> Iterator[None]:
    """Bound the time Hypothesis spends shrinking (its own cap is 300 s per test), restored
    afterwards."""
    engine = _shrink_engine()
    if engine is None:
        yield
        return
    before = engine.MAX_SHRINKING_SECONDS
    engine.MAX_SHRINKING_SECONDS = seconds
    try:
        yield
    finally:
        engine.MAX_SHRINKING_SECONDS = before


def minimise(mode: ModuleType, case: Case, budget: int = MINIMISE_REPLAYS,
             until: float | None = None) -> Case:
    """Drop every step the violation does not need, judged by replaying (in-process targets
    only, where a replay is exact and cheap). Hypothesis shrinks the program it generated;
    this pass also removes steps that stayed only because removing them changed how later
    draws were decoded. One pass from the end, repeated while it removes something."""
    from mavconform.conformance.target_uri import parse_target

    if case.violation is None or not parse_target(case.target).in_process:
        return case
    want = case.violation.invariant
    steps = list(case.steps)
    best = case
    changed = True
    while changed and budget > 0:
        changed = False
        for i in reversed(range(len(steps))):
            if budget <= 0 or (until is not None and time.monotonic() >= until):
                budget = 0
                break
            budget -= 1
            trial = Case(case.mode, case.target, case.seed, tuple(steps[:i] + steps[i + 1:]),
                         case.violation, case.found_by)
            try:
                got = mode.replay(trial)
            except (UsageError, *MALFORMED):
                continue                          # the mode needs that step to read the case
            if got is not None and got.invariant == want:
                steps = list(trial.steps)
                best = Case(case.mode, case.target, case.seed, trial.steps, got, case.found_by)
                changed = True
    return best
