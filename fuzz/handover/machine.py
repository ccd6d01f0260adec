"""Random delivery flights for the safety properties: Hypothesis strategies and a campaign.

`flight_cases()` draws a `FlightCase`: one of the geographic delivery scenarios, a seed, the
scenario's handover bound or the default 40 s, a fault model for each direction of each
GCS's link (loss up to 25 %, duplication up to 20 %, reordering up to 30 % held back up to
0.5 s, latency and jitter up to 0.2 s each, up to two partitions of up to 8 s) and a
behaviour for each GCS (world.py: cooperating, refusing, without handover agent, a slow
operator, releasing; a silent window of up to 15 s; meddling while not in control; retaking
an uncontrolled vehicle). Hypothesis shrinks a
failing case towards clean links and cooperating GCSs, so a finding reads as the least that
breaks the property.

`campaign(examples, seed)` flies that many cases (Hypothesis, seeded, no example database)
and returns the figures: flights, handovers by outcome, the longest handover against the
bound, emergencies, takebacks, the longest stale belief, and the first violation (shrunk).
`python -m mavconform.fuzz.handover --examples N --seed S` prints them.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import seed as hypothesis_seed
from hypothesis import strategies as st

from ..seeded import seeded_hypothesis
from .properties import Judge, Report
from .world import BEHAVIOURS, MEDDLES, SCENARIOS, Behaviour, FlightCase, Link, World, fly

__all__ = ["CampaignResult", "campaign", "check", "fly_and_judge", "flight_cases"]

GCS_NAMES = ("A", "B")      # the delivery scenarios' two stations
FLIGHT_S = 550.0            # their flight time at cruise, without emergencies


def _windows(max_count: int, max_len: float) -> st.SearchStrategy[tuple[tuple[float, float], ...]]:
    window = st.tuples(st.floats(0.0, FLIGHT_S), st.floats(0.5, max_len)).map(lambda w: (w[0], w[0] + w[1]))
    return st.lists(window, max_size=max_count).map(lambda ws: tuple(sorted(ws)))


def links() -> st.SearchStrategy[Link]:
    return st.builds(Link, loss=st.floats(0.0, 0.25), duplicate=st.floats(0.0, 0.2), reorder=st.floats(0.0, 0.3),
                     reorder_delay=st.floats(0.01, 0.5), delay=st.floats(0.0, 0.2), jitter=st.floats(0.0, 0.2),
                     partitions=_windows(2, 8.0))


def behaviours() -> st.SearchStrategy[Behaviour]:
    meddle = st.tuples(st.floats(0.0, FLIGHT_S), st.sampled_from(MEDDLES), st.integers(0, 8))
    return st.builds(Behaviour, kind=st.sampled_from(BEHAVIOURS), answer_delay=st.floats(0.5, 12.0),
                     silent=_windows(1, 15.0),
                     meddle=st.lists(meddle, max_size=3).map(lambda m: tuple(sorted(m))), retake=st.booleans())


@st.composite
def flight_cases(draw: Callable[..., Any]) -> FlightCase:
    return FlightCase(
        scenario=draw(st.sampled_from(SCENARIOS)),
        seed=draw(st.integers(0, 2**32 - 1)),
        bound=draw(st.sampled_from([None, 40.0])),
        links=tuple((name, draw(links()), draw(links())) for name in GCS_NAMES),
        behaviours=tuple((name, draw(behaviours())) for name in GCS_NAMES),
    )


def fly_and_judge(case: FlightCase, vehicle_factory: Any = None) -> tuple[World, Report]:
    """Fly `case` with a judge watching; the world and what the judge found."""
    world = fly(case, judge_factory=Judge, vehicle_factory=vehicle_factory)
    return world, world.judge.report


class PropertyViolated(AssertionError):
    """A flight broke a safety property; the message names the case and every violation."""


def check(case: FlightCase, vehicle_factory: Any = None) -> Report:
    """Fly `case`; raise PropertyViolated if any property failed."""
    _, report = fly_and_judge(case, vehicle_factory)
    if report.setup_failed:
        raise PropertyViolated(f"setup failed: {report.setup_failed} ({case})")
    if report.violations:
        lines = "\n".join(f"  {v}" for v in report.violations[:10])
        raise PropertyViolated(f"{len(report.violations)} violation(s) in\n  {case}\n{lines}")
    return report


@dataclass
class CampaignResult:
    examples: int = 0                    # flights flown (shrinking included)
    handovers: dict[str, int] = field(default_factory=dict)
    worst: dict[float, float] = field(default_factory=dict)   # bound -> the longest handover seen under it
    emergencies: int = 0
    takebacks: int = 0
    max_stale_belief: float = 0.0
    virtual_s: float = 0.0
    wall_s: float = 0.0
    failure: str = ""                    # the (shrunk) finding, if any

    def add(self, case: FlightCase, bound: float, report: Report) -> None:
        self.examples += 1
        for k, n in report.handovers.items():
            self.handovers[k] = self.handovers.get(k, 0) + n
        self.worst[bound] = max([self.worst.get(bound, 0.0), *report.durations])
        self.emergencies += report.emergencies
        self.takebacks += report.takebacks
        self.max_stale_belief = max(self.max_stale_belief, report.max_stale_belief)
        self.virtual_s += report.flight_time

    def summary(self) -> str:
        n = sum(self.handovers.values())
        outcomes = ", ".join(f"{k} {v}" for k, v in sorted(self.handovers.items())) or "none"
        lines = [f"flights: {self.examples} ({self.virtual_s / 3600:.1f} h of virtual flight in {self.wall_s:.0f} s)",
                 f"handovers: {n} ({outcomes})",
                 "longest handover: " + "; ".join(f"{w:.2f} s with bound {b:g} s" for b, w in sorted(self.worst.items())),
                 f"emergencies: {self.emergencies}, taken back: {self.takebacks}",
                 f"longest stale belief (a GCS believing it commands while another does): "
                 f"{self.max_stale_belief:.2f} s",
                 "violations: none" if not self.failure else f"FINDING:\n{self.failure}"]
        return "\n".join(lines)


def campaign(examples: int, seed: int = 0, *, vehicle_factory: Any = None, shrink: bool = True) -> CampaignResult:
    """Fly `examples` random cases (seeded); stop at the first violation and shrink it."""
    from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, load_scenario

    result = CampaignResult()
    bounds = {name: load_scenario(SCENARIOS_DIR / name).timeouts.handover_bound_s for name in SCENARIOS}
    phases = [Phase.generate, Phase.shrink] if shrink else [Phase.generate]

    @hypothesis_seed(seed)
    @settings(max_examples=examples, deadline=None, database=None, phases=phases,
              suppress_health_check=list(HealthCheck), print_blob=False)
    @given(flight_cases())
    def one(case: FlightCase) -> None:
        _, report = fly_and_judge(case, vehicle_factory)
        result.add(case, case.bound or bounds[case.scenario], report)
        if report.violations or report.setup_failed:
            lines = "\n".join(f"  {v}" for v in report.violations[:10]) or f"  setup failed: {report.setup_failed}"
            raise PropertyViolated(f"{case}\n{lines}")

    started = time.monotonic()
    try:
        with seeded_hypothesis(virtual_time=True):
            one()
    except PropertyViolated as finding:
        result.failure = str(finding)
    result.wall_s = time.monotonic() - started
    return result
