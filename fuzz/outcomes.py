"""What a campaign can end with besides "no finding" and a finding about the target.

- `TargetUnresponsive`: the target never said HEARTBEAT, so nothing was fuzzed. Not a
  finding (nothing was sent that could have broken it); the CLI says so and exits 1.
- `ToolFailure`: an exception inside mavconform while it ran an example. A bug of ours,
  never a finding about the target: it is reported apart (exit 3), with the steps that
  led to it saved as a case so it can be replayed and fixed.
- `SearchInterrupted`: Ctrl-C (or SIGTERM, made one) stopped a mode's search; it carries
  the findings seen so far, so an interrupt never loses one. The campaign saves them and
  reports like a finished campaign, marked interrupted (exit 130).
- `DEATH_KINDS`: the findings that mean the target stopped answering altogether.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import traceback
from dataclasses import dataclass
from typing import Any, Callable, Iterator

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


INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM)


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


class InterruptWatch:
    """The signals that came while `interrupts_watched` ran (their names, in order)."""

    def __init__(self) -> None:
        self.noted: list[str] = []

    def check(self) -> None:
        """Raise KeyboardInterrupt if a signal came (again, if Python dropped the first)."""
        if self.noted:
            raise KeyboardInterrupt


@contextlib.contextmanager
def interrupts_watched() -> Iterator[InterruptWatch]:
    """Note every Ctrl-C and SIGTERM; the handlers in place still raise KeyboardInterrupt at
    once. But one raised inside a gc callback (Hypothesis installs one) or a `__del__` is
    dropped by Python (which prints its traceback: not here), and a campaign would run on
    to its budget: calling `check()` after every example raises it again. Signals left to
    their default action (or ignored), and threads other than the main one, are left alone."""
    watch = InterruptWatch()
    unraisable = sys.unraisablehook

    def dropped(info: Any) -> None:
        if not (isinstance(info.exc_value, KeyboardInterrupt) and watch.noted):
            unraisable(info)

    def watched(handler: Callable[[int, Any], Any]) -> Callable[[int, Any], Any]:
        def handle(signum: int, frame: Any) -> Any:
            watch.noted.append(signal.Signals(signum).name)
            return handler(signum, frame)
        return handle

    wrapped = {signum: handler for signum in INTERRUPT_SIGNALS
               if callable(handler := signal.getsignal(signum))}
    try:
        for signum, handler in wrapped.items():
            signal.signal(signum, watched(handler))
    except ValueError:   # not the main thread (the first call fails: nothing was changed)
        yield watch
        return
    sys.unraisablehook = dropped
    try:
        yield watch
    finally:
        sys.unraisablehook = unraisable
        for signum, handler in wrapped.items():
            signal.signal(signum, handler)


@contextlib.contextmanager
def interrupts_noted() -> Iterator[list[str]]:
    """While the block runs, Ctrl-C and SIGTERM are only noted (their names appended to the
    list yielded), so the files it writes are never left half-written; the caller decides
    what a noted signal means. Outside the main thread signals cannot be handled: no-op."""
    noted: list[str] = []

    def note(signum: int, frame: object) -> None:
        noted.append(signal.Signals(signum).name)

    try:   # a signal the process ignores (a background job's SIGINT) stays ignored
        previous = {signum: signal.signal(signum, note) for signum in INTERRUPT_SIGNALS
                    if signal.getsignal(signum) is not signal.SIG_IGN}
    except ValueError:   # not the main thread: leave signals alone
        yield noted
        return
    try:
        yield noted
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
