"""One GCS conformance run from options to reports: `mavconform run --role gcs`.

The GCS under test is named like a vehicle target: `builtin:gcs` (the reference GCS, in
this process, over UDP loopback), `gcs-mutant:NAME` (one with a planted bug), or a command
(`--gcs-cmd 'CMD {port} {op} {file}'`, adapters.py). Everything is checked before the first
operation, as for vehicles; the reports, expectation files and baseline gating are the
vehicle run's own (conformance/document.py, gating.py, reports/).
"""

from __future__ import annotations

import math
import signal
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.sim import CaptureHook

from .. import catalogue, document, expectations
from ..clause import Clause, Role
from ..runner import InterruptGuard, OnResult, RunOutcome
from ..session import BUILTIN_CLOCK_SPEED
from ..suite import checked_outputs, guarded_run
from .adapters import CommandAdapter, GcsAdapter, NodeAdapter
from .harness import GcsHarness
from .runner import run_gcs_clauses

BUILTIN = "builtin:gcs"
MUTANT_PREFIX = "gcs-mutant:"
TARGET_FORMS = f"{BUILTIN} (the reference GCS) or {MUTANT_PREFIX}NAME (`mavconform clauses --mutants`)"
DEFAULT_TIMEOUT_S = 30.0


@dataclass
class PreparedGcs:
    options: document.RunOptions
    adapter: GcsAdapter
    clauses: list[Clause]
    expected: expectations.Expectations
    baseline: dict[str, str] | None
    report_dir: Path | None
    timeout_s: float
    clock_speed: float = 1.0     # of the clock the stages and an in-process GCS share


def gcs_adapter(target: str | None, command: str | None, workdir: Path | None = None) -> GcsAdapter:
    """The adapter for `--target` or `--gcs-cmd` (one of them; neither: the reference GCS)."""
    if command is not None:
        if target is not None:
            raise UsageError("--gcs-cmd and --target both name the GCS under test: give one")
        return CommandAdapter(command, workdir=workdir)
    target = target or BUILTIN
    if target == BUILTIN:
        return NodeAdapter()
    if target.startswith(MUTANT_PREFIX):
        from .mutants import GCS_MUTANTS
        name = target[len(MUTANT_PREFIX):]
        if name not in GCS_MUTANTS:
            raise UsageError(f"--target {target!r}: no GCS mutant {name!r} (known: {', '.join(sorted(GCS_MUTANTS))})")
        return NodeAdapter(f"GCS mutant {name}", build=GCS_MUTANTS[name].build)
    raise UsageError(f"--target {target!r}: with --role gcs the GCS under test is {TARGET_FORMS}, "
                     "or a command (--gcs-cmd)")


def prepare(options: document.RunOptions, *, target: str | None, command: str | None,
            levels: str | None = None, report_dir: str | Path | None = None,
            timeout_s: float = DEFAULT_TIMEOUT_S) -> PreparedGcs:
    if not (timeout_s > 0 and math.isfinite(timeout_s)):
        raise UsageError(f"--gcs-timeout must be a finite number > 0, got {timeout_s!r}")
    clauses = catalogue.select(options.clauses, levels, role=Role.GCS)
    if not clauses:
        raise UsageError(f"no GCS clause matches --clauses {options.clauses!r} with --level {levels!r}")
    expected, baseline, out = checked_outputs(options, report_dir)
    speed = options.clock_speed
    if command is not None and speed not in (None, 1.0):
        raise UsageError("--clock-speed: a GCS command lives in real time (a faster clock is for "
                         f"{BUILTIN} and {MUTANT_PREFIX}NAME, in this process)")
    if speed is None:   # a process is told a real port and keeps real time; ours share our clock
        speed = 1.0 if command is not None else BUILTIN_CLOCK_SPEED
    workdir = (out / "gcs-jobs") if out is not None else Path(tempfile.mkdtemp(prefix="mavconform-gcs-"))
    return PreparedGcs(options, gcs_adapter(target, command, workdir), clauses, expected, baseline, out,
                       timeout_s, speed)


def execute(p: PreparedGcs, *, virtual: bool = False, on_result: OnResult | None = None,
            stop_signals: tuple[int, ...] = (signal.SIGINT, signal.SIGTERM)) -> tuple[dict[str, Any], RunOutcome]:
    """Run the prepared GCS clauses; return the run document (reports written if asked).
    `virtual`: in virtual time (an in-process GCS only; the tool's own tests)."""
    def clauses(guard: InterruptGuard, capture: CaptureHook | None, on_result: OnResult | None) -> RunOutcome:
        harness = GcsHarness(p.adapter, real_time=not virtual, timeout_s=p.timeout_s, seed=p.options.seed,
                             capture=capture, clock_speed=1.0 if virtual else p.clock_speed)
        return run_gcs_clauses(harness, p.clauses, on_result=on_result, guard=guard)
    return guarded_run(p.options, p.expected, p.baseline, p.report_dir, clauses, on_result=on_result,
                       stop_signals=stop_signals, capture=not virtual)
