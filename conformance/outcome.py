"""How a clause came out, and the exceptions a check raises to say so.

h11's split carries over: `ClauseFailed` is a finding about the target (RemoteProtocolError
in h11's terms); a bug in a check is an ordinary exception and is reported as our error,
never as the target's failure. A check that returns normally has passed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from contextlib import contextmanager
from typing import Any, Iterator


class Outcome(str, Enum):
    PASS = "pass"
    FAIL = "fail"
    KNOWN_DEVIATION = "known-deviation"   # fails, and an expectations file says it will
    NOT_APPLICABLE = "not-applicable"     # the target lacks the optional feature the clause is about
    SKIPPED = "skipped"                   # not run (e.g. needs flight and flight was not allowed)
    ERROR = "error"                       # undecided: target unresponsive, or a precondition failed


class ClauseFailed(Exception):
    """The target broke the clause. The message says what was expected and what came."""


class NotApplicable(Exception):
    """The clause is about an optional behaviour this target does not have."""


class Skipped(Exception):
    """The check was not run, for a reason the user controls."""


class PreconditionFailed(Exception):
    """The state the check needs could not be set up (e.g. the setup upload failed), so the
    clause is undecided. Another clause is where that failure is judged."""


class TargetUnresponsive(Exception):
    """The target sent nothing at all for longer than any protocol wait."""


@dataclass
class ClauseResult:
    clause_id: str
    outcome: Outcome
    detail: str = ""
    duration_s: float = 0.0
    exchange: list[dict[str, Any]] = field(default_factory=list)
    expectation: str | None = None   # the expectations file's reason, when it lists this clause
    decided_by: int | None = None    # index in `exchange` of the event the verdict is about (Tester)


@contextmanager
def beyond_the_clause(what: str) -> Iterator[None]:
    """Steps a check takes after its clause is decided (finishing an upload, reading the
    plan back) or before (setting up): a failure there leaves the clause undecided instead
    of failing it, so each clause fails only for its own behaviour."""
    try:
        yield
    except ClauseFailed as exc:
        raise PreconditionFailed(f"{what}: {exc}") from None
