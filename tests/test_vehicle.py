"""The reference vehicle as a whole, in virtual time: progress reporting and the flight."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.flight import haversine_m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionState
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.vehicle import VehicleConfig
from mavconform.reference_impl.wire.dialect import mavlink as d

from .rigs import vehicle_and_gcs

HOME = (47.397742, 8.545594)


def wp(seq, north_m, alt=20.0, command=Cmd.NAV_WAYPOINT, **kw):
    lat = HOME[0] + north_m / 111_195.0
    return MissionItem(seq, 3, int(command), x=round(lat * 1e7), y=round(HOME[1] * 1e7), z=alt, **kw)


def rig(config=None):
    r = vehicle_and_gcs(config, seed=1)
    return r.net, r.vehicle, r.gcs, r.session


def start_mission(net, gcs):
    gcs.send(d.MAVLink_command_long_message(1, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    net.run_for(0.01)


def reached(gcs):
    return [m.seq for m in gcs.received if m.get_type() == "MISSION_ITEM_REACHED"]


def test_flight_reaches_every_item_in_order_and_reports_progress():
    net, vehicle, gcs, s = rig()
    plan = [wp(0, 0, command=Cmd.NAV_TAKEOFF), wp(1, 100), wp(2, 200, param1=5.0),
            MissionItem(3, 2, int(Cmd.DO_CHANGE_SPEED), param2=5.0), wp(4, 300, command=Cmd.NAV_LAND, alt=0)]
    assert s.upload(MissionType.MISSION, plan).ok
    gcs.received.clear()
    t0 = net.clock.now()
    start_mission(net, gcs)
    acks = [m for m in gcs.received if m.get_type() == "COMMAND_ACK"]
    assert [a.result for a in acks] == [CommandResult.ACCEPTED]
    net.run_until(lambda: 4 in reached(gcs), timeout=600)
    elapsed = net.clock.now() - t0
    net.run_for(0.01)                    # the MISSION_CURRENT sent right after the last item
    assert reached(gcs) == [0, 1, 2, 3, 4]
    # the take-off straight up (20 m at 2.5 m/s), 300 m north at 10 m/s, the 5 s hold at item 2,
    # the DO item's 0.1 s, and the landing's 20 m descent at 2 m/s
    assert elapsed == pytest.approx(20 / 2.5 + 300 / 10 + 5 + 0.1 + 20 / 2, abs=0.2)
    currents = [m for m in gcs.received if m.get_type() == "MISSION_CURRENT"]
    assert [c.seq for c in currents if c.mission_state == MissionState.ACTIVE][:1] == [0]
    assert {c.seq for c in currents} >= {0, 1, 2, 3, 4}
    assert currents[-1].mission_state == MissionState.COMPLETE
    positions = [m for m in gcs.received if m.get_type() == "GLOBAL_POSITION_INT"]
    lats = [p.lat for p in positions]
    assert lats == sorted(lats) and lats[-1] > lats[0]   # it flew north
    end = vehicle.flight.where(net.clock.now())
    assert haversine_m(HOME[0], HOME[1], end.lat, end.lon) == pytest.approx(300, abs=1)


def test_a_hold_is_spent_at_the_waypoint_not_spread_over_the_leg():
    """NAV_WAYPOINT param1 is the time to stay there: the vehicle flies the leg at its speed,
    then waits at the waypoint (the position a GCS, or the mission computer, reads)."""
    net, vehicle, gcs, s = rig()
    assert s.upload(MissionType.MISSION, [wp(0, 0, alt=0.0), wp(1, 100, alt=0.0, param1=10.0)]).ok
    start_mission(net, gcs)
    net.run_until(lambda: 0 in reached(gcs), timeout=60)
    t0 = net.clock.now()
    for after, north in ((5.0, 50.0), (10.0, 100.0), (15.0, 100.0)):
        net.run_until(lambda: False, timeout=t0 + after - net.clock.now())
        p = vehicle.flight.where(net.clock.now())
        assert haversine_m(HOME[0], HOME[1], p.lat, p.lon) == pytest.approx(north, abs=1.5), after
    assert 1 not in reached(gcs)           # still holding at 15 s: reached at 20 s
    net.run_until(lambda: 1 in reached(gcs), timeout=10)
    assert net.clock.now() - t0 == pytest.approx(20.0, abs=0.1)


def test_set_current_mid_flight_skips_ahead():
    net, vehicle, gcs, s = rig()
    s.upload(MissionType.MISSION, [wp(i, 100 * i) for i in range(5)])
    start_mission(net, gcs)
    net.run_until(lambda: 1 in reached(gcs), timeout=60)
    assert s.set_current(4).ok
    net.run_until(lambda: 4 in reached(gcs), timeout=120)
    assert reached(gcs) == [0, 1, 4]


def test_do_jump_repeats_then_continues():
    net, vehicle, gcs, s = rig()
    jump = MissionItem(2, 2, int(Cmd.DO_JUMP), param1=1.0, param2=2.0)
    s.upload(MissionType.MISSION, [wp(0, 0), wp(1, 50), jump, wp(3, 100)])
    start_mission(net, gcs)
    net.run_until(lambda: 3 in reached(gcs), timeout=300)
    assert reached(gcs) == [0, 1, 2, 1, 2, 1, 2, 3]


def test_mission_start_without_a_mission_fails_and_autostart_flies_at_once():
    net, vehicle, gcs, s = rig()
    start_mission(net, gcs)
    acks = [m for m in gcs.received if m.get_type() == "COMMAND_ACK"]
    assert [a.result for a in acks] == [CommandResult.FAILED]
    net, vehicle, gcs, s = rig(VehicleConfig(autostart=True))
    s.upload(MissionType.MISSION, [wp(0, 0), wp(1, 30)])
    net.run_until(lambda: 1 in reached(gcs), timeout=60)
    assert reached(gcs) == [0, 1]


def test_unknown_command_is_unsupported_and_heartbeat_is_1hz():
    net, vehicle, gcs, s = rig()
    gcs.received.clear()
    gcs.send(d.MAVLink_command_long_message(1, 1, 31000, 0, 0, 0, 0, 0, 0, 0, 0))
    net.run_for(10.0)
    acks = [m for m in gcs.received if m.get_type() == "COMMAND_ACK"]
    assert [(a.command, a.result) for a in acks] == [(31000, CommandResult.UNSUPPORTED)]
    beats = [m for m in gcs.received if m.get_type() == "HEARTBEAT"]
    assert len(beats) == 10


def test_heartbeat_says_generic_autopilot_with_full_mission_support():
    """MAV_AUTOPILOT_GENERIC_MISSION_FULL is 7; the vehicle once sent 4 (MAV_AUTOPILOT_OPENPILOT)."""
    net, vehicle, gcs, s = rig()
    beat = gcs.target_heartbeat
    assert beat.autopilot == d.MAV_AUTOPILOT_GENERIC_MISSION_FULL == 7
    assert (beat.type, beat.system_status) == (d.MAV_TYPE_QUADROTOR, d.MAV_STATE_STANDBY)
    assert beat.base_mode == d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and beat.custom_mode == 0
