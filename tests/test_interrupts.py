"""Issue 29: one interrupt mechanism for every command (reference_impl/interrupts.py).

Each behaviour a command relies on, with real signals sent to this process."""

from __future__ import annotations

import os
import signal
import threading

import pytest

from mavconform.reference_impl.interrupts import InterruptGuard

pytestmark = pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                                reason="signals are handled in the main thread only")


@pytest.fixture(autouse=True)
def interactive_signals():
    """SIGINT and SIGTERM as an interactive shell leaves them: a job started in the background
    (CI's, nohup's) inherits SIGINT ignored, which the guard rightly leaves alone."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler), signal.signal(signal.SIGTERM, signal.SIG_DFL)
    yield
    signal.signal(signal.SIGINT, previous[0])
    signal.signal(signal.SIGTERM, previous[1])


def _send(signum: int = signal.SIGTERM) -> None:
    os.kill(os.getpid(), signum)   # the handler runs before kill returns to Python code


def test_the_first_signal_raises_and_a_later_one_is_only_noted() -> None:
    with InterruptGuard() as guard:
        with pytest.raises(KeyboardInterrupt):
            _send()
        _send(signal.SIGINT)   # the clean-up a run does now must not be cut short
    assert guard.received == ["SIGTERM", "SIGINT"] and guard.first == "SIGTERM"


def test_without_once_every_signal_raises_until_held() -> None:
    with InterruptGuard(once=False) as guard:
        for _ in range(2):
            with pytest.raises(KeyboardInterrupt):
                _send()
        guard.hold()
        _send()
    assert guard.received == ["SIGTERM"] * 3


def test_a_held_guard_says_its_note(capfd) -> None:
    with InterruptGuard(held=True, held_note="stopping after the reports"):
        _send()
    assert "stopping after the reports" in capfd.readouterr().err


def test_an_atomic_writer_finishes_before_the_interrupt() -> None:
    written = []

    def writer(value: int) -> None:
        _send()
        written.append(value)   # the signal came mid-write: the write still ends

    with InterruptGuard() as guard:
        with pytest.raises(KeyboardInterrupt):
            guard.atomic(writer)(7)
    assert written == [7] and guard.holding


def test_check_raises_again_an_interrupt_python_dropped() -> None:
    with InterruptGuard(once=False) as guard:
        guard.check()   # nothing came: nothing raised
        guard.received.append("SIGINT")   # as a handler does before its raise is lost in a gc callback
        with pytest.raises(KeyboardInterrupt):
            guard.check()


def test_handlers_are_put_back_and_an_ignored_signal_stays_ignored() -> None:
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)   # a shell's background job
    try:
        before = signal.getsignal(signal.SIGTERM)
        with InterruptGuard():
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            _send(signal.SIGINT)   # ignored: nothing raised
        assert signal.getsignal(signal.SIGTERM) == before and signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)
