"""The flight model's take-off and landing (sans-IO FlightSim, virtual time given by hand):
a take-off item climbs, a landing item descends and ends the mission, a ground vehicle never
leaves the ground; outside the mission the autopilot's climb, hold and stop."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.flight import CLIMB_SPEED, DESCENT_SPEED, FlightSim, Position, haversine_m
from mavconform.reference_impl.mission.constants import Cmd, MissionState
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.progress import MissionProgress
from mavconform.reference_impl.mission.store import MissionStore

HOME = Position(47.397742, 8.545594, 0.0)
M_PER_DEG = 111_195.0
SPEED = 10.0


def item(seq: int, command: int, north_m: float | None = None, alt: float = 0.0, **kw) -> MissionItem:
    """An item `north_m` north of home (None: no position, lat/lon 0)."""
    x = y = 0
    if north_m is not None:
        x, y = round((HOME.lat + north_m / M_PER_DEG) * 1e7), round(HOME.lon * 1e7)
    return MissionItem(seq, 3, int(command), x=x, y=y, z=alt, **kw)


def flight(items: list[MissionItem], *, ground: bool = False, speedup: float = 1.0) -> FlightSim:
    store = MissionStore()
    store.commit(MissionType.MISSION, items)
    return FlightSim(store, MissionProgress(store, 1.0), home=HOME, speed=SPEED, ground=ground, speedup=speedup)


def reached(sends) -> list[int]:
    return [s.msg.seq for s in sends if s.msg.get_type() == "MISSION_ITEM_REACHED"]


def north_of_home(p: Position) -> float:
    return haversine_m(HOME.lat, HOME.lon, p.lat, p.lon)


def test_a_take_off_item_without_a_position_climbs_straight_up():
    f = flight([item(0, Cmd.NAV_TAKEOFF, alt=30.0), item(1, Cmd.NAV_WAYPOINT, 100, alt=30.0)])
    f.start(0.0)
    assert f.next_deadline() == pytest.approx(30.0 / CLIMB_SPEED)
    mid = f.where(6.0)
    assert mid.alt == pytest.approx(6.0 * CLIMB_SPEED) and north_of_home(mid) < 0.01
    assert f.airborne(6.0) and not f.airborne(0.0)
    assert reached(f.poll(30.0 / CLIMB_SPEED)) == [0]
    assert f.where(30.0 / CLIMB_SPEED).alt == pytest.approx(30.0)


def test_a_take_off_item_with_a_position_climbs_on_the_way_there():
    f = flight([item(0, Cmd.NAV_VTOL_TAKEOFF, 50, alt=20.0)])
    f.start(0.0)
    # 50 m at 10 m/s (5 s) against 20 m at the climb speed (8 s): the slower one
    assert f.next_deadline() == pytest.approx(max(50.0 / SPEED, 20.0 / CLIMB_SPEED), rel=1e-3)


def test_a_landing_item_flies_over_its_spot_descends_and_ends_the_mission():
    after = item(2, Cmd.NAV_WAYPOINT, 500, alt=20.0)
    f = flight([item(0, Cmd.NAV_WAYPOINT, 0, alt=20.0), item(1, Cmd.NAV_LAND, 100), after])
    f.start(0.0)
    assert reached(f.poll(2.0)) == [0]                   # 20 m up at home (20 m at 10 m/s)
    over = 2.0 + 100.0 / SPEED
    assert f.where(over).alt == pytest.approx(20.0, abs=0.05)
    assert north_of_home(f.where(over)) == pytest.approx(100, abs=0.5)
    down = over + 20.0 / DESCENT_SPEED
    assert f.next_deadline() == pytest.approx(down, rel=1e-3)
    assert f.where((over + down) / 2).alt == pytest.approx(10.0, abs=0.1)
    out = f.poll(down + 0.01)
    assert reached(out) == [1] and f.landed_at == pytest.approx(down, rel=1e-3)
    assert not f.flying and not f.airborne(down + 1) and f.position.alt == HOME.alt
    assert f.progress.state is MissionState.COMPLETE and f.progress.seq == 1   # item 2 is never flown
    assert f.next_deadline() is None and reached(f.poll(down + 100)) == []


def test_a_landing_item_without_a_position_lands_where_the_vehicle_is():
    f = flight([item(0, Cmd.NAV_WAYPOINT, 80, alt=10.0), item(1, Cmd.NAV_VTOL_LAND)])
    f.start(0.0)
    f.poll(100.0)
    assert f.landed_at is not None and north_of_home(f.position) == pytest.approx(80, abs=0.5)


def test_a_ground_vehicle_never_leaves_the_ground():
    plan = [item(0, Cmd.NAV_TAKEOFF, alt=30.0), item(1, Cmd.NAV_WAYPOINT, 100, alt=50.0),
            item(2, Cmd.NAV_LAND, 200)]
    f = flight(plan, ground=True)
    f.start(0.0)
    assert reached(f.poll(0.1)) == [0]                  # the take-off is done at once: no climb
    assert f.where(5.0).alt == HOME.alt and not f.airborne(5.0)
    assert reached(f.poll(0.1 + 100 / SPEED)) == [1]    # 100 m at its speed, no climb to 50 m
    assert f.position.alt == HOME.alt
    assert reached(f.poll(0.1 + 200 / SPEED)) == [2]    # a landing item is one more place to drive to
    assert f.landed_at is None and f.progress.state is MissionState.COMPLETE


def test_a_climb_outside_the_mission_holds_at_its_altitude_until_the_mission_starts():
    f = flight([item(0, Cmd.NAV_WAYPOINT, 100, alt=10.0)])
    f.climb(10.0, 0.0)
    assert f.flying and f.diverting and f.next_deadline() == pytest.approx(10.0 / CLIMB_SPEED)
    f.poll(10.0)
    assert f.where(10.0).alt == pytest.approx(10.0) and f.next_deadline() is None   # holding up there
    f.start(10.0)
    assert not f.diverting and f.next_deadline() == pytest.approx(10.0 + 100 / SPEED, rel=1e-3)


def test_hold_stops_mid_leg_and_stop_puts_the_vehicle_on_the_ground():
    f = flight([item(0, Cmd.NAV_WAYPOINT, 200, alt=20.0)])
    f.start(0.0)
    f.hold(10.0)
    here = f.where(10.0)
    assert f.flying and not f.progress.running and f.where(50.0) == here and here.alt > 5
    f.stop(60.0)
    assert not f.flying and not f.progress.running and f.where(70.0) == Position(here.lat, here.lon, HOME.alt)


@pytest.mark.parametrize("speedup", [1.0, 4.0])
def test_a_speedup_flies_legs_climbs_and_descents_faster_but_holds_as_long(speedup):
    """The builtin vehicles' real-time runs fly 4 times faster (conformance/session.py): the
    same path, every leg, climb and descent `speedup` times shorter, a loiter's time unchanged."""
    hold = 3.0
    f = flight([item(0, Cmd.NAV_TAKEOFF, alt=20.0), item(1, Cmd.NAV_WAYPOINT, 200, alt=20.0),
                item(2, Cmd.NAV_LOITER_TIME, 200, alt=20.0, param1=hold), item(3, Cmd.NAV_LAND, 0)],
               speedup=speedup)
    f.start(0.0)
    ends = []
    for _ in range(4):
        at = f.next_deadline()
        ends.append(at)
        f.poll(at)
    climb, leg, home_leg = 20.0 / CLIMB_SPEED, 200.0 / SPEED, 200.0 / SPEED + 20.0 / DESCENT_SPEED
    assert ends == pytest.approx([climb / speedup, (climb + leg) / speedup,
                                  (climb + leg) / speedup + hold, (climb + leg + home_leg) / speedup + hold],
                                 rel=1e-3)
    assert f.landed_at == pytest.approx(ends[-1]) and not f.airborne(ends[-1])
