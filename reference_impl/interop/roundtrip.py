"""A round trip through one vehicle profile under link faults, as a user runs it: upload,
download, set-current, clear, each retried by hand (at most `ATTEMPTS` times) if it fails.

It is the interop report's first table and the shape of the interop property test: what
comes back must equal what went up, modulo the profile's documented transforms
(`Profile.stored_items`: home item, rounding, frame forms).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from ..mission.items import PLAN_TYPES, MissionItem, MissionType
from ..mission.results import OperationResult
from ..net import FaultModel
from ..profiles import Profile
from .harness import Pair, build_pair, expected_plan, sample_plan

ATTEMPTS = 3
REPORT_FAULTS = FaultModel(loss=0.1, duplicate=0.05, reorder=0.05, reorder_delay=0.05, jitter=0.02)


@dataclass
class Step:
    what: str
    result: OperationResult | None
    attempts: int
    problem: str = ""      # "" when it did what it should

    @property
    def ok(self) -> bool:
        return not self.problem


@dataclass
class RoundTrip:
    profile: str
    steps: list[Step] = field(default_factory=list)
    adaptations_used: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        return all(s.ok for s in self.steps)


def attempt(pair: Pair, start: Callable[[], OperationResult | None]) -> tuple[OperationResult | None, int]:
    """Run an operation up to ATTEMPTS times (a user pressing the button again after a
    failure, once both ends are idle); the last result and how many attempts it took."""
    result = None
    for n in range(1, ATTEMPTS + 1):
        result = start()
        if result is None or result.ok:
            return result, n
        pair.settle()
    return result, ATTEMPTS


def round_trip(profile: Profile, *, seed: int = 1, faults: FaultModel = REPORT_FAULTS,
               plans: dict[MissionType, list[MissionItem]] | None = None, set_current: int = 1) -> RoundTrip:
    pair = build_pair(profile, seed=seed, up=faults, down=faults.copy())
    plans = plans if plans is not None else {t: sample_plan(4, t) for t in PLAN_TYPES}
    out = RoundTrip(profile.name)

    def step(what: str, start: Callable[[], OperationResult | None], check: Callable[[OperationResult], str]) -> None:
        result, n = attempt(pair, start)
        if result is None:
            problem = "no result (hang)"
        elif not result.ok:
            problem = result.summary()
        else:
            problem = check(result)
        if pair.settle() is None:
            problem = problem or "an end stayed busy"
        out.steps.append(Step(what, result, n, problem))

    for t, items in plans.items():
        wanted = expected_plan(profile, items, t)
        step(f"upload {t.label}", lambda: pair.upload(t, items),
             lambda r: "" if pair.held(t) == wanted else "vehicle does not hold the plan")
        step(f"download {t.label}", lambda: pair.download(t),
             lambda r: "" if r.items == wanted else "downloaded plan differs")
    home = 1 if profile.behaviour.home_at_seq0 else 0
    step(f"set current {set_current}", lambda: pair.set_current(set_current),
         lambda r: "" if pair.vehicle.server.progress.seq == set_current + home else
         f"vehicle's current item is {pair.vehicle.server.progress.seq}")
    step("clear all", lambda: pair.clear(MissionType.ALL),
         lambda r: "" if all(pair.held(t) == () for t in PLAN_TYPES) else "a plan is left")
    out.adaptations_used = pair.gcs.adaptations_used
    return out


def render_markdown(trips: list[RoundTrip], faults: FaultModel = REPORT_FAULTS, seed: int = 1) -> str:
    lines = [
        "### Round trip under link faults",
        "",
        f"Upload, download, set-current and clear of a 4-item mission, fence and rally plan with "
        f"loss {faults.loss:g}, duplication {faults.duplicate:g}, reordering {faults.reorder:g} and "
        f"jitter {faults.jitter * 1000:g} ms each way (seed {seed}); a failed operation is retried "
        f"by hand up to {ATTEMPTS} times. *ok (n)*: done as it should in n attempts; downloads equal "
        "the upload modulo the profile's documented transforms (`Profile.stored_items`).",
        "",
    ]
    names = [s.what for s in trips[0].steps] if trips else []
    lines.append("| profile | " + " | ".join(names) + " | adaptations used |")
    lines.append("|---|" + "---|" * (len(names) + 1))
    for trip in trips:
        cells = [f"ok ({s.attempts})" if s.ok else f"FAIL: {s.problem}" for s in trip.steps]
        lines.append(f"| {trip.profile} | " + " | ".join(cells) + f" | {', '.join(trip.adaptations_used) or 'none'} |")
    return "\n".join(lines) + "\n"
