"""The run document: everything a run decided, as the canonical JSON the reports render.

Format "mavconform-run/1" (reports/run_document.py checks it). It is built once, at the
end of a run, from the results and the run's options; every report is a view of it. A run
stopped by a signal says so (`run.interrupted`, where and by what) and its verdict is
"interrupted": the clauses it did not reach are skipped, not passed.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import Any

from mavconform import __version__

from .catalogue import BY_ID
from .gating import verdict
from .outcome import ClauseResult, Outcome
from .runner import RunOutcome

FORMAT = "mavconform-run/1"


@dataclass(frozen=True)
class RunOptions:
    target: str
    clauses: str = "*"
    strict: bool = False
    time_scale: float = 1.0
    seed: int = 0
    expectations: str | None = None
    baseline: str | None = None


def build(options: RunOptions, run: RunOutcome, *, started: dt.datetime,
          gating_flags: dict[str, bool], gating: dict[str, Any], capture: str | None) -> dict[str, Any]:
    counts = {o.value: 0 for o in Outcome}
    for r in run.results:
        counts[r.outcome.value] += 1
    failing = sum(1 for flag in gating_flags.values() if flag)
    return {
        "format": FORMAT,
        "tool": {"name": "mavconform", "version": __version__},
        "run": {
            "target": options.target, "started": started.strftime("%Y-%m-%dT%H:%M:%SZ"),
            "duration_s": round(run.duration_s, 3), "seed": options.seed,
            "time_scale": options.time_scale, "strict": options.strict, "clauses": options.clauses,
            "expectations": options.expectations, "baseline": options.baseline,
            "forced_wait_s": round(run.forced_wait_s, 3), "interrupted": run.interrupted,
            "interrupted_at": run.interrupted_at, "interrupted_by": run.interrupted_by,
        },
        "identity": run.identity,
        "summary": {"total": len(run.results), **counts, "gating_failures": failing,
                    "verdict": verdict(failing, interrupted=run.interrupted)},
        "gating": gating,
        "restore": run.restore,
        "capture": capture,
        "clauses": [_clause(r, gating_flags.get(r.clause_id, False)) for r in run.results],
    }


def _clause(r: ClauseResult, gating: bool) -> dict[str, Any]:
    c = BY_ID[r.clause_id]
    return {"id": c.id, "group": c.group, "level": c.level.value, "role": c.role.value,
            "title": c.title, "source": c.source, "requirement": c.requirement,
            "outcome": r.outcome.value, "gating": gating, "detail": r.detail,
            "expectation": r.expectation, "duration_s": r.duration_s, "exchange": r.exchange}
