"""How every command takes Ctrl-C and SIGTERM: one guard for all of them.

A long command (a conformance run, a fuzz campaign, a served vehicle, proxy or bridge) stops
on SIGINT or SIGTERM (how CI cancels a job and a service manager stops one) as on Ctrl-C: a
KeyboardInterrupt where it is. What it does next (put a target's plans back, save a finding,
write the reports, close a capture) must not be cut short, since every wait in it is bounded
and a half-written file is worse than a second's delay: there a signal is only noted, and
the command honours it when it is done. A signal the process ignores (the SIGINT of a shell's
background job) stays ignored. Signals are handled in the main thread only: elsewhere the
guard changes nothing.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
from typing import Any, Callable

INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class InterruptGuard:
    """While entered, the first signal raises KeyboardInterrupt and later ones are only noted
    (`once`, the default: one interrupt per run); with `once=False` every signal raises until
    `hold()` (a fuzz campaign's saving may itself be interrupted, and says so). `held=True`
    notes from the start (a block that writes files). `atomic(hook)` wraps a writer a signal
    must not split. `check()` raises again a KeyboardInterrupt Python dropped: one raised in
    a gc callback (Hypothesis installs one) or a `__del__` is printed and lost."""

    def __init__(self, signals: tuple[int, ...] = INTERRUPT_SIGNALS, *, once: bool = True,
                 held: bool = False, held_note: str | None = None) -> None:
        self.signals = signals
        self.once = once
        self.holding = held
        self.held_note = held_note   # said on stderr for a signal noted while holding
        self.received: list[str] = []   # the signals' names, in order
        self._atomic = 0
        self._pending = False
        self._previous: dict[int, Any] = {}
        self._unraisable: Callable[[Any], Any] | None = None

    def __enter__(self) -> "InterruptGuard":
        if threading.current_thread() is not threading.main_thread():
            return self
        for signum in self.signals:
            if signal.getsignal(signum) is not signal.SIG_IGN:
                self._previous[signum] = signal.signal(signum, self._handle)
        self._unraisable = sys.unraisablehook
        sys.unraisablehook = self._dropped
        return self

    def __exit__(self, *exc: object) -> None:
        for signum, previous in self._previous.items():
            signal.signal(signum, signal.SIG_DFL if previous is None else previous)
        self._previous.clear()
        if self._unraisable is not None:
            sys.unraisablehook = self._unraisable
            self._unraisable = None

    @property
    def first(self) -> str | None:
        return self.received[0] if self.received else None

    def hold(self) -> None:
        """From now on signals are noted, never raised."""
        self.holding = True

    def check(self) -> None:
        """Raise KeyboardInterrupt if a signal came and the guard does not hold (again, if
        Python dropped the first)."""
        if self.received and not self.holding:
            raise KeyboardInterrupt

    def atomic(self, hook: Callable[..., None]) -> Callable[..., None]:
        def guarded(*args: Any, **kwargs: Any) -> None:
            self._atomic += 1
            try:
                hook(*args, **kwargs)
            finally:
                self._atomic -= 1
            if self._pending and not self._atomic and not self.holding:
                self._pending = False
                self._raise()
        mark = getattr(hook, "mark", None)
        if mark is not None:   # the capture's clause markers are writes too
            guarded.mark = self.atomic(mark)  # type: ignore[attr-defined]
        return guarded

    def _handle(self, signum: int, frame: object) -> None:
        self.received.append(signal.Signals(signum).name)
        if self.holding:
            if self.held_note:
                _say(self.held_note)
        elif self._atomic:
            self._pending = True
        else:
            self._raise()

    def _raise(self) -> None:
        if self.once:
            self.holding = True   # a second signal must not cut the clean-up short
        raise KeyboardInterrupt

    def _dropped(self, info: Any) -> None:
        if not (isinstance(info.exc_value, KeyboardInterrupt) and self.received):
            assert self._unraisable is not None
            self._unraisable(info)


def _say(line: str) -> None:
    """One line on stderr from a signal handler: os.write, since print may be mid-line."""
    try:
        os.write(2, (line + "\n").encode())
    except OSError:
        pass
