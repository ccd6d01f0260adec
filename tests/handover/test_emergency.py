"""The emergency decision: where to go (home, a rally point, or land here), and when it fires."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.handover.emergency import (
    BatteryModel, BatteryState, RefugeKind, TriggerKind, TriggerPolicy, choose_refuge, due_triggers, usable_range_m,
)
from mavconform.reference_impl.handover.geo import GeoPoint, destination, haversine_m

HOME = GeoPoint(47.397742, 8.545594)
MODEL = BatteryModel(capacity_wh=100.0, consumption_wh_per_m=0.01, reserve_wh=20.0)   # 1 km per 10 Wh


def at(bearing: float, metres: float) -> GeoPoint:
    return destination(HOME, bearing, metres)


def wh_for_range(metres: float) -> BatteryState:
    """A battery whose usable range is `metres` (above the reserve)."""
    return BatteryState(MODEL.reserve_wh + metres * MODEL.consumption_wh_per_m)


# --- the energy model ------------------------------------------------------------------

def test_usable_range_is_what_is_left_above_the_reserve_per_metre() -> None:
    assert usable_range_m(BatteryState(100.0), MODEL) == pytest.approx(8000.0)
    assert usable_range_m(BatteryState(20.0), MODEL) == 0.0
    assert usable_range_m(BatteryState(5.0), MODEL) == 0.0          # below the reserve: nothing, not negative


def test_a_fraction_of_the_pack_and_what_a_leg_costs() -> None:
    state = BatteryState.from_fraction(0.5, MODEL)
    assert state.remaining_wh == 50.0 and state.fraction(MODEL) == 0.5
    assert state.after(1000.0, MODEL).remaining_wh == pytest.approx(40.0)
    assert state.after(1e9, MODEL).remaining_wh == 0.0                # an empty pack, never below
    assert BatteryModel.with_reserve_fraction(90.0, 0.0075, 0.25).reserve_wh == 22.5


@pytest.mark.parametrize("build, message", [
    (lambda: BatteryModel(0.0, 0.01), "capacity_wh must be more than 0"),
    (lambda: BatteryModel(100.0, -1.0), "consumption_wh_per_m must be more than 0"),
    (lambda: BatteryModel(100.0, 0.01, 101.0), "reserve_wh 101 is more than the capacity 100 Wh"),
    (lambda: BatteryModel(100.0, math.nan), "consumption_wh_per_m must be a finite number"),
    (lambda: BatteryModel.with_reserve_fraction(100.0, 0.01, 1.5), "reserve_fraction must be in [0, 1]"),
    (lambda: BatteryState(-1.0), "remaining_wh must be at least 0"),
    (lambda: BatteryState.from_fraction(1.2, MODEL), "remaining fraction must be in [0, 1]"),
    (lambda: TriggerPolicy(0.0), "loss_timeout_s must be more than 0"),
])
def test_bad_numbers_are_refused_by_name(build, message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("[", r"\[").replace("]", r"\]")):
        build()


# --- the choice ------------------------------------------------------------------------

def test_home_when_it_is_the_nearest() -> None:
    r = choose_refuge(at(45, 500), HOME, [at(45, 2000)], BatteryState(100.0), MODEL)
    assert r.kind is RefugeKind.HOME and r.point == HOME and r.rally_index is None
    assert r.distance_m == pytest.approx(500.0, abs=1e-6)
    assert r.command == "MAV_CMD_NAV_RETURN_TO_LAUNCH"
    assert r.reason.startswith("return to launch: home is 500 m away")
    assert "home is nearer than every rally point (nearest 1.50 km)" in r.reason


def test_the_nearest_rally_point_when_it_is_nearer_than_home() -> None:
    rally = [at(45, 2000), at(45, 3500), at(0, 3000)]
    r = choose_refuge(at(45, 3000), HOME, rally, BatteryState(100.0), MODEL)
    assert r.kind is RefugeKind.RALLY and r.rally_index == 1 and r.point == rally[1]
    assert r.command == "MAV_CMD_DO_REPOSITION"
    assert r.reason.startswith("rally point 1: the nearest refuge in range, 500 m away (home 3.00 km)")


def test_a_nearer_refuge_out_of_range_means_nothing_is_in_range() -> None:
    # Reachability is a distance threshold: the nearest is out of range only if all are.
    r = choose_refuge(at(45, 3000), HOME, [at(45, 3500)], wh_for_range(400.0), MODEL)
    assert r.kind is RefugeKind.LAND_HERE and not r.reachable
    assert r.point == at(45, 3000) and r.distance_m == 0.0 and r.margin_m == 0.0
    assert r.command == "MAV_CMD_NAV_LAND"
    assert r.reason.startswith("land here: the nearest refuge (rally point 0, 500 m) is beyond the usable range of 400 m")


def test_farther_refuges_out_of_range_are_counted_in_the_reason() -> None:
    r = choose_refuge(at(45, 3000), HOME, [at(45, 3500), at(225, 1000)], wh_for_range(600.0), MODEL)
    assert r.kind is RefugeKind.RALLY and r.rally_index == 0
    assert r.reason.endswith("; 2 farther refuges out of range")
    assert r.margin_m == pytest.approx(100.0, abs=1e-6)


def test_a_refuge_exactly_at_the_range_is_reachable() -> None:
    position = at(90, 1234.5)
    d = haversine_m(position, HOME)
    exact = BatteryModel(capacity_wh=1e9, consumption_wh_per_m=1.0)     # range = remaining Wh, exactly
    r = choose_refuge(position, HOME, [], BatteryState(d), exact)
    assert r.kind is RefugeKind.HOME and r.margin_m == 0.0
    assert r.reason.endswith("no rally points")
    assert choose_refuge(position, HOME, [], BatteryState(math.nextafter(d, 0.0)), exact).kind is RefugeKind.LAND_HERE


def test_a_tie_goes_to_home_then_to_the_first_rally_point() -> None:
    r = choose_refuge(HOME, HOME, [HOME, HOME], BatteryState(100.0), MODEL)
    assert r.kind is RefugeKind.HOME and "ties with the nearest rally point and is preferred" in r.reason
    twin = at(10, 800)
    r = choose_refuge(at(10, 1000), HOME, [at(200, 50), twin, twin], BatteryState(100.0), MODEL)
    assert r.kind is RefugeKind.RALLY and r.rally_index == 1


def test_inputs_that_are_not_points_are_refused() -> None:
    with pytest.raises(TypeError, match=r"rally\[1\] must be a GeoPoint"):
        choose_refuge(HOME, HOME, [HOME, (47.0, 8.0)], BatteryState(1.0), MODEL)  # type: ignore[list-item]


# --- properties ------------------------------------------------------------------------

def around_home(max_m: float = 6000.0):
    return st.builds(at, st.floats(0.0, 359.99), st.floats(0.0, max_m))


def batteries():
    return st.floats(0.0, MODEL.capacity_wh).map(BatteryState)


refuge_inputs = st.tuples(around_home(), around_home(), st.lists(around_home(), max_size=6), batteries())


def _distances(position: GeoPoint, home: GeoPoint, rally: list[GeoPoint]) -> list[float]:
    return [haversine_m(position, home)] + [haversine_m(position, p) for p in rally]


@given(refuge_inputs)
def test_the_choice_is_reachable_whenever_any_refuge_is(args) -> None:
    position, home, rally, battery = args
    r = choose_refuge(position, home, rally, battery, MODEL)
    reach = usable_range_m(battery, MODEL)
    any_reachable = any(d <= reach for d in _distances(position, home, rally))
    assert r.reachable is any_reachable
    if r.reachable:
        assert r.distance_m <= reach
        assert r.distance_m == haversine_m(position, r.point)
        assert r.point == (home if r.kind is RefugeKind.HOME else rally[r.rally_index])
    else:
        assert r.kind is RefugeKind.LAND_HERE and r.point == position


@given(refuge_inputs)
def test_never_a_farther_refuge_when_a_nearer_one_is_reachable(args) -> None:
    position, home, rally, battery = args
    r = choose_refuge(position, home, rally, battery, MODEL)
    reach = usable_range_m(battery, MODEL)
    for d in _distances(position, home, rally):
        if d <= reach:
            assert r.distance_m <= d


@given(refuge_inputs, st.floats(0.0, MODEL.capacity_wh))
def test_more_battery_never_changes_a_reachable_choice(args, more_wh: float) -> None:
    position, home, rally, battery = args
    richer = BatteryState(min(MODEL.capacity_wh, battery.remaining_wh + more_wh))
    low = choose_refuge(position, home, rally, battery, MODEL)
    high = choose_refuge(position, home, rally, richer, MODEL)
    assert high.usable_range_m >= low.usable_range_m
    if low.reachable:
        assert (high.kind, high.rally_index, high.point) == (low.kind, low.rally_index, low.point)
    if not high.reachable:
        assert not low.reachable


# --- triggers --------------------------------------------------------------------------

POLICY = TriggerPolicy(loss_timeout_s=5.0, outside_grace_s=1.0)


def test_the_commander_is_lost_at_the_timeout_not_before() -> None:
    assert due_triggers(14.999, commander_last_heard=10.0, outside_since=None, policy=POLICY) == ()
    (fired,) = due_triggers(15.0, commander_last_heard=10.0, outside_since=None, policy=POLICY)
    assert fired.kind is TriggerKind.COMMANDER_LOST and fired.due_at == 15.0
    assert fired.reason == "commander silent for 5.0 s (loss timeout 5 s)"


def test_outside_every_coverage_after_the_grace() -> None:
    assert due_triggers(20.5, commander_last_heard=20.0, outside_since=20.0, policy=POLICY) == ()
    (fired,) = due_triggers(21.0, commander_last_heard=20.0, outside_since=20.0, policy=POLICY)
    assert fired.kind is TriggerKind.OUTSIDE_COVERAGE
    assert fired.reason == "outside every GCS's coverage for 1.0 s (grace 1 s)"


def test_no_commander_and_inside_coverage_never_fire() -> None:
    assert due_triggers(1e6, commander_last_heard=None, outside_since=None, policy=POLICY) == ()


def test_triggers_come_earliest_first_and_commander_lost_first_on_a_tie() -> None:
    fired = due_triggers(30.0, commander_last_heard=20.0, outside_since=10.0, policy=POLICY)
    assert [t.kind for t in fired] == [TriggerKind.OUTSIDE_COVERAGE, TriggerKind.COMMANDER_LOST]
    fired = due_triggers(30.0, commander_last_heard=10.0, outside_since=14.0, policy=POLICY)
    assert [t.kind for t in fired] == [TriggerKind.COMMANDER_LOST, TriggerKind.OUTSIDE_COVERAGE]


def test_a_time_that_is_not_a_number_is_refused() -> None:
    with pytest.raises(ValueError, match="commander_last_heard must be a finite time"):
        due_triggers(1.0, commander_last_heard=math.inf, outside_since=None, policy=POLICY)
