"""The handover's safety properties under faults (mavconform.fuzz.handover), in virtual time.

Whole delivery flights from the shipped scenario files, with a random fault model on each
direction of each GCS's link (loss, duplication, reordering, latency, jitter, partitions) and
a random behaviour per GCS (cooperating, refusing, no agent, slow operator, releasing; silent
for a while; meddling while not in control; retaking an uncontrolled vehicle). The five
properties are stated in fuzz/handover/properties.py and docs/handover.md ("Safety
properties"). Each one is shown failing on a vehicle broken for it (fuzz/handover/variants.py)
on a flight the reference vehicle passes.

CI cost: two seeded Hypothesis tests of EXAMPLES flights each (xdist runs them side by side);
longer campaigns: `python -m mavconform.fuzz.handover --examples N --seed S`.
"""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import seed as hypothesis_seed

from mavconform.fuzz.handover import PROPERTIES, Behaviour, FlightCase, Link, check, flight_cases, fly_and_judge
from mavconform.fuzz.handover.__main__ import main
from mavconform.fuzz.handover.variants import VARIANTS, WITNESSES
from mavconform.fuzz.handover.world import vehicle_with
from mavconform.reference_impl.handover.mission_computer import MissionComputer
from mavconform.reference_impl.handover.mission_computer_transitions import McState

EXAMPLES = 20
_SETTINGS = settings(max_examples=EXAMPLES, deadline=None, database=None,
                     suppress_health_check=list(HealthCheck), print_blob=True)


@hypothesis_seed(20261124)
@_SETTINGS
@given(flight_cases())
def test_every_property_holds_on_random_delivery_flights_under_faults(case):
    check(case)


@hypothesis_seed(14)
@_SETTINGS
@given(flight_cases())
def test_every_property_holds_on_more_random_delivery_flights_under_faults(case):
    check(case)


# --- the properties can fail ----------------------------------------------------------------------
@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_each_property_fails_on_the_vehicle_broken_for_it_and_holds_on_the_reference(variant):
    factory, prop = VARIANTS[variant]
    case = WITNESSES[variant]
    _, broken = fly_and_judge(case, factory)
    assert not broken.setup_failed
    assert prop in {v.prop for v in broken.violations}, (variant, broken.violations)
    _, reference = fly_and_judge(case)
    assert not reference.setup_failed and reference.violations == [], reference.violations


def test_the_variants_cover_every_property():
    assert sorted(prop for _, prop in VARIANTS.values()) == sorted(PROPERTIES)


# --- what the judge measures ----------------------------------------------------------------------
def test_a_clean_flight_hands_over_twice_with_no_stale_belief_beyond_a_hop():
    report = check(FlightCase(seed=7))
    assert report.handovers == {"completed": 2} and report.emergencies == 0
    assert report.max_stale_belief <= 0.01 + 1e-6      # CONTROL_STATUS at once on the change: one hop


def test_a_commander_that_cannot_hear_the_vehicle_believes_it_commands_until_it_does():
    """A's uplink is cut for 10 s a minute after take-off and its downlink for 30 s: the vehicle
    drops A after the loss timeout (the emergency), but A hears nothing until 90 s, so it
    believes it commands for about 25 s after it lost control. Stale, not a violation: no
    CONTROL_STATUS reached it meanwhile, and the first one that does corrects it."""
    case = FlightCase(seed=8, links=(("A", Link(partitions=((60.0, 70.0),)), Link(partitions=((60.0, 90.0),))),),
                      max_duration=150.0)
    report = check(case)
    assert report.emergencies == 1 and 20.0 < report.max_stale_belief < 30.0


def test_a_silent_commander_is_an_emergency_and_a_returning_operator_takes_back_and_resumes():
    case = FlightCase(seed=9, behaviours=(("A", Behaviour(silent=((40.0, 52.0),), retake=True)),))
    world, report = fly_and_judge(case)
    assert report.violations == [] and report.emergencies == 1 and report.takebacks == 1
    assert report.handovers.get("completed", 0) == 2                 # resumed, then handed over and back
    assert not world.vehicle.flight.flying


def test_the_campaign_entry_point_prints_the_figures(capsys):
    assert main(["--examples", "2", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "flights: 2 " in out and "longest handover:" in out and "violations: none" in out
    with pytest.raises(SystemExit) as stop:
        main(["--examples", "0"])
    assert stop.value.code == 2


# --- findings ---------------------------------------------------------------------------------------
FOUND_LATE_ALLOW = FlightCase(
    scenario="delivery_flight_circles.json", seed=0,
    links=(("B", Link(loss=0.125, duplicate=0.125, reorder=0.25, reorder_delay=0.5, delay=0.0,
                      partitions=((0.0, 3.0),)), Link(delay=0.0)), ("A", Link(delay=0.0), Link(delay=0.0))),
    behaviours=(("A", Behaviour(kind="slow", answer_delay=8.0)),))


def test_regression_a_late_allow_after_the_abort_does_not_hand_control_over():
    """Found by the campaign (seed 3, shrunk): A's operator allows 8 s after the forward, after
    the handover was aborted at its commit deadline; the manager, with no request pending,
    took that as "takeover allowed" and granted B's waiting request 0.35 s after the abort,
    inside the region (P2). The vehicle now refuses the aborted partner's requests
    (TEMPORARILY_REJECTED) until it has left the region."""
    world, report = fly_and_judge(FOUND_LATE_ALLOW)
    assert report.violations == [] and report.handovers == {"aborted": 1, "completed": 1}
    assert any("was aborted: not before the vehicle leaves it" in e for e in world.vehicle.events)

    class WithoutTheBar(MissionComputer):
        def screen(self, frame):
            return super().screen(frame) if self.state is McState.ON_EMERGENCY else None
    _, before = fly_and_judge(FOUND_LATE_ALLOW, vehicle_with(mission_computer=WithoutTheBar))
    assert [v.prop for v in before.violations] == ["P2"] and "after its handover" in before.violations[0].text


def test_after_an_abort_at_the_deadline_the_partner_is_refused_until_the_vehicle_leaves_the_region():
    from mavconform.reference_impl.handover.control_results import ControlChanged
    from mavconform.reference_impl.handover.mission_computer import MissionComputerConfig
    from mavconform.reference_impl.wire.dialect import mavlink as d

    from .test_mission_computer import COVERAGES, A, B, at, request

    mc = MissionComputer(1, 1, MissionComputerConfig(parent=A, coverages=COVERAGES["polygon"]))
    mc.control_changed(ControlChanged(A, 0, False, "t"), 0.0)

    def fly(north: float, until: float) -> None:
        for _ in range(10_000):
            t = mc.next_deadline()
            if t is None or t > until:
                return
            mc.observe(at(north), t)
            mc.poll(t)
    mc.observe(at(0), 0.0)
    mc.start(0.0)
    mc.poll(0.0)                                                              # starts outside the region
    fly(1000, 5.0)
    assert mc.attempt is not None and mc.screen(request(B)) is None          # during it: the manager decides
    fly(1000, 5.0 + mc.config.commit_timeout + 1.0)
    assert mc.results[-1].outcome.value == "aborted"
    refusal = mc.screen(request(B))
    assert refusal is not None and refusal.actions[0].msg.result == d.MAV_RESULT_TEMPORARILY_REJECTED
    assert mc.screen(request(A)) is None and mc.screen(request(B, action=0.0)) is None   # owner; a release
    fly(1500, 60.0)                                                           # left the region (B's side only)
    assert mc.screen(request(B)) is None
