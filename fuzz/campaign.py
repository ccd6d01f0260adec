"""A fuzz campaign: search with one mode, save each finding as a replayable case, report.

The modes (`fuzz.protocol`, `fuzz.frames`) search and shrink; this module is what they
have in common around that: the budget (examples or wall time, shrinking and saving
included), the progress counters, the findings directory (`NAME.json` + `NAME.mcap` per
finding, the capture taken by replaying the case, which also proves the case reproduces),
and the run document that the reports package renders, so CI shows fuzz findings the way
it shows conformance failures.

A UDP target that dies (`target-crash`, `target-hang`) cannot be replayed as it is: the
case is saved at once, unminimised, with the capture of the live traffic that led to it
(the last RING_SECONDS, kept while the campaign ran). With a restart hook (`Restarter`,
`--restart-cmd`) the target is restarted, the case replayed to confirm it, and minimised
with a restart before every attempt; without one the case says it was neither.

An interrupt (Ctrl-C, or SIGTERM made one) ends a campaign as the budget does, at once:
the search hands over the findings it had seen (`SearchInterrupted`), shrunk as far as it
got; they are saved without minimising (in-process: replayed once, in virtual time, for the
capture; over UDP: with the live capture, not replayed), and `run_campaign` raises
`CampaignInterrupted` with the result, so its caller can still report. An interrupt while a
finding is minimised or replayed saves it as it was (`save_unreplayed`), never loses it.
"""

from __future__ import annotations

import collections
import contextlib
import datetime as dt
import importlib
import struct
import subprocess
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterator

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.messages import is_vehicle_heartbeat
from mavconform.conformance.harness.exchange import MAX_EVENTS, message_fields
from mavconform.reference_impl.interrupts import InterruptGuard
from mavconform.reference_impl.net.capture import McapCapture
from mavconform.reference_impl.net.sim import CaptureRecord
from mavconform.reference_impl.wire.codec import FrameDecoder

from .case import Case, Violation, save_case
from .outcomes import (DEATH_KINDS, SearchInterrupted, TargetUnresponsive, ToolError, ToolFailure,
                       caused_by_interrupt)

MODES = ("protocol", "frames")
SHRINK_LIMIT = 60.0          # s Hypothesis may spend shrinking one campaign's findings, at most
SAVE_GRACE = 2.0             # s left for saving a finding when the budget is spent (one replay)
RING_SECONDS = 120.0         # s of live traffic a UDP campaign keeps for a dying target's capture
RING_RECORDS = 100_000       # ... and at most this many datagram events
RESTART_TIMEOUT = 120.0      # s a --restart-cmd may run
RESTART_ATTEMPTS = 12        # restarts minimising one crash case may spend
RESTART_SETTLE = 8.0         # s after a restarted target's first HEARTBEAT before a replay: a
                             # SITL just booted refuses uploads for a few seconds (ArduCopter did)
# What a hand-edited case can make a mode's replay raise (bad types or values in its steps).
MALFORMED = (ValueError, TypeError, KeyError, AttributeError, IndexError, OverflowError, struct.error)


def load_mode(name: str) -> ModuleType:
    """The module of a fuzz mode; it offers `search`, `replay` and `INVARIANTS`."""
    if name not in MODES:
        raise UsageError(f"unknown fuzz mode {name!r} (expected {' or '.join(MODES)})")
    return importlib.import_module(f"{__package__}.{name}")


@dataclass(frozen=True)
class CampaignOptions:
    target: str
    mode: str
    seed: int = 0
    examples: int | None = None     # stop after this many examples ...
    time_s: float | None = None     # ... or after this much wall time (whichever comes first)
    findings_dir: str = "fuzz-findings"
    database: Any = None            # a Hypothesis ExampleDatabase, or None for none
    profile: str | None = None      # UDP targets: the vehicle profile the oracles apply
    restart_cmd: str | None = None  # a shell command that restarts a crashed target
    restart_timeout: float = RESTART_TIMEOUT
    handover: bool = False          # protocol mode: operator control on (control steps and invariants)


@dataclass
class Progress:
    """Counters the progress bar shows; `units` are steps (protocol) or frames (frames)."""

    examples: int = 0
    units: int = 0
    findings: int = 0
    started: float = field(default_factory=time.monotonic)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started


@dataclass(frozen=True)
class Finding:
    case: Case
    path: Path                       # the saved case (JSON)
    capture: Path | None             # the MCAP of its replay
    replayed: Violation | None       # what replaying it showed (None: it did not reproduce)
    exchange: list[dict[str, Any]]   # the replay's frames, as report events
    note: str = ""                   # how it was saved when that is not the usual way

    @property
    def reproduced(self) -> bool:
        return (self.replayed is not None and self.case.violation is not None
                and self.replayed.invariant == self.case.violation.invariant)


@dataclass(frozen=True)
class CampaignResult:
    options: CampaignOptions
    started: dt.datetime
    examples: int
    units: int
    duration_s: float
    findings: list[Finding]
    invariants: dict[str, str]       # name -> what it asserts, for the report's rows
    interrupted_at: str | None = None   # an interrupt ended it: "search", "shrinking", "saving findings"
    interrupted_by: str | None = None   # "SIGINT" (Ctrl-C), "SIGTERM"; None if not known

    @property
    def interrupted(self) -> bool:
        return self.interrupted_at is not None


class CampaignInterrupted(KeyboardInterrupt):
    """Raised by `run_campaign` after an interrupt, once what was found is saved: `result`
    is the campaign so far. A KeyboardInterrupt, so a caller that cannot report still stops."""

    def __init__(self, result: CampaignResult) -> None:
        super().__init__()
        self.result = result


class SaveInterrupted(KeyboardInterrupt):
    """An interrupt while a finding was minimised or replayed: `finding` is it, saved as it
    was then (not replayed)."""

    def __init__(self, finding: Finding) -> None:
        super().__init__()
        self.finding = finding


INTERRUPTED_NOTE = "saved unminimised and not replayed: the campaign was interrupted"


def run_campaign(options: CampaignOptions,
                 on_progress: Callable[[Progress], None] | None = None) -> CampaignResult:
    """Search, then save what was found. Raises `TargetUnresponsive` (no HEARTBEAT at the
    start), `ToolError` (an exception of ours, with the case that caused it) and, after an
    interrupt, `CampaignInterrupted` (what was found is saved; the result says so)."""
    with InterruptGuard(once=False) as guard:   # saving may be interrupted too, and says so
        return _run_campaign(options, on_progress, guard)


def _run_campaign(options: CampaignOptions, on_progress: Callable[[Progress], None] | None,
                  guard: InterruptGuard) -> CampaignResult:
    from mavconform.conformance.target_uri import parse_target

    uri = parse_target(options.target)   # a bad URI is the user's mistake: say so before searching
    if options.profile is not None:
        if uri.in_process:
            raise UsageError(f"--profile applies to external (udp:, tcp:, serial: ...) targets; {options.target} is held to "
                             "its own profile")
        from mavconform.reference_impl.profiles import load_profile
        load_profile(options.profile)    # a bad name or file: say so before searching
    if options.handover and options.mode != "protocol":
        raise UsageError(f"--operator-control applies to --mode protocol (operator control is fuzzed as GCS "
                         f"operations, not as {options.mode})")
    mode = load_mode(options.mode)
    started = dt.datetime.now(dt.timezone.utc)
    progress = Progress()
    deadline = None if options.time_s is None else progress.started + options.time_s
    ring = None if uri.in_process else RingCapture()

    def example_done(units: int) -> None:
        guard.check()                # an interrupt Python dropped (see InterruptGuard.check)
        progress.examples += 1
        progress.units += units
        if deadline is not None:     # shrinking what an example found gets what is left
            set_shrink_time_limit(min(SHRINK_LIMIT, deadline - time.monotonic()))
        if on_progress is not None:
            on_progress(progress)

    shrink = SHRINK_LIMIT if options.time_s is None else min(SHRINK_LIMIT, options.time_s)
    extra: dict[str, Any] = {"capture": ring}
    if options.profile is not None:
        extra["profile"] = options.profile
    if options.handover:
        extra["handover"] = True
    interrupted_at: str | None = None
    try:
        with shrink_time_limit(shrink):
            cases = mode.search(options.target, seed=options.seed, max_examples=options.examples,
                                stop_after=options.time_s, database=options.database,
                                on_example=example_done, **extra)
        if guard.received:               # dropped after the last example: still an interrupt
            interrupted_at = "search"
    except SearchInterrupted as exc:
        cases, interrupted_at = exc.cases, exc.phase
    except KeyboardInterrupt:            # e.g. while a UDP target was being discovered
        cases, interrupted_at = [], "search"
    except ToolError as exc:
        exc.saved = save_tool_failure(exc.failure, options, options.findings_dir)
        raise
    except (UsageError, TargetUnresponsive):
        raise
    except Exception as exc:   # noqa: BLE001 - outside an example (Hypothesis, the search loop): ours too
        if not caused_by_interrupt(exc):  # else what a mode let through as an interrupt unwound it
            failure = ToolFailure.from_exception(exc, [], options.seed)
            error = ToolError(failure)
            error.saved = save_tool_failure(failure, options, options.findings_dir)
            raise error from exc
        cases, interrupted_at = [], "search"
    duration = progress.elapsed
    until = time.monotonic() + SHRINK_LIMIT if deadline is None else max(deadline, time.monotonic() + SAVE_GRACE)
    restarter = Restarter(options.restart_cmd, options.restart_timeout) if options.restart_cmd else None
    findings = []
    for case in cases:
        case = Case(case.mode, case.target, case.seed, case.steps, case.violation,
                    {**case.found_by, "campaign_seed": options.seed,
                     **({"profile": options.profile} if options.profile else {}),
                     **({"interrupted": interrupted_at} if interrupted_at else {})})
        try:
            if interrupted_at is not None and ring is not None:   # no replays over UDP: stop now
                finding = save_unreplayed(case, options.findings_dir, ring, note=INTERRUPTED_NOTE)
            elif ring is not None and case.violation is not None and case.violation.invariant in DEATH_KINDS:
                finding = save_death(mode, case, options.findings_dir, ring, restarter, until=until)
            else:                        # interrupted: no minimising, one replay in virtual time
                finding = save_finding(mode, case, options.findings_dir,
                                       minimise_until=until if interrupted_at is None else time.monotonic())
        except SaveInterrupted as exc:
            finding, interrupted_at = exc.finding, interrupted_at or "saving findings"
        findings.append(finding)
        progress.findings += 1
        try:
            if on_progress is not None:
                on_progress(progress)
        except KeyboardInterrupt:
            interrupted_at = interrupted_at or "saving findings"
    result = CampaignResult(options, started, progress.examples, progress.units, duration,
                            findings, mode_invariants(mode, options), interrupted_at,
                            guard.first if interrupted_at else None)
    if interrupted_at is not None:
        raise CampaignInterrupted(result)
    return result


def mode_invariants(mode: ModuleType, options: CampaignOptions) -> dict[str, str]:
    """The invariants a campaign checks (its report's rows): the mode's, and the operator-control
    ones with --operator-control."""
    pick = getattr(mode, "invariants", None)
    if pick is not None:
        return dict(pick(options.handover))
    return dict(getattr(mode, "INVARIANTS", {}))


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


def save_finding(mode: ModuleType, case: Case, directory: str | Path, *,
                 minimise_until: float | None = None) -> Finding:
    """Save the case, then replay it once with a capture: the MCAP beside the JSON, and the
    exchange for the report. A case that does not replay to the same invariant is kept and
    flagged, since a finding that cannot be reproduced still happened. An interrupt raises
    `SaveInterrupted` with the case saved as it was then (minimised if that had finished)."""
    mcap = None
    try:
        case = minimise(mode, case, until=minimise_until)
        path = save_case(case, directory)
        mcap = path.with_suffix(".mcap")
        replayed, exchange = replay_recorded(mode, case, mcap)
    except KeyboardInterrupt:
        if mcap is not None:     # the replay's capture was cut short: no half a capture
            mcap.unlink(missing_ok=True)
        raise SaveInterrupted(save_unreplayed(case, directory, note=INTERRUPTED_NOTE)) from None
    return Finding(case, path, mcap, replayed, exchange)


def save_unreplayed(case: Case, directory: str | Path, ring: RingCapture | None = None, *,
                    note: str) -> Finding:
    """Save the case as it is, with the live capture if there is one, no replay: quick, and
    a further interrupt waits for it, so the files are whole."""
    with InterruptGuard(held=True):
        path = save_case(case, directory)
        mcap = path.with_suffix(".mcap") if ring is not None else None
        exchange = ring.write(mcap) if ring is not None and mcap is not None else []
    return Finding(case, path, mcap, None, exchange, note=note)


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


def save_tool_failure(failure: ToolFailure, options: CampaignOptions, directory: str | Path) -> Path:
    """The steps that made mavconform raise, as a case (`--replay` runs it again, under a
    debugger if need be), and the traceback beside it as NAME.txt."""
    case = Case(options.mode, options.target, failure.seed, failure.steps, None,
                {"campaign_seed": options.seed, "tool_error": failure.error,
                 **({"handover": True} if options.handover else {})})
    path = save_case(case, directory)
    named = path.with_name(path.name.replace(f"{options.mode}-case-", f"{options.mode}-tool-error-"))
    path.replace(named)
    named.with_suffix(".txt").write_text(failure.trace, encoding="utf-8")
    return named


def replay_recorded(mode: ModuleType, case: Case,
                    mcap: Path | None) -> tuple[Violation | None, list[dict[str, Any]]]:
    recorder = ExchangeRecorder()
    capture = McapCapture(mcap) if mcap is not None else None

    def hook(record: CaptureRecord) -> None:
        recorder(record)
        if capture is not None:
            capture(record)

    def mark(label: str, *, clock: Any = None, level: str = "info") -> None:
        recorder.mark(label, clock=clock, level=level)
        if capture is not None:
            capture.mark(label, clock=clock, level=level)

    hook.mark = mark   # type: ignore[attr-defined]  # step markers: a note in the exchange and the capture
    try:
        violation = mode.replay(case, capture=hook)
    except UsageError:
        raise
    except MALFORMED as exc:
        raise UsageError(f"the {case.mode} case for {case.target} has a malformed step "
                         f"({type(exc).__name__}: {exc})") from None
    finally:
        if capture is not None:
            capture.close()
    return violation, recorder.events


class ExchangeRecorder:
    """Capture records -> the run document's exchange events, one lane per peer.

    The target is the in-process vehicle (the node named `vehicle`) or, over UDP, the side
    whose HEARTBEAT names an autopilot: what it sends is `rx` from the lane of the peer it
    sends to; everything else (the fuzzer's GCS, a second GCS, raw bytes) is `tx` on the
    sender's lane. Lanes are given at the end, when the target is known, since it may speak
    before its first HEARTBEAT. Bytes that do not decode are one note each, so garbage shows
    as garbage; `mark` (a replay's step markers) adds a note where each step starts."""

    IN_PROCESS_TARGET = "vehicle"
    LANES = {"a": "tester", "gcs": "tester", "b": "gcs-b"}   # the fuzzers' node names

    def __init__(self) -> None:
        self._raw: list[tuple[float, Any, Any, str, str, dict[str, Any]]] = []
        self.omitted = 0
        self._decoders: dict[Any, FrameDecoder] = {}
        self._target: Any = None
        self._t0: float | None = None

    def __call__(self, record: CaptureRecord) -> None:
        if record.kind == "rx":
            return                                  # each datagram once: when it was sent
        t = self._time(record.time)
        if self._target is None and record.src == self.IN_PROCESS_TARGET:
            self._target = record.src
        if record.kind == "drop":
            self._add(t, record.src, record.dst, "note", f"link dropped {len(record.data)} bytes", {})
            return
        decoder = self._decoders.setdefault(record.src, FrameDecoder())
        decoded = 0
        for frame in decoder.feed(record.data):
            msg = getattr(frame, "msg", None)
            if msg is None:                          # a DecodeError
                continue
            decoded += 1
            name = msg.get_type()
            if self._target is None and is_vehicle_heartbeat(msg):
                self._target = record.src
            if name in ("HEARTBEAT", "GLOBAL_POSITION_INT"):
                continue
            self._add(t, record.src, record.dst, "", name, message_fields(msg))
        if not decoded:
            self._add(t, record.src, record.dst, "note",
                      f"{len(record.data)} bytes that decode to no frame: {record.data[:24].hex()}"
                      + ("..." if len(record.data) > 24 else ""), {})

    def mark(self, label: str, *, clock: Any = None, level: str = "info") -> None:
        """A note where a replay step starts (the capture's `mark` signature)."""
        t = self._time(clock.now()) if clock is not None else (self._raw[-1][0] if self._raw else 0.0)
        self._add(t, None, None, "note", label, {})

    @property
    def events(self) -> list[dict[str, Any]]:
        out = []
        for t, src, dst, kind, msg, fields in self._raw:
            if kind == "note":
                out.append({"t": t, "dir": "note", "peer": self._lane(src if src != self._target else dst),
                            "msg": msg, "fields": fields})
            elif src == self._target:
                out.append({"t": t, "dir": "rx", "peer": self._lane(dst), "msg": msg, "fields": fields})
            else:
                out.append({"t": t, "dir": "tx", "peer": self._lane(src), "msg": msg, "fields": fields})
        if self.omitted:
            last = out[-1]["t"] if out else 0.0
            out.append({"t": last, "dir": "note", "peer": "fuzzer",
                        "msg": f"... {self.omitted} more events in the MCAP capture", "fields": {}})
        return out

    def _time(self, now: float) -> float:
        if self._t0 is None:
            self._t0 = now
        return round(now - self._t0, 6)

    def _lane(self, address: Any) -> str:
        if address is None:
            return "fuzzer"
        if address == self._target:        # the target's own lane is the diagram's middle
            return "target"
        if isinstance(address, str):
            return self.LANES.get(address, address)
        return "tester" if self._target is not None else ":".join(map(str, address))

    def _add(self, t: float, src: Any, dst: Any, kind: str, msg: str, fields: dict[str, Any]) -> None:
        if len(self._raw) >= MAX_EVENTS:      # the MCAP keeps them all
            self.omitted += 1
            return
        self._raw.append((t, src, dst, kind, msg, fields))


def parse_duration(text: str) -> float:
    """'90', '90s', '2m', '1h', '1.5m' -> seconds; anything else is a UsageError."""
    raw = text.strip().lower()
    factor = {"s": 1.0, "m": 60.0, "h": 3600.0}.get(raw[-1:], None)
    number = raw[:-1] if factor is not None else raw
    try:
        value = float(number) * (factor or 1.0)
    except ValueError:
        raise UsageError(f"bad duration {text!r}: expected seconds, e.g. 60, 60s, 5m or 1h") from None
    if not value > 0 or value == float("inf"):
        raise UsageError(f"bad duration {text!r}: must be a positive, finite time")
    return value
