"""When a live target dies (`target-crash`, `target-hang`): it cannot be replayed as it is,
so the case is saved at once with the capture of the live traffic that led to it (the last
RING_SECONDS, kept while the campaign ran). With a restart hook (`Restarter`,
`--restart-cmd`) the target is restarted, the case replayed to confirm it, and minimised with
a restart before every attempt; without one the case says it was neither."""

from __future__ import annotations

import collections
import contextlib
import subprocess
import time
from dataclasses import replace
from pathlib import Path
from types import ModuleType
from typing import Any

from mavconform.reference_impl.net.capture import McapCapture
from mavconform.reference_impl.net.sim import CaptureRecord

from .case import Case, Violation, save_case
from .finding import INTERRUPTED_NOTE, Finding, SaveInterrupted, save_unreplayed
from .outcomes import TargetUnresponsive
from .replay_capture import ExchangeRecorder

RING_SECONDS = 120.0         # s of live traffic a UDP campaign keeps for a dying target's capture
RING_RECORDS = 100_000       # ... and at most this many datagram events
RESTART_TIMEOUT = 120.0      # s a --restart-cmd may run
RESTART_ATTEMPTS = 12        # restarts minimising one crash case may spend
RESTART_SETTLE = 8.0         # s after a restarted target's first HEARTBEAT before a replay: a
                             # SITL just booted refuses uploads for a few seconds (ArduCopter did)


class RingCapture:
    """The last RING_SECONDS (at most RING_RECORDS events) of a live campaign's traffic:
    what a dying target was sent and said before it fell silent."""

    def __init__(self, seconds: float = RING_SECONDS, records: int = RING_RECORDS) -> None:
        self.seconds = seconds
        self.records: collections.deque[CaptureRecord] = collections.deque(maxlen=records)

    def __call__(self, record: CaptureRecord) -> None:
        self.records.append(record)
        while self.records and self.records[0].time < record.time - self.seconds:
            self.records.popleft()

    def write(self, path: Path) -> list[dict[str, Any]]:
        """Write the kept records as an MCAP file; return them as report events."""
        recorder = ExchangeRecorder()
        with contextlib.closing(McapCapture(path)) as capture:
            for record in self.records:
                capture(record)
                recorder(record)
        return recorder.events


class Restarter:
    """Runs the user's restart command (a shell command line, bounded) and waits for the
    target's HEARTBEAT, so a crash case can be replayed and minimised."""

    def __init__(self, command: str, timeout: float = RESTART_TIMEOUT, settle: float = RESTART_SETTLE) -> None:
        self.command = command
        self.timeout = timeout
        self.settle = settle
        self.runs = 0

    def restart(self, target: str) -> str | None:
        """None when the target is back; else why not (one line)."""
        from mavconform.conformance.target_uri import parse_target
        from .protocol.connection import TargetConnection

        self.runs += 1
        try:
            done = subprocess.run(self.command, shell=True, timeout=self.timeout, check=False,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        except subprocess.TimeoutExpired:
            return f"--restart-cmd did not finish within {self.timeout:g} s"
        except OSError as exc:
            return f"--restart-cmd could not run: {exc.strerror or exc}"
        if done.returncode != 0:
            last = (done.stderr or "").strip().splitlines()[-1:] or [""]
            return f"--restart-cmd exited {done.returncode}" + (f": {last[0][:160]}" if last[0] else "")
        try:
            connection = TargetConnection(parse_target(target), discovery_timeout=self.timeout)
        except TargetUnresponsive as exc:
            return f"after --restart-cmd: {exc}"
        try:
            connection.driver.run_for(self.settle)
        finally:
            connection.close()
        return None


def save_death(mode: ModuleType, case: Case, directory: str | Path, ring: RingCapture,
               restarter: Restarter | None, *, until: float) -> Finding:
    """A UDP target that stopped answering: save the case and the live capture first (the
    finding must never be lost), then, given a restart hook and time, confirm it by replay
    and minimise it with a restart before every attempt. An interrupt raises
    `SaveInterrupted` with the case as first saved."""
    try:
        return _save_death(mode, case, directory, ring, restarter, until=until)
    except KeyboardInterrupt:
        raise SaveInterrupted(save_unreplayed(case, directory, ring, note=INTERRUPTED_NOTE)) from None


def _save_death(mode: ModuleType, case: Case, directory: str | Path, ring: RingCapture,
                restarter: Restarter | None, *, until: float) -> Finding:
    path = save_case(case, directory)
    exchange = ring.write(path.with_suffix(".mcap"))
    if restarter is None:
        return Finding(case, path, path.with_suffix(".mcap"), None, exchange,
                       note="saved unminimised and not replayed: a replay needs a restarted target "
                            "(give --restart-cmd)")
    if time.monotonic() >= until:
        return Finding(case, path, path.with_suffix(".mcap"), None, exchange,
                       note="saved unminimised and not replayed: the --time budget was spent")
    want = case.violation.invariant if case.violation else None

    def attempt(trial: Case) -> Violation | None:
        why = restarter.restart(trial.target)
        if why is not None:
            raise _RestartFailed(why)
        try:
            return mode.replay(trial)
        except TargetUnresponsive as exc:
            raise _RestartFailed(f"the restarted target stopped answering before the replay: {exc}") from None

    try:
        again = attempt(case)
        if again is None or again.invariant != want:
            return Finding(case, path, path.with_suffix(".mcap"), again, exchange,
                           note="saved unminimised: replayed after a restart, it did not die the same way")
        steps = list(case.steps)
        best = replace(case, violation=again)
        for i in reversed(range(len(steps))):
            if restarter.runs > RESTART_ATTEMPTS or time.monotonic() >= until:
                break
            trial = replace(case, steps=tuple(steps[:i] + steps[i + 1:]))
            got = attempt(trial)
            if got is not None and got.invariant == want:
                steps = list(trial.steps)
                best = replace(trial, violation=got)
        why = restarter.restart(case.target)   # leave it running for the next user
    except _RestartFailed as exc:
        return Finding(case, path, path.with_suffix(".mcap"), None, exchange,
                       note=f"saved unminimised and not replayed: {exc}")
    note = (f"replayed after a restart: it died again; minimised from {len(case.steps)} to "
            f"{len(best.steps)} step(s) ({restarter.runs} restarts)")
    if why is not None:
        note += f"; the last restart failed: {why}"
    if best.steps != case.steps:
        small = save_case(best, directory)
        return Finding(best, small, path.with_suffix(".mcap"), best.violation, exchange,
                       note=note + f"; the unminimised case is {path.name}")
    return Finding(case, path, path.with_suffix(".mcap"), again, exchange, note=note)


class _RestartFailed(Exception):
    pass
