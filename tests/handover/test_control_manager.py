"""Scripted virtual-time cases for the vehicle's operator-control manager, one rule each.

Each docstring quotes the sentence of MAVLink development.xml (MAV_CMD_REQUEST_OPERATOR_CONTROL,
CONTROL_STATUS, GCS_CONTROL_STATUS_FLAGS) the rule comes from. Frames go through the real codec.
"""

from __future__ import annotations

import math
from typing import Any

import pytest

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_manager import ControlManager, ManagerConfig
from mavconform.reference_impl.handover.control_results import ControlChanged, OwnerLost
from mavconform.reference_impl.handover.control_transitions import (
    MANAGER_TRANSITIONS, ControlEvent as E, ControlState as S)
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

VEHICLE = (1, 1)
G1, G2, G3 = (201, 190), (202, 190), (203, 190)
_decoder = FrameDecoder()


def frame(msg: Any, src: tuple[int, int]):
    (f,) = _decoder.feed(FrameEncoder(*src).encode(msg))
    return f


def request(allow: bool = False, timeout: float = 10.0, sysid: int | None = None, src=G1, action=1.0):
    return cm.request_command(VEHICLE, action, allow, timeout, src[0] if sysid is None else sysid)


def release(src=G1):
    return cm.request_command(VEHICLE, cm.ACTION_RELEASE, False, 0, src[0])


def heartbeat():
    return d.MAVLink_heartbeat_message(d.MAV_TYPE_GCS, d.MAV_AUTOPILOT_INVALID, 0, 0, d.MAV_STATE_ACTIVE, 3)


class Vehicle:
    """The manager, fed by hand: `feed` a message from a GCS at `now`, `advance` time."""

    def __init__(self, **config: Any) -> None:
        self.m = ControlManager(*VEHICLE, ManagerConfig(**config), record_history=True)
        self.now = 0.0
        self.m.poll(0.0)   # the first CONTROL_STATUS

    def feed(self, msg: Any, src=G1) -> list:
        return self.m.handle(frame(msg, src), self.now)

    def advance(self, dt: float, heartbeats_from: tuple = ()) -> list:
        """Fire every deadline up to now + dt in order; the given GCSs send a HEARTBEAT a second."""
        end, out, beat = self.now + dt, [], math.floor(self.now) + 1.0
        for _ in range(10_000):
            nd = self.m.next_deadline()
            assert nd is not None, "a deadline must always be defined (CONTROL_STATUS stream)"
            t = min(nd, beat) if heartbeats_from else nd
            if t > end:
                break
            self.now = max(self.now, t)
            if heartbeats_from and t == beat:
                for g in heartbeats_from:
                    out += self.m.handle(frame(heartbeat(), g), self.now)
                beat += 1.0
            out += self.m.poll(self.now)
        self.now = end
        return out


def msgs(actions: list, name: str | None = None) -> list:
    return [a.msg for a in actions if isinstance(a, Send) and (name is None or a.msg._type == name)]


def acks(actions: list) -> list[tuple[int, int]]:
    """(result, target_system) of each COMMAND_ACK."""
    return [(a.result, a.target_system) for a in msgs(actions, "COMMAND_ACK")]


def status(actions: list) -> list[tuple[int, int]]:
    """(gcs_main, flags) of each CONTROL_STATUS."""
    return [(s.gcs_main, s.flags) for s in msgs(actions, "CONTROL_STATUS")]


MANAGER = d.GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER
TAKEOVER = d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED


def owned_by_g1(allow: bool = False, **config: Any) -> Vehicle:
    v = Vehicle(**config)
    assert acks(v.feed(request(allow), G1)) == [(d.MAV_RESULT_ACCEPTED, G1[0])]
    return v


# --- granting ------------------------------------------------------------------------------
def test_an_uncontrolled_system_grants_a_request_with_accepted():
    """"The system manager component should grant control to the requested GCS(s) if the
    system does not require takeover permission (or is uncontrolled) and ACK the request
    with MAV_RESULT_ACCEPTED.\""""
    v = Vehicle()
    out = v.feed(request(), G1)
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G1[0])]
    assert v.m.owner == G1[0] and v.m.state is S.OWNED
    assert status(out) == [(G1[0], MANAGER)]
    assert [type(a) for a in out if not isinstance(a, Send)] == [ControlChanged]


def test_a_request_is_granted_when_the_owner_allows_takeover():
    """GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED: "Takeover allowed (requests for control will
    be granted).\""""
    v = owned_by_g1(allow=True)
    assert v.m.state is S.OWNED_TAKEOVER_ALLOWED and v.m.takeover_allowed
    out = v.feed(request(allow=False, src=G2), G2)
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G2[0])]
    assert v.m.owner == G2[0] and status(out) == [(G2[0], MANAGER)]


def test_the_owner_re_requesting_sets_the_takeover_flag_and_streams_it():
    """Param 2 "Allow takeover": "Enable automatic granting of ownership on request"; CONTROL_STATUS
    "emitted when ownership or takeover status change"."""
    v = owned_by_g1()
    out = v.feed(request(allow=True), G1)
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G1[0])] and status(out) == [(G1[0], MANAGER | TAKEOVER)]
    out = v.feed(request(allow=True), G1)     # no change: no extra CONTROL_STATUS
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G1[0])] and status(out) == []
    out = v.feed(request(allow=False), G1)
    assert status(out) == [(G1[0], MANAGER)] and v.m.state is S.OWNED


# --- refusing and forwarding ---------------------------------------------------------------
def test_a_request_needing_permission_is_refused_and_forwarded_to_the_owner():
    """"If the system manager component cannot grant control because takeover requires
    permission, the request should be rejected with MAV_RESULT_FAILED. The system manager
    component should then send this same command to the owning GCS ... in order to notify of
    the request.\""""
    v = owned_by_g1()
    out = v.feed(request(allow=True, timeout=20, src=G2), G2)
    assert acks(out) == [(d.MAV_RESULT_FAILED, G2[0])]
    (fwd,) = [a for a in out if isinstance(a, Send) and a.msg._type == "COMMAND_LONG"]
    assert fwd.to == G1
    c = fwd.msg
    assert (c.command, c.target_system, c.param1, c.param2, c.param3, c.param4) == (
        d.MAV_CMD_REQUEST_OPERATOR_CONTROL, G1[0], 1.0, 1.0, 20.0, float(G2[0]))
    assert v.m.owner == G1[0] and v.m.state is S.REQUEST_PENDING and v.m.pending_requester == G2[0]
    assert status(out) == []    # nothing about control changed


def test_a_repeated_request_is_refused_again_but_not_forwarded_again():
    """The owner is notified "of the request": a retransmission is the same request."""
    v = owned_by_g1()
    v.feed(request(src=G2), G2)
    out = v.feed(request(src=G2), G2)
    assert acks(out) == [(d.MAV_RESULT_FAILED, G2[0])] and msgs(out, "COMMAND_LONG") == []


def test_the_forward_is_resent_until_the_owner_acks_it_and_no_more():
    """"That owning GCS must ACK with MAV_RESULT_ACCEPTED": until it does, the notification is
    resent, a bounded number of times."""
    v = owned_by_g1(notify_timeout=1.0, notify_retries=2)
    v.feed(request(timeout=30, src=G2), G2)
    out = v.advance(10.0, heartbeats_from=(G1,))
    assert [c.confirmation for c in msgs(out, "COMMAND_LONG")] == [1, 2]
    v = owned_by_g1(notify_timeout=1.0, notify_retries=2)
    v.feed(request(timeout=30, src=G2), G2)
    v.feed(cm.command_ack(d.MAV_CMD_REQUEST_OPERATOR_CONTROL, d.MAV_RESULT_ACCEPTED, VEHICLE), G1)
    assert msgs(v.advance(10.0, heartbeats_from=(G1,)), "COMMAND_LONG") == []


@pytest.mark.parametrize("asked, applied", [(20.0, 20.0), (1.0, cm.TIMEOUT_MIN), (500.0, cm.TIMEOUT_MAX),
                                            (0.0, cm.DEFAULT_REQUEST_TIMEOUT),
                                            (math.nan, cm.DEFAULT_REQUEST_TIMEOUT)])
def test_an_unanswered_request_counts_as_refused_after_its_timeout(asked, applied):
    """Param 3 "Request timeout" (minValue 3, maxValue 60): "Timeout in seconds before a request
    to a GCS to allow takeover is assumed to be rejected." Out of range: clamped to the bounds."""
    v = owned_by_g1()
    out = v.feed(request(timeout=asked, src=G2), G2)
    assert msgs(out, "COMMAND_LONG")[0].param3 == applied
    v.advance(applied - 0.01, heartbeats_from=(G1,))
    assert v.m.state is S.REQUEST_PENDING
    v.advance(0.02, heartbeats_from=(G1,))
    assert v.m.state is S.OWNED and v.m.pending_requester == 0


# --- the owner's answer --------------------------------------------------------------------
def test_the_owner_allowing_takeover_opens_a_window_that_closes_after_ten_seconds():
    """The owner "may choose to ... re-request control with the takeover bit set to allow
    permission. In case it choses to re-request control with takeover bit set to allow
    permission, the requester GCS will only have 10 seconds to get control"."""
    v = owned_by_g1()
    v.feed(request(src=G2), G2)
    v.advance(2.0, heartbeats_from=(G1,))
    out = v.feed(request(allow=True), G1)
    assert v.m.state is S.WINDOW_OPEN and v.m.window_for == G2[0]
    assert status(out) == [(G1[0], MANAGER | TAKEOVER)]
    out = v.advance(cm.TAKEOVER_WINDOW - 0.01, heartbeats_from=(G1,))
    assert v.m.state is S.WINDOW_OPEN
    out = v.advance(0.02, heartbeats_from=(G1,))
    assert v.m.state is S.OWNED and status(out)[-1] == (G1[0], MANAGER)


def test_the_requester_gets_control_inside_the_window():
    """GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED: "If not set requests for control will be rejected,
    but the controlling GCS will be notified (and may release control or allow takeover).\""""
    v = owned_by_g1()
    v.feed(request(src=G2), G2)
    v.feed(request(allow=True), G1)
    out = v.feed(request(src=G2), G2)
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G2[0])] and v.m.owner == G2[0] and v.m.state is S.OWNED
    assert status(out) == [(G2[0], MANAGER)]


def test_the_owner_refusing_explicitly_ends_the_request():
    """Re-requesting with the takeover bit clear is the owner keeping control."""
    v = owned_by_g1()
    v.feed(request(src=G2), G2)
    v.feed(request(allow=False), G1)
    assert v.m.state is S.OWNED and v.m.pending_requester == 0
    assert acks(v.feed(request(src=G2), G2)) == [(d.MAV_RESULT_FAILED, G2[0])]


def test_release_frees_control_and_broadcasts_no_owner():
    """Param 1 "0: Release control"; CONTROL_STATUS gcs_main "0: no GCS in control"."""
    v = owned_by_g1()
    v.feed(request(src=G2), G2)
    out = v.feed(release(G1), G1)
    assert acks(out) == [(d.MAV_RESULT_ACCEPTED, G1[0])] and status(out) == [(0, MANAGER)]
    assert v.m.state is S.UNOWNED and v.m.pending_requester == 0
    assert acks(v.feed(request(src=G2), G2)) == [(d.MAV_RESULT_ACCEPTED, G2[0])]


def test_release_by_a_gcs_not_in_control_is_not_in_control():
    """"Commands to control the vehicle from other systems should be rejected with
    MAV_RESULT_NOT_IN_CONTROL (except for this command, which may be acknowledged with
    MAV_RESULT_ACCEPTED if control is granted)": a release grants nothing."""
    v = owned_by_g1()
    assert acks(v.feed(release(G2), G2)) == [(d.MAV_RESULT_NOT_IN_CONTROL, G2[0])]
    assert v.m.owner == G1[0]
    assert acks(Vehicle().feed(release(G2), G2)) == [(d.MAV_RESULT_NOT_IN_CONTROL, G2[0])]


@pytest.mark.parametrize("params", [dict(action=2.0), dict(action=math.nan), dict(sysid=99),
                                    dict(allow=None)])
def test_invalid_params_are_denied(params):
    """Param 1 "0: Release control, 1: Request control"; param 4 "System ID of GCS requesting
    control" and "the sender of the command must have a system id that is in the requested
    range". MAV_RESULT_DENIED: the command is supported but its params are invalid."""
    v = Vehicle()
    msg = request(**{k: v for k, v in params.items() if k != "allow"}, src=G2)
    if "allow" in params:
        msg.param2 = 0.5
    assert acks(v.feed(msg, G2)) == [(d.MAV_RESULT_DENIED, G2[0])]
    assert v.m.state is S.UNOWNED


def test_a_request_addressed_to_another_system_is_ignored():
    v = Vehicle()
    msg = cm.request_command((7, 1), cm.ACTION_REQUEST, False, 10, G1[0])
    assert v.feed(msg, G1) == [] and v.m.state is S.UNOWNED


# --- CONTROL_STATUS stream and owner loss --------------------------------------------------
def test_control_status_is_streamed_at_one_hertz_with_the_system_manager_flag():
    """CONTROL_STATUS "should be broadcast at low rate (nominally 1 Hz)"; the system manager
    "streams the CONTROL_STATUS message and sets the GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER flag"."""
    v = owned_by_g1()
    out = v.advance(4.5, heartbeats_from=(G1,))
    assert status(out) == [(G1[0], MANAGER)] * 4
    assert all(a.to is None for a in out if isinstance(a, Send) and a.msg._type == "CONTROL_STATUS")
    assert list(msgs(out, "CONTROL_STATUS")[0].gcs_secondary) == [0] * 10   # single-owner mode


def test_a_silent_owner_is_lost_reported_and_control_freed():
    """"If all owning GCS are disconnected the vehicle should GCS loss failsafe, and broadcast
    a CONTROL_STATUS indicating that it has no owner(s).\""""
    v = owned_by_g1(owner_loss_timeout=3.0)
    out = v.advance(20.0, heartbeats_from=(G1,))
    assert v.m.owner == G1[0] and not [a for a in out if isinstance(a, OwnerLost)]
    out = v.advance(5.0)
    (lost,) = [a for a in out if isinstance(a, OwnerLost)]
    assert lost.sysid == G1[0] and lost.at - lost.last_heard == pytest.approx(3.0)
    assert v.m.state is S.UNOWNED and (0, MANAGER) in status(out)


def test_while_the_owner_is_connected_the_system_stays_owned():
    """"While any owning GCS are connected the system should consider itself connected to a
    GCS, and still owned".\""""
    v = owned_by_g1(owner_loss_timeout=3.0)
    v.advance(60.0, heartbeats_from=(G1, G2))
    assert v.m.owner == G1[0] and v.m.stats.owners_lost == 0


# --- the filter ----------------------------------------------------------------------------
def command(cmd: int, target=VEHICLE):
    return d.MAVLink_command_long_message(target[0], target[1], cmd, 0, 0, 0, 0, 0, 0, 0, 0)


def test_commands_from_a_gcs_not_in_control_get_not_in_control():
    """"Commands to control the vehicle from other systems should be rejected with
    MAV_RESULT_NOT_IN_CONTROL"."""
    v = owned_by_g1()
    refusal = v.m.screen(frame(command(d.MAV_CMD_MISSION_START), G2))
    (send,) = refusal.actions
    assert send.to == G2 and (send.msg.command, send.msg.result) == (d.MAV_CMD_MISSION_START, d.MAV_RESULT_NOT_IN_CONTROL)
    assert v.m.screen(frame(command(d.MAV_CMD_MISSION_START), G1)) is None
    assert v.m.may_command(G1[0]) and not v.m.may_command(G2[0])


def test_mission_writes_from_a_gcs_not_in_control_are_denied_and_reads_pass():
    """"A controlled system should only accept MAVLink operations that change the state of the
    vehicle ... which are sent by its controlling GCS(s)"; "Messages and commands that don't
    control or change vehicle movement or functionality ... may still be send"."""
    v = owned_by_g1()
    write = d.MAVLink_mission_count_message(*VEHICLE, 3, d.MAV_MISSION_TYPE_FENCE, 0)
    (send,) = v.m.screen(frame(write, G2)).actions
    assert (send.msg._type, send.msg.type, send.msg.mission_type) == ("MISSION_ACK", d.MAV_MISSION_DENIED,
                                                                       d.MAV_MISSION_TYPE_FENCE)
    clear = d.MAVLink_mission_clear_all_message(*VEHICLE, d.MAV_MISSION_TYPE_ALL)
    assert v.m.screen(frame(clear, G2)).actions[0].msg.type == d.MAV_MISSION_DENIED
    assert v.m.screen(frame(d.MAVLink_mission_set_current_message(*VEHICLE, 2), G2)).actions[0].msg._type == "STATUSTEXT"
    read = d.MAVLink_mission_request_list_message(*VEHICLE, d.MAV_MISSION_TYPE_MISSION)
    assert v.m.screen(frame(read, G2)) is None
    assert v.m.screen(frame(write, G1)) is None


def test_the_request_itself_telemetry_requests_and_own_components_pass_the_filter():
    """"(except for this command ...)"; "such as telemetry requests"; "(or from other
    components in its own system/with the same system id, such as a companion computer)"."""
    v = owned_by_g1()
    assert v.m.screen(frame(request(src=G2), G2)) is None
    assert v.m.screen(frame(command(512), G2)) is None          # MAV_CMD_REQUEST_MESSAGE
    assert v.m.screen(frame(command(d.MAV_CMD_MISSION_START), (1, 191))) is None
    assert v.m.screen(frame(command(d.MAV_CMD_MISSION_START, target=(9, 1)), G2)) is None   # not ours


def test_unowned_the_filter_refuses_everyone_unless_configured_open():
    """Design choice (the XML binds only "a controlled system"): with no owner no GCS has
    authority, until `open_when_unowned`."""
    v = Vehicle()
    assert v.m.screen(frame(command(d.MAV_CMD_MISSION_START), G2)) is not None
    assert Vehicle(open_when_unowned=True).m.screen(frame(command(d.MAV_CMD_MISSION_START), G2)) is None


# --- the table -----------------------------------------------------------------------------
def test_every_state_is_reachable_and_every_event_used():
    reach, frontier = {S.UNOWNED}, [S.UNOWNED]
    while frontier:
        s = frontier.pop()
        for (a, _), b in MANAGER_TRANSITIONS.items():
            if a is s and b not in reach:
                reach.add(b)
                frontier.append(b)
    assert reach == set(S)
    assert {e for _, e in MANAGER_TRANSITIONS} == set(E)


def test_the_engine_moves_only_through_the_table():
    v = owned_by_g1(owner_loss_timeout=3.0)
    v.feed(request(src=G2), G2)
    v.feed(request(allow=True), G1)
    v.advance(30.0)
    assert v.m.stats.history and all(MANAGER_TRANSITIONS[(a, e)] is b for a, e, b in v.m.stats.history)
    with pytest.raises(LocalProtocolError):
        v.m._move(E.WINDOW_CLOSED)      # UNOWNED has no WINDOW_CLOSED
