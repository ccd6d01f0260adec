"""The loop every run shares, whichever side it tests (a vehicle, an MSP flight controller, a GCS).

Clauses run in order, each result recorded and told to `on_result` as it comes. Once the target
is found dead the rest are `error`, not run: waiting out every bound would only cost time. An
interrupt (under the run's `InterruptGuard`) ends the loop in the clause it came in: that clause
and every later one are `skipped`, saying where the run stopped, and the guard holds from then
on, so a second signal cannot cut short what the runner does next (restore, reports).
"""

from __future__ import annotations

from contextlib import contextmanager
from typing import Callable, Iterable, Iterator

from mavconform.reference_impl.interrupts import InterruptGuard

from .clause import Clause
from .outcome import ClauseResult, Outcome

OnResult = Callable[[Clause, ClauseResult], None]
# after a clause: why the target is now given up on, or None while it still answers
DeadAfter = Callable[[Clause, ClauseResult], "str | None"]


class ClauseLoop:
    def __init__(self, clauses: Iterable[Clause], on_result: OnResult | None,
                 guard: InterruptGuard | None, phase: str = "discovery") -> None:
        self.clauses = list(clauses)
        self.results: list[ClauseResult] = []
        self.on_result = on_result
        self.guard = guard
        self.phase = phase             # where an interrupt would land: a clause id, or a phase
        self.dead: str | None = None   # why the target was given up on
        self.interrupted = False

    @property
    def interrupted_by(self) -> str | None:
        """The first signal ("SIGINT", "SIGTERM"), if the guard saw one."""
        return self.guard.first if self.guard is not None else None

    def record(self, clause: Clause, result: ClauseResult) -> None:
        self.results.append(result)
        if self.on_result:
            self.on_result(clause, result)

    def run(self, decide: Callable[[Clause], ClauseResult], dead_after: DeadAfter) -> None:
        """Decide each clause in turn; after each, `dead_after` says whether the target died."""
        for clause in self.clauses:
            if self.dead is not None:
                self.record(clause, ClauseResult(clause.id, Outcome.ERROR, f"not run: {self.dead}"))
                continue
            self.phase = clause.id
            result = decide(clause)
            self.dead = dead_after(clause, result)
            self.record(clause, result)

    def never_answered(self, why: str) -> None:
        """Discovery failed: every clause is `error`, the target unresponsive."""
        for clause in self.clauses:
            self.record(clause, ClauseResult(clause.id, Outcome.ERROR, f"target unresponsive: {why}"))

    def give_up(self, why: str) -> None:
        """The target died outside any clause: every clause not decided is `error`, not run."""
        self.dead = why
        for clause in self.clauses[len(self.results):]:
            self.record(clause, ClauseResult(clause.id, Outcome.ERROR, f"not run: {why}"))

    @contextmanager
    def interruptible(self) -> Iterator[None]:
        """The block an interrupt may end: the guard holds after it, and an interrupt inside
        leaves the clauses not yet decided `skipped`."""
        try:
            yield
        except KeyboardInterrupt:
            self.interrupted = True
        finally:
            if self.guard is not None:
                self.guard.hold()
        if self.interrupted:
            skip_undecided(self.clauses, self.results, self.phase, self.interrupted_by, self.record)


def skip_undecided(clauses: list[Clause], results: list[ClauseResult], phase: str, how: str | None,
                   record: Callable[[Clause, ClauseResult], None]) -> None:
    """After an interrupt: every clause not decided is `skipped`, saying where the run stopped."""
    by = f" ({how})" if how else ""
    done = {r.clause_id for r in results}
    for clause in clauses:
        if clause.id not in done:
            record(clause, ClauseResult(clause.id, Outcome.SKIPPED,
                                        f"interrupted{by} while it ran: not decided" if clause.id == phase
                                        else f"not run: the run was interrupted{by} during {phase}"))
