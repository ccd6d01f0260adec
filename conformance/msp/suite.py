"""One MSP conformance run from options to reports: `mavconform run --target builtin:msp|msp:...`.

As for vehicles and GCSs, everything the user gave is checked before the first byte, and the
reports, expectation files and baseline gating are the same (conformance/suite.py,
document.py, gating.py, reports/).
"""

from __future__ import annotations

import math
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.msp.capture import msp_frames
from mavconform.reference_impl.net.sim import CaptureHook

from .. import catalogue, document, expectations
from ..clause import Clause, Role
from ..runner import InterruptGuard, OnResult, RunOutcome, interrupted_before_start
from ..suite import checked_outputs, guarded_run
from .runner import run_msp_clauses
from .session import MspSession
from .target import MspTarget, parse_msp_target


@dataclass
class PreparedMsp:
    options: document.RunOptions
    target: MspTarget
    clauses: list[Clause]
    expected: expectations.Expectations
    baseline: dict[str, str] | None
    report_dir: Path | None


def prepare(options: document.RunOptions, *, levels: str | None = None,
            report_dir: str | Path | None = None) -> PreparedMsp:
    if not (options.time_scale > 0 and math.isfinite(options.time_scale)):
        raise UsageError(f"--time-scale must be a finite number > 0, got {options.time_scale!r}")
    target = parse_msp_target(options.target)
    clauses = catalogue.select(options.clauses, levels, role=Role.MSP)
    if not clauses:
        raise UsageError(f"no MSP clause matches --clauses {options.clauses!r} with --level {levels!r}")
    expected, baseline, out = checked_outputs(options, report_dir)
    return PreparedMsp(options, target, clauses, expected, baseline, out)


def execute(p: PreparedMsp, *, virtual: bool = False, restore: bool = True, on_result: OnResult | None = None,
            stop_signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)) -> tuple[dict[str, Any], RunOutcome]:
    """Run the prepared MSP clauses; return the run document (reports written if asked)."""
    def clauses(guard: InterruptGuard, capture: CaptureHook | None, on_result: OnResult | None) -> RunOutcome:
        try:
            with MspSession(p.target, virtual=virtual, scale=p.options.time_scale, seed=p.options.seed,
                            capture=capture) as session:
                return run_msp_clauses(session, p.clauses, on_result=on_result, restore=restore, guard=guard)
        except KeyboardInterrupt:
            guard.hold()
            return interrupted_before_start(p.clauses, guard.first, on_result)
    return guarded_run(p.options, p.expected, p.baseline, p.report_dir, clauses, on_result=on_result,
                       stop_signals=stop_signals, capture=not virtual, frames=msp_frames())
