"""A campaign as a run document ("mavconform-run/2"), so every report writer shows it.

Each invariant the mode checks is one row, like a clause: `FUZZ.PROTOCOL.atomic-upload`
passes if no example broke it and fails with the finding's detail, the replay command and
the replayed exchange (drawn as a sequence diagram in the HTML report) if one did. The
document also carries a `fuzz` block: the campaign's counters and every saved case.

As in a conformance run, what differs between two campaigns with the same seed and budget
(when it started, how long it took, the times of the replayed exchange) is in the
`volatile` section only: two campaigns with the same seed and budget against an in-process
target write fuzz.json files that diff to nothing outside it.

An interrupted campaign is marked so (`run.interrupted`, `run.interrupted_at`, where known
`run.interrupted_by`, and `fuzz.interrupted`). Its verdict is "fail" if it found something (a finding stands, however
the search ended), else "interrupted": a search that did not finish is not known to pass.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mavconform import __version__
from mavconform.reports.run_document import FORMAT, INTERRUPTED, outcome_counts

from .campaign import CampaignResult, Finding


def row_id(mode: str, invariant: str) -> str:
    return f"FUZZ.{mode.upper()}.{invariant}"


def campaign_document(result: CampaignResult) -> dict[str, Any]:
    opts = result.options
    by_invariant: dict[str, list[Finding]] = {}
    for finding in result.findings:
        name = finding.case.violation.invariant if finding.case.violation else "unknown"
        by_invariant.setdefault(name, []).append(finding)
    names = list(result.invariants) + sorted(set(by_invariant) - set(result.invariants))
    so_far = f"no example broke it in the {result.examples} examples run before the campaign was interrupted"
    rows = [_row(opts.mode, name, result.invariants.get(name, name), by_invariant.get(name, []),
                 so_far if result.interrupted else "no example broke it")
            for name in names]
    failing = sum(1 for r in rows if r["gating"])
    counts = outcome_counts(rows)
    run: dict[str, Any] = {
        "target": opts.target, "seed": opts.seed, "mode": opts.mode,
        "examples": result.examples, "units": result.units,
        "budget": (f"{opts.examples} examples" if opts.examples is not None else "")
        + (" / " if opts.examples is not None and opts.time_s is not None else "")
        + (f"{opts.time_s:g} s" if opts.time_s is not None else ""),
    }
    if result.interrupted:
        run.update(interrupted=True, interrupted_at=result.interrupted_at,
                   interrupted_by=result.interrupted_by)
    verdict = "fail" if failing else INTERRUPTED if result.interrupted else "pass"
    first_capture = next((f.capture for f in result.findings if f.capture is not None), None)
    return {
        "format": FORMAT,
        "tool": {"name": "mavconform", "version": __version__},
        "run": run,
        "identity": None,
        "summary": {"total": len(rows), **counts, "gating_failures": failing,
                    "verdict": verdict},
        "gating": {"mode": "default", "regressions": [], "fixed": []},
        "restore": {"status": "skipped",
                    "detail": "a fuzz campaign does not put back the target's plans"},
        "capture": str(first_capture) if first_capture is not None else None,
        "clauses": rows,
        "volatile": {
            "started": result.started.strftime("%Y-%m-%dT%H:%M:%SZ"),
            "duration_s": round(result.duration_s, 3),
            "clauses": {row["id"]: _volatile(row) for row in rows},
        },
        "fuzz": {"mode": opts.mode, "examples": result.examples, "units": result.units,
                 "interrupted": result.interrupted,
                 "findings": [_finding(f) for f in result.findings]},
    }


def replay_command(finding: Finding) -> str:
    return f"mavconform fuzz --replay {finding.path}"


def _row(mode: str, name: str, description: str, findings: list[Finding], unbroken: str) -> dict[str, Any]:
    failed = bool(findings)
    if failed:
        detail = " | ".join(
            f"{f.case.violation} (saved {f.path}; replay: {replay_command(f)}"
            + (f"; {f.note}" if f.note else "" if f.reproduced
               else "; WARNING: the replay did not reproduce it") + ")"
            for f in findings)
    else:
        detail = unbroken
    return {
        "id": row_id(mode, name), "group": f"FUZZ.{mode.upper()}", "level": "MUST",
        "role": "vehicle", "title": description, "source": f"fuzz oracle ({mode} mode)",
        "requirement": description, "outcome": "fail" if failed else "pass", "gating": failed,
        "detail": detail, "expectation": None, "duration_s": 0.0,
        "exchange": findings[0].exchange if failed else [],
    }


def _volatile(row: dict[str, Any]) -> dict[str, Any]:
    """Take the row's event times out of its exchange, for volatile.clauses[ID]."""
    times = [event.get("t", 0.0) for event in row["exchange"]]
    row["exchange"] = [{k: v for k, v in event.items() if k != "t"} for event in row["exchange"]]
    return {"duration_s": row.pop("duration_s"), "events": times}


def _finding(f: Finding) -> dict[str, Any]:
    v = f.case.violation
    return {
        "invariant": v.invariant if v else None, "detail": v.detail if v else "",
        "step": v.step if v else None, "steps": len(f.case.steps), "seed": f.case.seed,
        "case": str(f.path), "capture": str(f.capture) if f.capture else None,
        "reproduced": f.reproduced, "replay": replay_command(f),
        "name": Path(f.path).stem, "note": f.note or None,
    }
