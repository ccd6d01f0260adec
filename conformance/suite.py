"""One conformance run from options to reports: the function behind `mavconform run`,
the pytest plugin and the benchmark.

Everything the user gave is checked before the first datagram (target URI, clause glob,
expectations file, baseline file, report folder), so a mistake costs nothing and gets one
line and exit code 2.
"""

from __future__ import annotations

import datetime as dt
import math
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.capture import McapCapture
from mavconform.reference_impl.net.sim import CaptureHook

from . import catalogue, document, expectations, gating
from .clause import Clause
from .outcome import ClauseResult
from .runner import InterruptGuard, OnResult, RunOutcome, interrupted_before_start, run_clauses, run_guard
from .session import Session
from .target_uri import TargetUri, load_handover_scenario, parse_target

CAPTURE_NAME = "run.mcap"


@dataclass
class Prepared:
    """A run's inputs, all checked."""
    options: document.RunOptions
    uri: TargetUri
    clauses: list[Clause]
    expected: expectations.Expectations
    baseline: dict[str, str] | None
    report_dir: Path | None


def prepare(options: document.RunOptions, *, levels: str | None = None,
            report_dir: str | Path | None = None) -> Prepared:
    if not (options.time_scale > 0 and math.isfinite(options.time_scale)):
        raise UsageError(f"--time-scale must be a finite number > 0, got {options.time_scale!r}")
    uri = parse_target(options.target)
    if options.handover_scenario:
        uri = uri.with_scenario(load_handover_scenario(options.handover_scenario))
    uri = uri.with_profile(options.profile)
    if options.clock_speed is not None and options.clock_speed != 1.0 and not uri.in_process:
        raise UsageError(f"--clock-speed: {uri} is an external target, which lives in real time "
                         "(a faster clock is for builtin: and mutant: targets)")
    clauses = catalogue.select(options.clauses, levels)
    if not clauses:
        raise UsageError(f"no clause matches --clauses {options.clauses!r} with --level {levels!r}")
    expected, baseline, out = checked_outputs(options, report_dir)
    return Prepared(options, uri, clauses, expected, baseline, out)


def checked_outputs(options: document.RunOptions, report_dir: str | Path | None
                    ) -> tuple[expectations.Expectations, dict[str, str] | None, Path | None]:
    """The expectations, the baseline's outcomes and the report folder (made), each checked:
    what judges and keeps a run, whichever side of the protocol it tests."""
    expected = expectations.load(options.expectations) if options.expectations else expectations.Expectations()
    baseline = None
    if options.baseline:
        from mavconform.reports.run_document import load_run
        earlier = load_run(options.baseline)
        role = earlier["run"].get("role", "vehicle")
        if role != options.role:
            raise UsageError(f"--baseline {options.baseline}: a run of the {role} clauses; this run is "
                             f"of the {options.role}'s")
        baseline = gating.baseline_outcomes(earlier, options.baseline)
    out = None
    if report_dir is not None:
        out = Path(report_dir)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"cannot create report folder {str(out)!r}: {exc.strerror}") from None
    return expected, baseline, out


def execute(p: Prepared, *, virtual: bool = False, allow_flight: bool | None = None,
            restore: bool = True, on_result: OnResult | None = None,
            stop_signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM),
            ) -> tuple[dict[str, Any], RunOutcome]:
    """Run the prepared clauses; return the run document (reports written if asked).

    A `stop_signals` signal stops the run at the current clause (see `InterruptGuard`); the
    target's plans are still put back and every report written, a second signal cannot cut
    that short, and the outcome says it was interrupted (or, in `late_signal`, that a signal
    came while that was being done)."""
    def clauses(guard: InterruptGuard, capture: CaptureHook | None, on_result: OnResult | None) -> RunOutcome:
        try:
            with Session(p.uri, scale=p.options.time_scale, virtual=virtual, seed=p.options.seed,
                         allow_flight=allow_flight, capture=capture,
                         clock_speed=None if virtual else p.options.clock_speed) as session:
                session.on_identity = p.expected.identify
                run = run_clauses(session, p.clauses, on_result=on_result, restore=restore, guard=guard)
                if session.guard is not None and session.guard.crash:
                    run.restore = {**run.restore, "detail": run.restore["detail"]
                                   + f"; the in-process vehicle crashed: {session.guard.crash}"}
                return run
        except KeyboardInterrupt:   # before the session was open: nothing was sent
            guard.hold()
            return interrupted_before_start(p.clauses, guard.first, on_result)
    return guarded_run(p.options, p.expected, p.baseline, p.report_dir, clauses, on_result=on_result,
                       stop_signals=stop_signals, capture=True)


def guarded_run(options: document.RunOptions, expected: expectations.Expectations,
                baseline: dict[str, str] | None, report_dir: Path | None,
                clauses: Callable[[InterruptGuard, CaptureHook | None, OnResult | None], RunOutcome], *,
                on_result: OnResult | None, stop_signals: tuple[int, ...], capture: bool,
                frames: Callable[..., list[dict[str, Any]]] | None = None,
                ) -> tuple[dict[str, Any], RunOutcome]:
    """What every run does around its clauses, whichever side it tests: under an
    `InterruptGuard`, with the MCAP capture (if `capture` and a report folder), each result
    judged against the expectations as it comes; then the run judged, its document built and
    its reports written, and a signal that came meanwhile noted in `late_signal`.
    `clauses(guard, capture_hook, on_result)` runs them; `frames`: how the capture reads
    another protocol's bytes (MSP), MAVLink's if None."""
    started = dt.datetime.now(dt.timezone.utc)
    on_result = _judged_live(on_result, expected)
    with run_guard(stop_signals) as guard:
        mcap = McapCapture(report_dir / CAPTURE_NAME, frames=frames) if capture and report_dir is not None else None
        try:
            run = clauses(guard, guard.atomic(mcap) if mcap is not None else None, on_result)
        finally:
            guard.hold()
            if mcap is not None:
                mcap.close()
        gating.apply_expectations(run.results, expected)
        flags, summary = gating.gate(run.results, strict=options.strict, baseline=baseline)
        doc = document.build(options, run, started=started, gating_flags=flags, gating=summary,
                             capture=CAPTURE_NAME if mcap is not None else None)
        if report_dir is not None:
            from mavconform.reports.write import write_reports
            write_reports(doc, report_dir)
    if guard.received and not run.interrupted:
        run.late_signal = guard.first
    return doc, run


def _judged_live(on_result: OnResult | None, expected: expectations.Expectations) -> OnResult | None:
    """`on_result` with each result judged against the expectations as it comes, so the live
    line already says KNOWN (or "deviation no longer observed"), as the reports will."""
    if not expected.entries:
        return on_result

    def judged(clause: Clause, result: ClauseResult) -> None:
        gating.apply_expectations([result], expected)
        if on_result is not None:
            on_result(clause, result)
    return judged

