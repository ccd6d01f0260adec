"""A verdict is the target's only while the tester keeps its own clock.

Over real sockets the driver sleeps to the next deadline. A host too busy to wake it on time
(other jobs on two cores; the builtin vehicle's 4x clock asks four times the punctuality)
serves the in-process vehicle's timers late and reads replies late, and a timing clause can
then fail for the host's sake: a false verdict, the one thing the suite must not give. The
driver measures how far behind its own schedule it ran (`UdpDriver.lag`; the vehicle suite's
Session and the GCS suite's harness pass it on). A clause that did not pass while the driver
ran more than `LAG_TOLERANCE` behind is run once more. The second attempt decides, unless it
too did not pass under lag: then the clause is an error that names the host, not a verdict on
the target. The run document's volatile section keeps the first attempt and the lag. Virtual
time never lags, so nothing changes there.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Callable, Protocol

from .clause import Clause
from .harness.measured import Measured
from .outcome import ClauseResult, Outcome

# clock seconds. On an idle 2-core machine the main job's 4x clock runs at most ~0.013 s
# behind, and ~0.05 s with six CPU hogs beside it; the shortest timer a clause judges is the
# 250 ms item timeout (MIS.UP.07), so 0.1 s behind is where a timing verdict stops being sure
LAG_TOLERANCE = 0.1


class Judging(Protocol):
    """What a clause is run against: the vehicle suite's Session, the GCS suite's harness."""

    clock_speed: float

    def take_lag(self) -> float:
        """The most the driver ran behind its clock since the last call."""

    def forget_lagged(self, tolerance: float) -> None:
        """Drop the shared observations made while it ran more than `tolerance` behind."""


RunOne = Callable[[Any, Clause], ClauseResult]


def judged_on_time(session: Judging, clause: Clause, run_one: RunOne) -> ClauseResult:
    """`run_one(session, clause)`, run again if it did not pass while the host lagged; an
    error if the second attempt did too. A re-run result keeps the first in `first_attempt`;
    a result judged under lag says how much in `host_lag_s`."""
    session.take_lag()
    first = run_one(session, clause)
    lag = session.take_lag()
    if _sure(first, lag):
        return _noted(first, lag)
    session.forget_lagged(LAG_TOLERANCE)   # what it shares with other clauses is observed again
    again = run_one(session, clause)
    lag_again = session.take_lag()
    attempt = {"outcome": first.outcome.value, "host_lag_s": round(lag, 3)}
    if _sure(again, lag_again):
        return _noted(_with(again, first_attempt=attempt), lag_again)
    speed = session.clock_speed
    hint = f"; a {speed:g}x clock asks more of the host than --clock-speed 1" if speed != 1.0 else ""
    detail = Measured(f"not judged: the host was too busy. The tester ran up to <lag> s behind its clock "
                      f"(tolerance {LAG_TOLERANCE:g} s) in both attempts, which ended <first> and "
                      f"<second>; a timing verdict would be the host's, not the target's. Run it on a "
                      f"quieter machine{hint}",
                      lag=f"{max(lag, lag_again):.2f}", first=first.outcome.value, second=again.outcome.value)
    return _noted(_with(again, outcome=Outcome.ERROR, detail=detail, decided_by=None, first_attempt=attempt,
                        measured=[detail]), lag_again)


def _sure(result: ClauseResult, lag: float) -> bool:
    """Whether `result` stands: the host kept up while it was judged, it was not run, or it
    passed. Lag delays what the tester sees: that makes a target look slow (a late timer, a
    reply read late), which is what fails a timing clause falsely. A pass stands, with the
    lag noted: lag could only have hidden a target that is too quick."""
    return lag <= LAG_TOLERANCE or result.outcome in (Outcome.PASS, Outcome.SKIPPED)


def _noted(result: ClauseResult, lag: float) -> ClauseResult:
    return _with(result, host_lag_s=round(lag, 3)) if lag > LAG_TOLERANCE else result


def _with(result: ClauseResult, **changes: object) -> ClauseResult:
    """`result` with `changes`; fields its class lacks (a plain ClauseResult has no
    `measured`, `first_attempt` or `host_lag_s`) are left out."""
    fields = getattr(result, "__dataclass_fields__", {})
    return replace(result, **{k: v for k, v in changes.items() if k in fields})
