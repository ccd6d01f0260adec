"""The system manager's withdraw hook and the GCS handover agent's policy, alone (sans-IO),
on the line geometry of test_mission_computer.py."""

from __future__ import annotations

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig
from mavconform.reference_impl.handover.control_manager import ControlManager, ManagerConfig
from mavconform.reference_impl.handover.control_results import Decision, TakeoverRequested
from mavconform.reference_impl.handover.control_transitions import ControlState
from mavconform.reference_impl.handover.gcs_handover import GcsHandoverConfig, HandoverAgent
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

from .line_geometry import A, B, C, COVERAGES, VEHICLE, at

_dec = FrameDecoder()


# --- the system manager's hook ----------------------------------------------------------------
def test_withdraw_ends_a_forwarded_request_or_a_window_and_nothing_else():
    enc = {s: FrameEncoder(s, 190) for s in (A, B)}

    def f(sender, msg):
        (fr,) = FrameDecoder().feed(enc[sender].encode(msg))
        return fr
    m = ControlManager(*VEHICLE, ManagerConfig())
    m.handle(f(A, cm.request_command(VEHICLE, 1, False, 10, A)), 0.0)
    m.handle(f(B, cm.request_command(VEHICLE, 1, False, 10, B)), 0.1)
    assert m.state is ControlState.REQUEST_PENDING
    assert m.withdraw(C, 0.2) == [] and m.state is ControlState.REQUEST_PENDING
    m.withdraw(B, 0.2)
    assert m.state is ControlState.OWNED and m.owner == A
    m.handle(f(B, cm.request_command(VEHICLE, 1, False, 10, B)), 0.3)
    m.handle(f(A, cm.request_command(VEHICLE, 1, True, 10, A)), 0.4)
    assert m.state is ControlState.WINDOW_OPEN
    out = m.withdraw(B, 0.5)
    assert m.state is ControlState.OWNED and m.owner == A
    (status,) = [a.msg for a in out if isinstance(a, Send)]
    assert status.gcs_main == A and not status.flags & d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED


# --- the GCS agent's policy -------------------------------------------------------------------
def test_the_commander_allows_a_known_partner_only_when_its_telemetry_says_the_handover_is_due():
    agent = HandoverAgent(A, GcsHandoverConfig(COVERAGES["polygon"], slack_m=50.0), fallback=lambda r: Decision.RELEASE)
    req = TakeoverRequested(B, False, 10.0, 10.0)
    assert agent.policy(req) is Decision.REFUSE and "no recent" in agent.decisions[-1][2]
    agent.position = (at(500), 9.5)
    assert agent.policy(req) is Decision.REFUSE                     # 300 m short of the region
    agent.position = (at(780), 2.0)
    assert agent.policy(req) is Decision.REFUSE                     # inside the slack, but 8 s old
    agent.position = (at(780), 9.5)
    assert agent.policy(req) is Decision.ALLOW and agent.authorised_for == B
    # param2 1: B's own allow-takeover, resent after it lost control to A: never a handover
    assert agent.policy(TakeoverRequested(B, True, 10.0, 10.0)) is Decision.REFUSE
    assert agent.policy(TakeoverRequested(C, False, 10.0, 10.0)) is Decision.RELEASE   # not a partner: fallback


def test_the_commander_under_the_waypoint_method_follows_mission_current():
    agent = HandoverAgent(A, GcsHandoverConfig(COVERAGES["waypoints"]))
    req = TakeoverRequested(B, False, 10.0, 10.0)
    agent.mission_current = (1, 9.0)
    assert agent.policy(req) is Decision.REFUSE
    agent.mission_current = (2, 9.0)                                # flying the leg to B's waypoint
    assert agent.policy(req) is Decision.ALLOW


def test_a_commander_that_lost_and_regained_control_is_asked_again_by_the_same_partner():
    """Regression: the client used to keep a forwarded request for its whole param3 timeout, so
    the same partner asking again after a handover there and back (within 30 s) went unasked,
    and the second handover to it aborted. Losing control ends what there was to answer."""
    from mavconform.reference_impl.handover.control_client import ControlClient
    asked = []
    client = ControlClient(A, 190, VEHICLE, ClientConfig(), policy=lambda r: asked.append(r.at) or Decision.REFUSE)
    vehicle = FrameEncoder(*VEHICLE)

    def hear(msg, now):
        (fr,) = _dec.feed(vehicle.encode(msg))
        return client.handle(fr, now)

    def status(owner):
        return cm.control_status(owner, takeover_allowed=False)
    forward = cm.request_command((A, 190), cm.ACTION_REQUEST, False, 30.0, B)
    hear(status(A), 0.0)
    hear(forward, 1.0)
    hear(forward, 2.0)                       # a resend of the same notice: not asked twice
    assert asked == [1.0]
    hear(status(B), 3.0)                     # B took over ...
    hear(status(A), 6.0)                     # ... and handed back
    hear(forward, 9.0)                       # B asks again, 8 s after the first: a new request
    assert asked == [1.0, 9.0]
