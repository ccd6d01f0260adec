"""One conformance run from options to reports: the function behind `mavconform run`,
the pytest plugin and the benchmark.

Everything the user gave is checked before the first datagram (target URI, clause glob,
expectations file, baseline file, report folder), so a mistake costs nothing and gets one
line and exit code 2.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.capture import McapCapture

from . import catalogue, document, expectations, gating
from .clause import Clause
from .outcome import ClauseResult
from .runner import OnResult, RunOutcome, run_clauses
from .session import Session
from .target_uri import TargetUri, parse_target

CAPTURE_NAME = "run.mcap"


@dataclass
class Prepared:
    """A run's inputs, all checked."""
    options: document.RunOptions
    uri: TargetUri
    clauses: list[Clause]
    expected: dict[str, expectations.Deviation]
    baseline: dict[str, str] | None
    report_dir: Path | None


def prepare(options: document.RunOptions, *, levels: str | None = None,
            report_dir: str | Path | None = None) -> Prepared:
    if not (options.time_scale > 0 and math.isfinite(options.time_scale)):
        raise UsageError(f"--time-scale must be a finite number > 0, got {options.time_scale!r}")
    uri = parse_target(options.target)
    clauses = catalogue.select(options.clauses, levels)
    if not clauses:
        raise UsageError(f"no clause matches --clauses {options.clauses!r} with --level {levels!r}")
    expected = expectations.load(options.expectations) if options.expectations else {}
    baseline = None
    if options.baseline:
        from mavconform.reports.run_document import load_run
        baseline = gating.baseline_outcomes(load_run(options.baseline))
    out = None
    if report_dir is not None:
        out = Path(report_dir)
        try:
            out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"cannot create report folder {str(out)!r}: {exc.strerror}") from None
    return Prepared(options, uri, clauses, expected, baseline, out)


def execute(p: Prepared, *, virtual: bool = False, allow_flight: bool | None = None,
            restore: bool = True, on_result: OnResult | None = None) -> tuple[dict[str, Any], RunOutcome]:
    """Run the prepared clauses; return the run document (reports written if asked)."""
    started = dt.datetime.now(dt.timezone.utc)
    if p.expected:
        # Judge each result against the expectations as it comes, so the live line already
        # says KNOWN (or "deviation no longer observed"), as the reports will.
        shown = on_result

        def on_result(clause: Clause, result: ClauseResult) -> None:
            gating.apply_expectations([result], p.expected)
            if shown is not None:
                shown(clause, result)
    capture = None
    if p.report_dir is not None:
        capture = McapCapture(p.report_dir / CAPTURE_NAME)
    try:
        with Session(p.uri, scale=p.options.time_scale, virtual=virtual, seed=p.options.seed,
                     allow_flight=allow_flight, capture=capture) as session:
            run = run_clauses(session, p.clauses, on_result=on_result, restore=restore)
            if session.guard is not None and session.guard.crash:
                run.restore = {**run.restore, "detail": run.restore["detail"]
                               + f"; the in-process vehicle crashed: {session.guard.crash}"}
    finally:
        if capture is not None:
            capture.close()
    gating.apply_expectations(run.results, p.expected)
    flags, summary = gating.gate(run.results, strict=p.options.strict, baseline=p.baseline)
    doc = document.build(p.options, run, started=started, gating_flags=flags, gating=summary,
                         capture=CAPTURE_NAME if capture is not None else None)
    if p.report_dir is not None:
        from mavconform.reports.write import write_reports
        write_reports(doc, p.report_dir)
    return doc, run
