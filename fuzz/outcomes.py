"""What a campaign can end with besides "no finding" and a finding about the target.

- `TargetUnresponsive`: the target never said HEARTBEAT, so nothing was fuzzed. Not a
  finding (nothing was sent that could have broken it); the CLI says so and exits 1.
- `ToolFailure`: an exception inside mavconform while it ran an example. A bug of ours,
  never a finding about the target: it is reported apart (exit 3), with the steps that
  led to it saved as a case so it can be replayed and fixed.
- `SearchInterrupted`: Ctrl-C or SIGTERM (reference_impl/interrupts.py) stopped a mode's search; it carries
  the findings seen so far, so an interrupt never loses one. The campaign saves them and
  reports like a finished campaign, marked interrupted (exit 130).
- `DEATH_KINDS`: the findings that mean the target stopped answering altogether.
"""

from __future__ import annotations

import traceback
from dataclasses import dataclass
from typing import Any

DEATH_KINDS = ("target-crash", "target-hang")


class TargetUnresponsive(Exception):
    """No HEARTBEAT from the target when the campaign began; `str()` says where."""


@dataclass(frozen=True)
class ToolFailure:
    error: str                          # "TypeError: ..." (one line)
    trace: str                          # the formatted traceback
    steps: tuple[dict[str, Any], ...]   # what the example had run, the failing step last
    seed: int                           # the example's seed (protocol) or the campaign's

    @classmethod
    def from_exception(cls, exc: BaseException, steps: list[dict[str, Any]], seed: int) -> "ToolFailure":
        first = str(exc).splitlines()[0] if str(exc) else ""
        return cls(f"{type(exc).__name__}: {first}".rstrip(": "),
                   "".join(traceback.format_exception(exc)), tuple(steps), seed)


class ToolError(Exception):
    """Raised out of `search` when an example hit a `ToolFailure`."""

    def __init__(self, failure: ToolFailure) -> None:
        super().__init__(failure.error)
        self.failure = failure


class SearchInterrupted(KeyboardInterrupt):
    """Raised out of a mode's `search` by an interrupt. `cases` are the findings seen by
    then, shrunk only as far as the search got (possibly not at all): a subclass of
    KeyboardInterrupt, so a caller that knows nothing of it still stops."""

    def __init__(self, cases: list[Any] | None = None, *, phase: str = "search") -> None:
        super().__init__()
        self.cases = list(cases or [])
        self.phase = phase               # what the search was doing: "search" or "shrinking"


def raised_while_handling(exc: BaseException | None, kind: type[BaseException]) -> bool:
    """`exc` is a `kind`, or what code handling one raised instead (its `__context__` chain,
    a few links deep): Hypothesis turns an exception it did not expect mid-test into one
    of its own."""
    for _ in range(8):
        if exc is None:
            return False
        if isinstance(exc, kind):
            return True
        exc = exc.__context__
    return False


def caused_by_interrupt(exc: BaseException | None) -> bool:
    """A KeyboardInterrupt, or what Hypothesis made of one: interrupted before its engine
    was set up, it fails an assertion of its own about it."""
    return raised_while_handling(exc, KeyboardInterrupt)
