"""The fault-tolerance table: the reference GCS against every QGC MockLink failure mode, on
every vehicle profile, in virtual time.

For each (profile, mode) cell: a fresh GCS and vehicle, a plan already on the vehicle (the
one a read fetches; the one a write must replace or leave alone), the mode armed, one
download or upload, then a wait for both ends to go idle. The verdict:
- "recovers": the operation succeeded and the plan is right (downloaded == what the
  profile documents; after an upload the vehicle holds it);
- "fails cleanly": exactly one result, a NACK / timeout / protocol-error / rejection,
  both ends idle within `IDLE_BOUND`, and the vehicle's plan unchanged unless the result
  said the outcome is unknown;
- "FAILS UNCLEANLY: <why>": anything else (no result within `RESULT_BOUND`, a second result,
  a wrong plan reported as success, a plan changed while the result claimed it was not,
  an end still busy).
Times are virtual seconds from the start of the operation to its result. Same inputs, same
table, byte for byte (CI regenerates it and compares it with docs/fault-tolerance.md).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from typing import Sequence

from ..mission.adaptations import BY_ID
from ..mission.constants import MissionResult
from ..mission.items import MissionType
from ..mission.results import Operation, OperationResult, Outcome
from ..profiles import Profile
from .harness import IDLE_BOUND, RESULT_BOUND, build_pair, expected_plan, sample_plan
from .mocklink import MODES, FailureMode, MockLinkVehicle

PLAN_SIZE = 5          # "final ACK with requests missing" needs request 3
OLD_PLAN_SIZE = 3
CLEAN_OUTCOMES = frozenset({Outcome.NACK, Outcome.TIMEOUT, Outcome.PROTOCOL_ERROR, Outcome.REJECTED})
RECOVERS, FAILS_CLEANLY, FAILS_UNCLEANLY = "recovers", "fails cleanly", "FAILS UNCLEANLY"
SETUP_ERROR = "ERROR"   # undecided: the plan could not be put on the vehicle first


@dataclass(frozen=True)
class Cell:
    profile: str
    mode: str
    verdict: str                   # RECOVERS | FAILS_CLEANLY | FAILS_UNCLEANLY | SETUP_ERROR
    result: str                    # e.g. "timeout", "nack ERROR", "success"; "" if none
    seconds: float | None          # start of the operation to its result (virtual)
    idle_after: float | None       # result to both ends idle (virtual)
    why: str = ""                  # what made it unclean, or a note on a clean failure
    detail: str = ""               # the result's own detail
    injections: int = 0            # how many times the mode acted on the wire
    first_injection: str = ""
    adaptations: tuple[str, ...] = ()

    @property
    def text(self) -> str:
        if self.verdict in (FAILS_UNCLEANLY, SETUP_ERROR):
            return f"{self.verdict}: {self.why}"
        secs = f"{self.seconds:.1f} s"
        if self.verdict == RECOVERS:
            return f"recovers ({secs})"
        note = f"; {self.why}" if self.why else ""
        return f"fails cleanly: {self.result} ({secs}){note}"


@dataclass(frozen=True)
class FaultTable:
    profiles: tuple[str, ...]
    modes: tuple[FailureMode, ...]
    cells: tuple[Cell, ...]
    seed: int = 0
    adaptations: dict[str, tuple[str, ...]] = field(default_factory=dict)   # profile -> armed

    def cell(self, profile: str, mode: str) -> Cell:
        return next(c for c in self.cells if c.profile == profile and c.mode == mode)

    @property
    def unclean(self) -> tuple[Cell, ...]:
        """Cells that failed uncleanly or could not be decided."""
        return tuple(c for c in self.cells if c.verdict in (FAILS_UNCLEANLY, SETUP_ERROR))


def _describe(result: OperationResult) -> str:
    if result.outcome is Outcome.NACK and result.nack is not None:
        return f"nack {MissionResult.describe(int(result.nack))}"
    return result.outcome.value.replace("_", " ")


def run_cell(profile: Profile, mode: FailureMode, *, seed: int = 0) -> Cell:
    """One cell of the table: `mode` injected in front of a fresh `profile` vehicle."""
    wrapper: list[MockLinkVehicle] = []

    def wrap(vehicle):
        wrapper.append(MockLinkVehicle(vehicle, mode))
        return wrapper[0]

    pair = build_pair(profile, seed=seed, wrap=wrap)
    injector = wrapper[0]
    t = MissionType.MISSION
    old, new = sample_plan(OLD_PLAN_SIZE, t, shift=100), sample_plan(PLAN_SIZE, t)
    setup = pair.upload(t, old if mode.operation is Operation.UPLOAD else new)
    if setup is None or not setup.ok or pair.settle() is None:
        why = setup.summary() if setup is not None else "no result"
        return Cell(profile.name, mode.id, SETUP_ERROR, "", None, None, f"putting the plan on the vehicle failed ({why})")
    before = pair.vehicle.store.snapshot()
    injector.armed = True
    n_results = len(pair.gcs.results)
    start = pair.download if mode.operation is Operation.DOWNLOAD else (lambda tt: pair.upload(tt, new))
    result = start(t)

    def cell(verdict: str, why: str = "", idle: float | None = None) -> Cell:
        return Cell(profile.name, mode.id, verdict, _describe(result) if result else "",
                    None if result is None else round(result.finished - result.started, 3),
                    None if idle is None else round(idle, 3), why,
                    result.detail if result else "", injector.fired,
                    injector.injections[0][1] if injector.injections else "",
                    result.adaptations if result else ())

    if result is None:
        return cell(FAILS_UNCLEANLY, f"no result within {RESULT_BOUND:g} s")
    idle = pair.settle()
    pair.net.run_for(IDLE_BOUND)      # anything still to come would be a second result
    if len(pair.gcs.results) != n_results + 1:
        return cell(FAILS_UNCLEANLY, f"{len(pair.gcs.results) - n_results} results for one operation", idle)
    if idle is None:
        busy = "vehicle" if not pair.vehicle.server.is_idle() else "GCS"
        return cell(FAILS_UNCLEANLY, f"{busy} still busy {IDLE_BOUND:g} s after the result")
    changed = pair.vehicle.store.snapshot() != before
    held, wanted = pair.held(t), expected_plan(profile, new, t)
    if result.ok:
        if mode.operation is Operation.DOWNLOAD:
            if result.items != wanted:
                return cell(FAILS_UNCLEANLY, "success with a downloaded plan that differs from the vehicle's", idle)
        elif held != wanted:
            return cell(FAILS_UNCLEANLY, "success, but the vehicle does not hold the uploaded plan", idle)
        return cell(RECOVERS, idle=idle)
    if result.outcome not in CLEAN_OUTCOMES:
        return cell(FAILS_UNCLEANLY, f"ended as {result.outcome.value}", idle)
    if not changed:
        return cell(FAILS_CLEANLY, idle=idle)
    if mode.operation is Operation.DOWNLOAD:
        return cell(FAILS_UNCLEANLY, "a failed download changed the vehicle's plan", idle)
    if not result.outcome_unknown:
        return cell(FAILS_UNCLEANLY, "plan changed while the result said it was not", idle)
    what = "new plan applied" if held == wanted else "vehicle holds a mix of old and new (non-atomic)"
    return cell(FAILS_CLEANLY, f"outcome unknown, {what}", idle)


def build_table(profiles: Sequence[Profile], modes: Sequence[FailureMode] = MODES, *,
                seed: int = 0) -> FaultTable:
    cells = tuple(run_cell(p, mode, seed=seed) for mode in modes for p in profiles)
    armed = {}
    for p in profiles:
        pair = build_pair(p, seed=seed)
        armed[p.name] = tuple(a.id for a in pair.gcs.adaptations.armed())
    return FaultTable(tuple(p.name for p in profiles), tuple(modes), cells, seed, armed)


# --- rendering ---------------------------------------------------------------------------
def render_markdown(table: FaultTable) -> str:
    lines = [
        "### QGroundControl MockLink failure modes",
        "",
        "Each cell: one download (read) or upload (write) of a 5-item mission by the reference GCS, "
        "with the failure injected in front of a fresh vehicle of that profile "
        "(`reference_impl/interop/mocklink.py`). *recovers*: the operation succeeded with the right "
        "plan. *fails cleanly*: one NACK / timeout / protocol-error result, both ends idle within "
        f"{IDLE_BOUND:g} s, the vehicle's plan untouched unless the result said the outcome is unknown. "
        "Times are virtual seconds from the start of the operation to its result. QGC's own "
        "expectation (MissionManagerTest) is in the second column.",
        "",
        "| failure mode | QGC expects | " + " | ".join(table.profiles) + " |",
        "|---|---|" + "---|" * len(table.profiles),
    ]
    for mode in table.modes:
        kind = "read" if mode.operation is Operation.DOWNLOAD else "write"
        row = [f"{kind}: {mode.description} (`{mode.qgc}`)", "recovers" if mode.qgc_recovers else "fails"]
        row += [table.cell(p, mode.id).text for p in table.profiles]
        lines.append("| " + " | ".join(row) + " |")
    lines += ["", "Adaptations the GCS chose from each vehicle's HEARTBEAT, and those that acted in "
              "this table:", ""]
    for p in table.profiles:
        used: dict[str, None] = {}
        for c in table.cells:
            if c.profile == p:
                used.update(dict.fromkeys(c.adaptations))
        armed = ", ".join(table.adaptations.get(p, ())) or "none (spec-exact GCS)"
        lines.append(f"- **{p}**: chosen: {armed}; used: {', '.join(used) or 'none'}")
    unclean = table.unclean
    lines += ["", f"{len(table.cells) - len(unclean)} of {len(table.cells)} cells recover or fail cleanly."]
    return "\n".join(lines) + "\n"


def to_json(table: FaultTable) -> dict:
    return {
        "seed": table.seed,
        "profiles": list(table.profiles),
        "adaptations_chosen": {p: list(a) for p, a in table.adaptations.items()},
        "modes": [{"id": m.id, "qgc": m.qgc, "operation": m.operation.value, "description": m.description,
                   "qgc_expects": "recovers" if m.qgc_recovers else "fails"} for m in table.modes],
        "cells": [{**asdict(c), "adaptations": list(c.adaptations), "text": c.text} for c in table.cells],
    }


def render_json(table: FaultTable) -> str:
    return json.dumps(to_json(table), indent=2, sort_keys=True) + "\n"


def adaptation_lines() -> list[str]:
    """The adaptation catalogue as Markdown bullets (id, what it does, where it comes from)."""
    return [f"- `{a.id}`: {a.description} ({a.source})" for a in BY_ID.values()]
