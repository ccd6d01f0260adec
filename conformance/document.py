"""The run document: everything a run decided, as the canonical JSON the reports render.

Format "mavconform-run/2" (reports/run_document.py checks it and says where what lives). It
is built once, at the end of a run, from the results and the run's options; every report
is a view of it. Each clause's `decided_by` is the index of the exchange event its check
judged last (the report marks it): an index, so stable, since the events' order is. What differs between two runs of the same target (start time, durations,
event times, forced waits, the target's ephemeral address, the numbers of `Measured`
texts, the datagrams our sockets dropped) goes into its `volatile` section only, so the
rest diffs to nothing. A run stopped
by a signal says so (`run.interrupted`, where and by what) and its verdict is
"interrupted": the clauses it did not reach are skipped, not passed.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import Any

from mavconform import __version__

from mavconform.reports.run_document import AMBIENT, FORMAT

from .catalogue import BY_ID
from .gating import verdict
from .harness.measured import Measured
from .outcome import ClauseResult, Outcome
from .runner import DecidedResult, RunOutcome


@dataclass(frozen=True)
class RunOptions:
    target: str
    clauses: str = "*"
    strict: bool = False
    time_scale: float = 1.0
    seed: int = 0
    clock_speed: float | None = None        # --clock-speed (None: the session's default)
    expectations: str | None = None
    baseline: str | None = None
    handover_scenario: str | None = None   # --handover-scenario (None: the conformance scenario)
    role: str = "vehicle"                   # --role: which side of the protocol the target plays
    profile: str | None = None              # --profile: what an external target is (its stored form)


def build(options: RunOptions, run: RunOutcome, *, started: dt.datetime,
          gating_flags: dict[str, bool], gating: dict[str, Any], capture: str | None) -> dict[str, Any]:
    counts = {o.value: 0 for o in Outcome}
    for r in run.results:
        counts[r.outcome.value] += 1
    failing = sum(1 for flag in gating_flags.values() if flag)
    left_armed = sum(1 for f in run.flights if f["disarmed"] is False)
    identity = None if run.identity is None else dict(run.identity)
    address = identity.pop("address", None) if identity is not None else None
    measured_identity = _measured_identity(identity)
    clauses, per_clause = [], {}
    for r in run.results:
        clauses.append(_clause(r, gating_flags.get(r.clause_id, False)))
        per_clause[r.clause_id] = _volatile(r, clauses[-1])
    return {
        "format": FORMAT,
        "tool": {"name": "mavconform", "version": __version__},
        "run": {
            "target": options.target, "seed": options.seed,
            "time_scale": options.time_scale, "strict": options.strict, "clauses": options.clauses,
            "expectations": options.expectations, "baseline": options.baseline,
            "interrupted": run.interrupted,
            "interrupted_at": run.interrupted_at, "interrupted_by": run.interrupted_by,
            **({"handover_scenario": options.handover_scenario} if options.handover_scenario else {}),
            **({"role": options.role} if options.role != "vehicle" else {}),
            **({"profile": options.profile} if options.profile else {}),
            **({"link": dict(run.link)} if run.link is not None else {}),
        },
        "identity": identity,
        "summary": {"total": len(run.results), **counts, "gating_failures": failing,
                    **({"left_armed": left_armed} if run.flights else {}),
                    "verdict": verdict(failing, interrupted=run.interrupted, left_armed=left_armed)},
        "gating": gating,
        "restore": run.restore,
        "capture": capture,
        **({"flights": [dict(f) for f in run.flights]} if run.flights else {}),
        "clauses": clauses,
        "volatile": {"started": started.strftime("%Y-%m-%dT%H:%M:%SZ"),
                     "duration_s": round(run.duration_s, 3),
                     "forced_wait_s": round(run.forced_wait_s, 3),
                     "address": address, "clauses": per_clause,
                     **({"identity": measured_identity} if measured_identity else {}),
                     **({"receive_queue": dict(run.receive_queue)} if run.receive_queue is not None else {}),
                     **({"link": dict(run.link_events)} if run.link_events is not None else {})},
    }


def _measured_identity(identity: dict[str, Any] | None) -> dict[str, dict[str, str]]:
    """Replace each measured identity text (the readiness line: how long the target took to
    boot) by its stable form; return the numbers, for volatile.identity."""
    values = {}
    for key, value in (identity or {}).items():
        if isinstance(value, Measured):
            identity[key] = value.stable
            if value.values:
                values[key] = dict(value.values)
    return values


def _clause(r: ClauseResult, gating: bool) -> dict[str, Any]:
    c = BY_ID[r.clause_id]
    return {"id": c.id, "group": c.group, "level": c.level.value, "role": c.role.value,
            "title": c.title, "source": c.source, "requirement": c.requirement,
            "outcome": r.outcome.value, "gating": gating, "detail": r.detail,
            "expectation": r.expectation, "exchange": r.exchange, "decided_by": r.decided_by}


def _volatile(r: ClauseResult, clause: dict[str, Any]) -> dict[str, Any]:
    """Take the clause's volatile values out of `clause` (its detail and exchange become
    stable) and return them, for volatile.clauses[ID]: the times, measured numbers, and the
    ambient events (a stream's messages no check used: how many fell inside the clause is
    the stream's phase), each with the index it had in the whole exchange."""
    entry: dict[str, Any] = {"duration_s": r.duration_s}
    for key in ("host_lag_s", "first_attempt"):   # conformance/host_lag.py
        if getattr(r, key, None) is not None:
            entry[key] = getattr(r, key)
    detail, values = str(r.detail), {}
    for text in (r.measured if isinstance(r, DecidedResult) else []):
        if text.values and str(text) in detail:   # an expectation may have reworded around it
            detail = detail.replace(str(text), text.stable)
            values.update(text.values)
    clause["detail"] = detail
    if values:
        entry["detail"] = values
    events, times, notes, ambient, kept_as = [], [], {}, [], {}
    for index, recorded in enumerate(r.exchange):
        event = {key: value for key, value in recorded.items() if key not in ("t", AMBIENT)}
        t = recorded.get("t", 0.0)
        if recorded.get(AMBIENT) and index != r.decided_by:
            ambient.append({"at": index, "t": t, **event})   # a stream's timing, not evidence
            continue
        kept_as[index] = len(events)
        times.append(t)
        if isinstance(event["msg"], Measured):
            if event["msg"].values:
                notes[str(len(events))] = dict(event["msg"].values)
            event["msg"] = event["msg"].stable
        events.append(event)
    clause["exchange"] = events
    clause["decided_by"] = kept_as.get(r.decided_by) if r.decided_by is not None else None
    entry["events"] = times
    if notes:
        entry["notes"] = notes
    if ambient:
        entry["ambient"] = ambient
    return entry
