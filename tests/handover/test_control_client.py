"""Scripted virtual-time cases for the GCS's operator-control client, one rule each.

Each docstring quotes the sentence of MAVLink development.xml the rule comes from. The vehicle
is played by hand: its messages go through the real codec with explicit `now` values.
"""

from __future__ import annotations

from typing import Any

import pytest

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig, ControlClient, always
from mavconform.reference_impl.handover.control_results import (
    ControlOperation as Op, ControlOutcome as O, Decision, StatusChanged, TakeoverRequested)
from mavconform.reference_impl.handover.control_transitions import CLIENT_TRANSITIONS, ClientState
from mavconform.reference_impl.mission.actions import Finished, Send
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

VEHICLE = (1, 1)
MANAGER_COMP = (1, 191)   # a system manager that is not the autopilot
ME, OTHER = 201, 202
_decoder = FrameDecoder()
MANAGER = d.GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER
TAKEOVER = d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED


def frame(msg: Any, src=VEHICLE):
    (f,) = _decoder.feed(FrameEncoder(*src).encode(msg))
    return f


class Gcs:
    def __init__(self, policy=always(None), **config: Any) -> None:
        self.c = ControlClient(ME, 190, VEHICLE, ClientConfig(**config), policy=policy)
        self.now = 0.0
        self.results: list = []

    def take(self, actions: list) -> list:
        self.results += [a.result for a in actions if isinstance(a, Finished)]
        return actions

    def feed(self, msg: Any, src=VEHICLE) -> list:
        return self.take(self.c.handle(frame(msg, src), self.now))

    def status(self, owner: int, takeover: bool = False, src=VEHICLE) -> list:
        return self.feed(cm.control_status(owner, takeover_allowed=takeover), src)

    def ack(self, result: int, src=VEHICLE) -> list:
        return self.feed(cm.command_ack(d.MAV_CMD_REQUEST_OPERATOR_CONTROL, result, (ME, 190)), src)

    def advance(self, dt: float) -> list:
        end, out = self.now + dt, []
        for _ in range(10_000):
            nd = self.c.next_deadline()
            if nd is None or nd > end:
                break
            self.now = max(self.now, nd)
            out += self.take(self.c.poll(self.now))
        self.now = end
        return out


def commands(actions: list) -> list:
    return [a.msg for a in actions if isinstance(a, Send) and a.msg._type == "COMMAND_LONG"]


def owning_gcs(**kw: Any) -> Gcs:
    g = Gcs(**kw)
    g.c.request_control(g.now)
    g.ack(d.MAV_RESULT_ACCEPTED)
    g.status(ME)
    g.results.clear()
    return g


def test_request_goes_to_the_system_manager_component_and_is_granted():
    """"A GCS that wants to control the system should also monitor for the same message and
    flag, and address the MAV_CMD_REQUEST_OPERATOR_CONTROL to its component id." Granted with
    "MAV_RESULT_ACCEPTED"."""
    g = Gcs()
    assert g.status(0, src=MANAGER_COMP) == []          # first status: nothing changed yet
    (cmd,) = commands(g.c.request_control(g.now, allow_takeover=True, timeout=15))
    assert (cmd.target_system, cmd.target_component, cmd.command) == (*MANAGER_COMP, d.MAV_CMD_REQUEST_OPERATOR_CONTROL)
    assert (cmd.param1, cmd.param2, cmd.param3, cmd.param4, cmd.confirmation) == (1.0, 1.0, 15.0, float(ME), 0)
    g.ack(d.MAV_RESULT_ACCEPTED, src=MANAGER_COMP)
    (r,) = g.results
    assert (r.operation, r.outcome, r.ok) == (Op.REQUEST, O.GRANTED, True)
    assert g.c.in_control and g.c.state is ClientState.IDLE and g.c.next_deadline() is None


def test_no_ack_means_bounded_resends_with_rising_confirmation_then_timeout():
    """COMMAND_LONG `confirmation`: "0: First transmission of this command. 1-255: Confirmation
    transmissions"; every wait has a deadline."""
    g = Gcs(ack_timeout=1.0, max_retries=3)
    g.c.request_control(g.now)
    out = g.advance(60.0)
    assert [c.confirmation for c in commands(out)] == [1, 2, 3]
    (r,) = g.results
    assert r.outcome is O.TIMEOUT and r.retries == 3 and r.finished == pytest.approx(4.0)


def test_a_refusal_without_waiting_is_refused():
    """"the request should be rejected with MAV_RESULT_FAILED\""""
    g = Gcs()
    g.c.request_control(g.now, wait=False)
    g.ack(d.MAV_RESULT_FAILED)
    assert [(r.outcome, r.result) for r in g.results] == [(O.REFUSED, d.MAV_RESULT_FAILED)]


def test_a_refused_request_waits_for_takeover_then_asks_again_and_is_granted():
    """The owner "may choose to release control of the vehicle, or re-request control with the
    takeover bit set to allow permission"; "the requester GCS will only have 10 seconds to get
    control" - so the requester asks again as soon as CONTROL_STATUS shows it may."""
    g = Gcs()
    g.status(OTHER)
    g.c.request_control(g.now, timeout=10)
    g.ack(d.MAV_RESULT_FAILED)
    assert g.c.state is ClientState.WAITING_FOR_OWNER and g.results == []
    g.advance(3.0)
    assert g.status(OTHER) == [] and g.c.state is ClientState.WAITING_FOR_OWNER
    out = g.status(OTHER, takeover=True)
    (again,) = commands(out)
    assert again.param1 == 1.0 and again.confirmation == 0
    g.ack(d.MAV_RESULT_ACCEPTED)
    assert [r.outcome for r in g.results] == [O.GRANTED]


def test_a_release_by_the_owner_lets_the_waiting_requester_in():
    """CONTROL_STATUS gcs_main "0: no GCS in control": an uncontrolled system grants."""
    g = Gcs()
    g.status(OTHER)
    g.c.request_control(g.now)
    g.ack(d.MAV_RESULT_FAILED)
    assert len(commands(g.status(0))) == 1


def test_a_refused_request_stops_waiting_after_its_timeout():
    """Param 3: "Timeout in seconds before a request to a GCS to allow takeover is assumed to be
    rejected.\""""
    g = Gcs(ack_timeout=1.0)
    g.status(OTHER)
    g.c.request_control(g.now, timeout=5)
    g.ack(d.MAV_RESULT_FAILED)
    g.advance(5.9)
    assert g.results == []
    g.advance(0.2)
    (r,) = g.results
    assert r.outcome is O.REFUSED and g.c.next_deadline() is None


def test_not_in_control_and_other_results_are_typed():
    """MAV_RESULT_NOT_IN_CONTROL: "Command has been rejected because source system is not in
    control of the target system/component.\""""
    g = Gcs()
    g.c.release_control(g.now)
    g.ack(d.MAV_RESULT_NOT_IN_CONTROL)
    g.c.request_control(g.now)
    g.ack(d.MAV_RESULT_DENIED)
    assert [(r.operation, r.outcome) for r in g.results] == [(Op.RELEASE, O.NOT_IN_CONTROL),
                                                             (Op.REQUEST, O.REJECTED)]


def test_release_and_takeover_flag_for_the_owner():
    """Param 1 "0: Release control"; param 2 "1: Allow automatic takeover"."""
    g = owning_gcs()
    (cmd,) = commands(g.c.set_takeover(True, g.now))
    assert (cmd.param1, cmd.param2) == (1.0, 1.0)
    g.ack(d.MAV_RESULT_ACCEPTED)
    (cmd,) = commands(g.c.release_control(g.now))
    assert cmd.param1 == 0.0
    g.ack(d.MAV_RESULT_ACCEPTED)
    assert [(r.operation, r.outcome) for r in g.results] == [(Op.ALLOW_TAKEOVER, O.GRANTED),
                                                             (Op.RELEASE, O.RELEASED)]
    assert not g.c.in_control


def test_usage_errors_are_local_protocol_errors():
    g = Gcs()
    with pytest.raises(LocalProtocolError):
        g.c.set_takeover(True, g.now)           # not in control: that would be a request
    with pytest.raises(LocalProtocolError):
        g.c.request_control(g.now, timeout=2)   # param 3 minValue is 3
    g.c.request_control(g.now)
    with pytest.raises(LocalProtocolError):
        g.c.release_control(g.now)              # one user operation at a time


def forwarded(requester: int = OTHER, allow: bool = False, timeout: float = 10.0):
    return cm.request_command((ME, 190), cm.ACTION_REQUEST, allow, timeout, requester)


def test_a_forwarded_request_is_acked_reported_and_refused_by_default():
    """"That owning GCS must ACK with MAV_RESULT_ACCEPTED, and may choose to release control of
    the vehicle, or re-request control" - or neither: the request then times out."""
    g = owning_gcs()
    out = g.feed(forwarded())
    assert [(a.msg._type, a.msg.result, a.to) for a in out if isinstance(a, Send)] == [
        ("COMMAND_ACK", d.MAV_RESULT_ACCEPTED, VEHICLE)]
    (req,) = [a for a in out if isinstance(a, TakeoverRequested)]
    assert (req.requester, req.timeout) == (OTHER, 10.0)
    assert commands(out) == [] and g.c.in_control


def test_allowing_a_forwarded_request_re_requests_with_takeover_then_reverts_after_ten_seconds():
    """"In case it choses to re-request control with takeover bit set to allow permission, the
    requester GCS will only have 10 seconds to get control, otherwise owning GCS will re-request
    control with takeover bit set to disallow permission\""""
    g = owning_gcs(policy=always(Decision.ALLOW))
    (allow,) = commands(g.feed(forwarded()))
    assert (allow.param1, allow.param2) == (1.0, 1.0)
    g.ack(d.MAV_RESULT_ACCEPTED)
    assert g.c.next_deadline() == pytest.approx(cm.TAKEOVER_WINDOW)
    assert commands(g.advance(cm.TAKEOVER_WINDOW - 0.01)) == []
    (revert,) = commands(g.advance(0.02))
    assert (revert.param1, revert.param2) == (1.0, 0.0)
    g.ack(d.MAV_RESULT_ACCEPTED)
    assert [r.operation for r in g.results] == [Op.ANSWER_ALLOW, Op.CLOSE_WINDOW]


def test_no_revert_once_the_requester_took_control():
    """The revert is the owner's: a GCS no longer in control has nothing to re-request."""
    g = owning_gcs(policy=always(Decision.ALLOW))
    g.feed(forwarded())
    g.ack(d.MAV_RESULT_ACCEPTED)
    out = g.status(OTHER)
    assert [a for a in out if isinstance(a, StatusChanged)] == [StatusChanged(OTHER, ME, False)]
    assert g.c.next_deadline() is None and commands(g.advance(30)) == []


def test_releasing_in_answer_and_answering_later():
    """The owner "may choose to release control of the vehicle"."""
    g = owning_gcs(policy=always(Decision.RELEASE))
    (cmd,) = commands(g.feed(forwarded()))
    assert cmd.param1 == 0.0
    g = owning_gcs()                                # the operator decides later
    g.feed(forwarded(timeout=5))
    g.advance(2.0)
    (cmd,) = commands(g.c.answer(Decision.ALLOW, g.now))
    assert cmd.param2 == 1.0
    assert g.c.answer(Decision.ALLOW, g.now) == []  # answered once


def test_a_resent_notification_is_acked_but_answered_once():
    """The vehicle resends the notification until the owner's ACK; the answer is given once."""
    calls = []
    g = owning_gcs(policy=lambda r: calls.append(r) or Decision.ALLOW)
    g.feed(forwarded())
    out = g.feed(forwarded())
    assert len(calls) == 1 and commands(out) == []
    assert [a.msg._type for a in out if isinstance(a, Send)] == ["COMMAND_ACK"]


def test_an_answer_waits_behind_the_command_in_flight():
    """One command in flight: an answer to a forwarded request is queued, not interleaved."""
    g = owning_gcs(policy=always(Decision.ALLOW))
    g.c.set_takeover(False, g.now)
    assert commands(g.feed(forwarded())) == []
    (nxt,) = commands(g.ack(d.MAV_RESULT_ACCEPTED))
    assert nxt.param2 == 1.0


def test_the_client_moves_only_through_its_table():
    g = owning_gcs(policy=always(Decision.ALLOW))
    g.feed(forwarded())
    g.advance(40)
    assert all(CLIENT_TRANSITIONS[(a, e)] is b for a, e, b in g.c.history)
    reached = {b for b in CLIENT_TRANSITIONS.values()} | {a for a, _ in CLIENT_TRANSITIONS}
    assert reached == set(ClientState)
