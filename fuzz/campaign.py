"""A fuzz campaign: search with one mode, save each finding as a replayable case, report.

The modes (`fuzz.protocol`, `fuzz.frames`) search and shrink; this module is what they
have in common around that: the budget (examples or wall time, shrinking and saving
included), the progress counters, the findings directory (`NAME.json` + `NAME.mcap` per
finding, the capture taken by replaying the case, which also proves the case reproduces),
and the run document that the reports package renders, so CI shows fuzz findings the way
it shows conformance failures.

Beside it: `minimise.py` (making a finding small), `replay_capture.py` (its replay with the
capture and the report's exchange), `target_death.py` (a live target that died: saved at once
with the live capture, confirmed and minimised only with a restart hook) and `finding.py`
(what a saved finding is).

An interrupt (Ctrl-C or SIGTERM) ends a campaign as the budget does, at once:
the search hands over the findings it had seen (`SearchInterrupted`), shrunk as far as it
got; they are saved without minimising (in-process: replayed once, in virtual time, for the
capture; over UDP: with the live capture, not replayed), and `run_campaign` raises
`CampaignInterrupted` with the result, so its caller can still report. An interrupt while a
finding is minimised or replayed saves it as it was (`save_unreplayed`), never loses it.
"""

from __future__ import annotations

import datetime as dt
import importlib
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.interrupts import InterruptGuard

from .case import Case, save_case
from .finding import INTERRUPTED_NOTE, Finding, SaveInterrupted, save_unreplayed
from .minimise import minimise, set_shrink_time_limit, shrink_time_limit
from .outcomes import (DEATH_KINDS, SearchInterrupted, TargetUnresponsive, ToolError, ToolFailure,
                       caused_by_interrupt)
from .replay_capture import replay_recorded
from .target_death import RESTART_TIMEOUT, Restarter, RingCapture, save_death

__all__ = ["MODES", "RESTART_TIMEOUT", "INTERRUPTED_NOTE", "CampaignInterrupted", "CampaignOptions",
           "CampaignResult", "Finding", "Progress", "Restarter", "RingCapture", "SaveInterrupted",
           "load_mode", "minimise", "mode_invariants", "parse_duration", "replay_recorded", "run_campaign",
           "save_death", "save_finding", "save_tool_failure", "save_unreplayed", "shrink_time_limit"]

MODES = ("protocol", "frames")
SHRINK_LIMIT = 60.0          # s Hypothesis may spend shrinking one campaign's findings, at most
SAVE_GRACE = 2.0             # s left for saving a finding when the budget is spent (one replay)


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
