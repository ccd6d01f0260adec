"""Operator control in the runnable nodes, in virtual time: the reference vehicle with its
system manager on, reference GCSs asking for control through `GcsSession`.

The rules are development.xml's (MAV_CMD_REQUEST_OPERATOR_CONTROL, CONTROL_STATUS); the
engines' own tests check them one by one, these check the wiring: what reaches the mission
server, what a GCS not in control is told, and that HEARTBEATs keep an owner.
"""

from __future__ import annotations

import pytest

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover.control_client import ClientConfig, always
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.control_results import (
    ControlChanged, ControlOperation as Op, ControlOutcome as O, Decision, OwnerLost, TakeoverRequested)
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.net import FaultModel
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleConfig
from mavconform.reference_impl.wire import FrameDecoder
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcs, vehicle_and_gcss

A, B = 201, 202
HOME = (47.397742, 8.545594)
LOSS = 5.0
LATENCY = FaultModel(delay=0.02)


def plan(n: int, north: float = 100.0) -> list[MissionItem]:
    return [MissionItem(i, 3, int(Cmd.NAV_WAYPOINT), x=round((HOME[0] + i * north / 111_195.0) * 1e7),
                        y=round(HOME[1] * 1e7), z=20.0) for i in range(n)]


def fleet(*, a_policy=always(Decision.ALLOW), b_policy=always(None), **manager):
    """The vehicle with its manager on; GCS A answers forwarded requests by `a_policy`."""
    config = VehicleConfig(control=ManagerConfig(owner_loss_timeout=LOSS, **manager))
    gcss = {n: GcsConfig(system=s, control=ClientConfig()) for n, s in (("A", A), ("B", B))}
    return vehicle_and_gcss(config, gcss, policies={"A": a_policy, "B": b_policy}, link=LATENCY, seed=3)


def acks_for(gcs, command: int) -> list[int]:
    return [m.result for m in gcs.received if m._type == "COMMAND_ACK" and m.command == command]


def start_mission(f, name: str) -> int:
    """MAV_CMD_MISSION_START from GCS `name`; the result of its COMMAND_ACK."""
    gcs = f.gcs(name)
    before = len(acks_for(gcs, Cmd.MISSION_START))
    gcs.send(d.MAVLink_command_long_message(1, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    assert f.net.run_until(lambda: len(acks_for(gcs, Cmd.MISSION_START)) > before, timeout=2.0)
    return acks_for(gcs, Cmd.MISSION_START)[-1]


def statuses(gcs) -> list:
    return [m for m in gcs.received if m._type == "CONTROL_STATUS"]


# --- control off: nothing changes ----------------------------------------------------------
def test_without_control_the_vehicle_answers_32100_unsupported_and_takes_anyones_plan():
    r = vehicle_and_gcs(seed=1)
    r.gcs.send(d.MAVLink_command_long_message(1, 1, d.MAV_CMD_REQUEST_OPERATOR_CONTROL, 0,
                                              1, 0, 10, r.gcs.config.system, 0, 0, 0))
    r.net.run_for(3.0)
    assert acks_for(r.gcs, d.MAV_CMD_REQUEST_OPERATOR_CONTROL) == [CommandResult.UNSUPPORTED]
    assert not statuses(r.gcs) and r.vehicle.control is None and r.vehicle.owner == 0
    assert r.session.upload(MissionType.MISSION, plan(3)).ok
    with pytest.raises(LocalProtocolError, match="operator control is off"):
        r.session.request_control()


def test_a_control_client_against_a_vehicle_without_it_is_told_unsupported():
    f = vehicle_and_gcss(None, {"A": GcsConfig(system=A, control=ClientConfig())})
    s = f.sessions["A"]
    assert not s.wait_for_control_status(3.0)
    r = s.request_control()
    assert (r.outcome, r.result) == (O.REJECTED, d.MAV_RESULT_UNSUPPORTED)


# --- control on ----------------------------------------------------------------------------
def test_unowned_the_filter_is_closed_but_reads_and_the_request_are_open():
    """Nobody owns control: a write is refused, a download and the request go through."""
    f = fleet()
    a = f.sessions["A"]
    assert a.wait_for_control_status(2.0)
    up = a.upload(MissionType.MISSION, plan(2))
    assert not up.ok and up.nack == MissionResult.DENIED
    assert a.download(MissionType.MISSION).ok
    assert start_mission(f, "A") == d.MAV_RESULT_NOT_IN_CONTROL
    assert a.request_control().outcome is O.GRANTED
    assert a.upload(MissionType.MISSION, plan(2)).ok


def test_open_when_unowned_lets_any_gcs_write_until_one_takes_control():
    f = fleet(open_when_unowned=True)
    a, b = f.sessions["A"], f.sessions["B"]
    assert b.upload(MissionType.MISSION, plan(2)).ok
    assert a.request_control().ok
    assert b.upload(MissionType.MISSION, plan(3)).nack == MissionResult.DENIED


def test_two_gcs_handover_through_the_vehicle():
    """A takes control; B's writes are refused and the plan stays A's; B asks, the vehicle
    forwards it to A, A allows, B gets control inside the 10 s window; now A is refused."""
    f = fleet()
    a, b = f.sessions["A"], f.sessions["B"]
    v = f.vehicle
    got = a.request_control()
    assert (got.operation, got.outcome) == (Op.REQUEST, O.GRANTED) and v.owner == A
    a_plan = plan(4)
    assert a.upload(MissionType.MISSION, a_plan).ok
    stored = v.store.items(MissionType.MISSION)

    refused = b.upload(MissionType.MISSION, plan(2, north=50.0))
    assert not refused.ok and refused.nack == MissionResult.DENIED
    assert b.clear(MissionType.MISSION).nack == MissionResult.DENIED
    assert start_mission(f, "B") == d.MAV_RESULT_NOT_IN_CONTROL
    assert not b.set_current(2).ok                      # refused with STATUSTEXT
    assert v.store.items(MissionType.MISSION) == stored and not v.flight.flying
    assert b.download(MissionType.MISSION).items == tuple(stored)   # reads stay open

    took = b.request_control(timeout=10)
    assert took.outcome is O.GRANTED and v.owner == B
    assert took.finished - took.started < 10.0
    asked = [e for e in f.gcs("A").control_events if isinstance(e, TakeoverRequested)]
    assert [e.requester for e in asked] == [B]
    assert [r.operation for r in f.gcs("A").control_results] == [Op.REQUEST, Op.ANSWER_ALLOW]

    assert a.upload(MissionType.MISSION, plan(2)).nack == MissionResult.DENIED
    assert start_mission(f, "A") == d.MAV_RESULT_NOT_IN_CONTROL
    assert b.upload(MissionType.MISSION, plan(3)).ok
    assert start_mission(f, "B") == d.MAV_RESULT_ACCEPTED
    changes = [e for e in v.control_events if isinstance(e, ControlChanged)]
    assert [c.owner for c in changes][:1] == [A] and changes[-1].owner == B
    assert any("gcs_main 202 (was 201)" in e for e in v.events)


def test_an_owner_that_refuses_keeps_control_and_the_request_times_out():
    f = fleet(a_policy=always(Decision.REFUSE))
    a, b = f.sessions["A"], f.sessions["B"]
    assert a.request_control().ok
    r = b.request_control(timeout=3)
    assert r.outcome is O.REFUSED and f.vehicle.owner == A
    assert r.finished - r.started < 3.0 + 2 * ClientConfig().ack_timeout


def test_the_operator_answers_a_forwarded_request_later():
    """A policy that returns None leaves the answer to the operator (`answer_takeover`)."""
    f = fleet(a_policy=always(None))
    a, b = f.gcs("A"), f.gcs("B")
    assert f.sessions["A"].request_control().ok
    b.request_control(f.net.clock.now(), timeout=20)
    asked = lambda: [e for e in a.control_events if isinstance(e, TakeoverRequested)]   # noqa: E731
    assert f.net.run_until(lambda: bool(asked()), timeout=2.0)
    f.net.run_for(5.0)                                     # the operator thinks it over
    assert f.vehicle.owner == A and not b.control_results
    a.answer_takeover(Decision.RELEASE, f.net.clock.now())
    assert f.net.run_until(lambda: bool(b.control_results), timeout=3.0)
    assert b.control_results[-1].outcome is O.GRANTED and f.vehicle.owner == B
    assert [r.operation for r in a.control_results] == [Op.REQUEST, Op.ANSWER_RELEASE]


def test_release_and_takeover_flag_from_the_session():
    f = fleet(a_policy=always(None))
    a, b = f.sessions["A"], f.sessions["B"]
    not_yet = a.allow_takeover(True)
    assert not_yet.outcome is O.NOT_IN_CONTROL and "nothing sent" in not_yet.detail
    assert a.request_control().ok
    assert a.allow_takeover(True).outcome is O.GRANTED and f.vehicle.control.takeover_allowed
    assert b.request_control().outcome is O.GRANTED        # no permission needed now
    assert f.vehicle.owner == B
    assert b.allow_takeover(False).ok and not f.vehicle.control.takeover_allowed
    assert a.release_control().outcome is O.NOT_IN_CONTROL
    assert b.release_control().outcome is O.RELEASED and f.vehicle.owner == 0


def test_heartbeats_keep_the_owner_and_silence_loses_it():
    """The owner's 1 Hz HEARTBEATs alone keep it in control; silent, it is lost: "If all
    owning GCS are disconnected the vehicle should GCS loss failsafe, and broadcast a
    CONTROL_STATUS indicating that it has no owner(s)." The vehicle also says so in a
    STATUSTEXT."""
    f = fleet()
    a = f.sessions["A"]
    assert a.request_control().ok
    decoder, sent_by_a = FrameDecoder(), []
    f.net.add_capture(lambda r: sent_by_a.extend(x.msg._type for x in decoder.feed(r.data))
                      if (r.src, r.kind) == ("A", "tx") else None)
    f.net.run_for(60.0)                                   # no traffic but HEARTBEATs
    assert f.vehicle.owner == A and not any(isinstance(e, OwnerLost) for e in f.vehicle.control_events)
    assert set(sent_by_a) == {"HEARTBEAT"} and 59 <= len(sent_by_a) <= 61

    b = f.gcs("B")
    b.received.clear()
    f.silence("A")
    lost_at = f.net.clock.now()
    assert f.net.run_until(lambda: f.vehicle.owner == 0, timeout=LOSS + 2.0)
    (lost,) = [e for e in f.vehicle.control_events if isinstance(e, OwnerLost)]
    assert lost.sysid == A and lost_at + LOSS - 1.0 <= lost.at <= lost_at + LOSS + 1.0
    f.net.run_for(0.1)
    texts = [m for m in b.received if m._type == "STATUSTEXT"]
    assert [(t.severity, t.text) for t in texts] == [(d.MAV_SEVERITY_CRITICAL, f"GCS {A} lost: no GCS in control")]
    assert statuses(b)[-1].gcs_main == 0 and b.control.owner == 0
    assert any(e.startswith(f"control: GCS {A} lost") for e in f.vehicle.events)
    assert f.sessions["B"].request_control().ok            # free for the next GCS


def test_control_status_streams_at_1_hz_with_the_system_manager_flag():
    f = fleet()
    b = f.gcs("B")
    b.received.clear()
    f.net.run_for(10.0)
    got = statuses(b)
    assert 9 <= len(got) <= 11
    assert all(s.flags & d.GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER and s.gcs_main == 0 for s in got)
    assert f.sessions["A"].request_control().ok
    f.net.run_for(0.1)
    assert statuses(b)[-1].gcs_main == A                  # at once on a change, not a second later


def test_the_vehicles_own_components_are_never_filtered():
    """"... (or from other components in its own system/with the same system id, such as a
    companion computer)": a companion computer (system 1) uploads while A owns control."""
    f = fleet()
    assert f.sessions["A"].request_control().ok
    node = GcsNode(GcsConfig(system=1, component=d.MAV_COMP_ID_ONBOARD_COMPUTER), remote="vehicle",
                   wall_clock=f.net.clock.wall)
    f.net.add_node("companion", node)
    f.net.connect("companion", "vehicle")
    s = GcsSession(f.net, node)
    s.wait_for_target(3.0)
    assert s.upload(MissionType.MISSION, plan(2)).ok
