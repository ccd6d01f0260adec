"""Operator control end to end: the vehicle's manager and GCS clients, moved by a small loop.

A scripted two-GCS handover (request refused and forwarded, owner allows, requester takes
over inside the 10 s window), and a Hypothesis state machine: three GCSs request, release,
allow takeover and fall silent while messages are delivered in any order or lost. However it
goes, there are never two owners, a GCS not in control never gets a command past the filter,
control only moves as the XML lets it, and every wait ends.
"""

from __future__ import annotations

from typing import Any

from hypothesis import settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, precondition, rule

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig, ControlClient, always
from mavconform.reference_impl.handover.control_manager import ControlManager, ManagerConfig
from mavconform.reference_impl.handover.control_results import (
    ControlOperation as Op, ControlOutcome as O, Decision, OwnerLost, TakeoverRequested)
from mavconform.reference_impl.handover.control_transitions import (
    GRANTING_STATES, MANAGER_TRANSITIONS, ControlState as S)
from mavconform.reference_impl.mission.actions import Finished, Send
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

VEHICLE = (1, 1)
GCS_IDS = (201, 202, 203)


class Rig:
    """One manager, several clients; every message crosses the real codec. `post` queues what
    an engine returned; `deliver(i)` hands in-flight message i to its receiver (any order)."""

    def __init__(self, policies: dict[int, Any], *, loss_timeout: float = 5.0) -> None:
        self.now = 0.0
        self.manager = ControlManager(*VEHICLE, ManagerConfig(owner_loss_timeout=loss_timeout),
                                      record_history=True)
        self.clients = {g: ControlClient(g, 190, VEHICLE, ClientConfig(), policy=policies[g]) for g in policies}
        self.alive = set(policies)
        self.in_flight: list[tuple[int, Any]] = []   # (receiver sysid, frame)
        self.results: dict[int, list] = {g: [] for g in policies}
        self.events: list[Any] = []
        self._encoders = {g: FrameEncoder(g, 190) for g in policies} | {VEHICLE[0]: FrameEncoder(*VEHICLE)}
        self._decoder = FrameDecoder()
        self._next_beat = 0.0
        self.post(VEHICLE[0], self.manager.poll(0.0))

    def frame(self, sender: int, msg: Any):
        (f,) = self._decoder.feed(self._encoders[sender].encode(msg))
        return f

    def post(self, sender: int, actions: list) -> None:
        for a in actions:
            if isinstance(a, Send):
                f = self.frame(sender, a.msg)
                if sender != VEHICLE[0]:
                    self.in_flight.append((VEHICLE[0], f))
                else:
                    for g in ([a.to[0]] if a.to else self.clients):
                        self.in_flight.append((g, f))
            elif isinstance(a, Finished):
                self.results[sender].append(a.result)
            else:
                self.events.append(a)

    def to_manager(self, f) -> list:
        """Hand a frame to the manager, checking that control moves only as the XML lets it."""
        m = self.manager
        before, state_before = m.owner, m.state
        out = self.checked(m.handle(f, self.now))
        msg, src = f.msg, f.src_system
        for ack in (a.msg for a in out if isinstance(a, Send) and a.msg._type == "COMMAND_ACK"):
            if ack.result == d.MAV_RESULT_ACCEPTED and cm.is_request_control(msg) and ack.target_system == src:
                # ACCEPTED to a request means the sender now owns control; to a release, no one does
                assert m.owner == (src if msg.param1 == 1 else 0), (ack, m.owner)
        if m.owner != before:
            assert cm.is_request_control(msg), "control changed hands on something other than a request"
            assert m.owner in (0, src), f"GCS {src}'s message gave control to GCS {m.owner}"
            assert m.owner == src or before == src, "a GCS released control it did not hold"
            if m.owner == src:
                # "grant control ... if the system does not require takeover permission (or is uncontrolled)"
                assert state_before in GRANTING_STATES, f"GCS {src} took control from GCS {before} in {state_before}"
        return out

    def checked(self, out: list) -> list:
        """Every CONTROL_STATUS the manager sends says what it holds right now."""
        m = self.manager
        for s in (a.msg for a in out if isinstance(a, Send) and a.msg._type == "CONTROL_STATUS"):
            assert (s.gcs_main, bool(s.flags & d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED)) == (
                m.owner, m.takeover_allowed), s
            assert s.flags & d.GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER
        return out

    def deliver(self, i: int) -> None:
        """Deliver in-flight message i; a GCS fallen silent has lost its link both ways."""
        to, f = self.in_flight.pop(i % len(self.in_flight))
        if (f.src_system if to == VEHICLE[0] else to) not in self.alive:
            return
        if to == VEHICLE[0]:
            self.post(VEHICLE[0], self.to_manager(f))
        else:
            self.post(to, self.clients[to].handle(f, self.now))

    def tick(self, dt: float) -> None:
        """Advance time by dt: heartbeats of the GCSs alive, every engine's deadlines in order."""
        end = self.now + dt
        for _ in range(100_000):
            ds = [self.manager.next_deadline(), self._next_beat,
                  *(c.next_deadline() for c in self.clients.values())]
            t = min(x for x in ds if x is not None)
            if t > end:
                break
            self.now = max(self.now, t)
            if self.now >= self._next_beat:
                self._next_beat = self.now + 1.0
                for g in sorted(self.alive):
                    hb = d.MAVLink_heartbeat_message(d.MAV_TYPE_GCS, d.MAV_AUTOPILOT_INVALID, 0, 0,
                                                     d.MAV_STATE_ACTIVE, 3)
                    self.post(VEHICLE[0], self.manager.handle(self.frame(g, hb), self.now))
            before = self.manager.owner
            self.post(VEHICLE[0], self.checked(self.manager.poll(self.now)))
            assert self.manager.owner in (before, 0), "a timer gave control to a GCS"
            for g, c in self.clients.items():
                self.post(g, c.poll(self.now))
        self.now = end

    def run(self, dt: float, latency: float = 0.05) -> None:
        """Deliver in order with a fixed latency, for dt seconds (the scripted exchange)."""
        end = self.now + dt
        while self.now < end:
            while self.in_flight:
                self.deliver(0)
            self.tick(min(latency, end - self.now))


# --- a scripted handover between two GCSs --------------------------------------------------
def test_two_gcs_handover_through_both_engines():
    """The XML's flow, end to end: A owns; B's request is "rejected with MAV_RESULT_FAILED" and
    sent "to the owning GCS ... in order to notify of the request"; A ACKs and re-requests
    "with the takeover bit set to allow permission"; B, waiting, asks again and gets control
    within "10 seconds"; A's window revert finds it no longer in control and does nothing."""
    A, B = 201, 202
    rig = Rig({A: always(Decision.ALLOW), B: always(Decision.REFUSE)})
    rig.post(A, rig.clients[A].request_control(rig.now))
    rig.run(1.0)
    assert [r.outcome for r in rig.results[A]] == [O.GRANTED] and rig.manager.owner == A
    assert rig.clients[B].owner == A                      # B learned it from CONTROL_STATUS
    rig.post(B, rig.clients[B].request_control(rig.now, timeout=10))
    rig.run(2.0)
    assert [e.requester for e in rig.events if isinstance(e, TakeoverRequested)] == [B]
    assert [r.outcome for r in rig.results[B]] == [O.GRANTED] and rig.manager.owner == B
    assert [r.operation for r in rig.results[A]] == [Op.REQUEST, Op.ANSWER_ALLOW]
    assert rig.clients[A].owner == B and not rig.clients[A].in_control
    history = [e for _, e, _ in rig.manager.stats.history]
    assert [e.name for e in history] == ["GRANT", "REFUSE_AND_FORWARD", "OWNER_ALLOWS", "GRANT"]
    rig.run(15.0)
    assert [r.operation for r in rig.results[A]] == [Op.REQUEST, Op.ANSWER_ALLOW]   # no revert sent
    assert rig.manager.owner == B and rig.manager.state is S.OWNED


def test_owner_loss_frees_control_for_the_next_gcs():
    """"If all owning GCS are disconnected the vehicle should GCS loss failsafe, and broadcast a
    CONTROL_STATUS indicating that it has no owner(s).\""""
    A, B = 201, 202
    rig = Rig({A: always(None), B: always(None)}, loss_timeout=3.0)
    rig.post(A, rig.clients[A].request_control(rig.now))
    rig.run(1.0)
    rig.alive.discard(A)
    rig.run(5.0)
    assert [e.sysid for e in rig.events if isinstance(e, OwnerLost)] == [A]
    assert rig.clients[B].owner == 0 and rig.manager.state is S.UNOWNED
    rig.post(B, rig.clients[B].request_control(rig.now))
    rig.run(1.0)
    assert rig.manager.owner == B


# --- random programs, random delivery ------------------------------------------------------
gcs_ids = st.sampled_from(GCS_IDS)
STATE_CHANGING = d.MAVLink_command_long_message(1, 1, d.MAV_CMD_MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0)


@settings(stateful_step_count=40, deadline=None)   # example count: the profile (tests/conftest.py)
class OperatorControl(RuleBasedStateMachine):
    """Three GCSs with random answering policies; messages delivered in any order, or lost."""

    @initialize(policies=st.tuples(*[st.sampled_from(list(Decision) + [None])] * 3))
    def start(self, policies):
        self.rig = Rig({g: always(p) for g, p in zip(GCS_IDS, policies)}, loss_timeout=4.0)

    @rule(g=gcs_ids, allow=st.booleans(), wait=st.booleans(), timeout=st.sampled_from([3.0, 10.0, 60.0]))
    def request_control(self, g, allow, wait, timeout):
        c = self.rig.clients[g]
        if not c.busy:
            self.rig.post(g, c.request_control(self.rig.now, allow_takeover=allow, timeout=timeout, wait=wait))

    @rule(g=gcs_ids)
    def release_control(self, g):
        c = self.rig.clients[g]
        if not c.busy:
            self.rig.post(g, c.release_control(self.rig.now))

    @rule(g=gcs_ids, allowed=st.booleans())
    def set_takeover(self, g, allowed):
        c = self.rig.clients[g]
        if not c.busy and c.in_control:
            self.rig.post(g, c.set_takeover(allowed, self.rig.now))

    @rule(g=gcs_ids)
    def send_a_command(self, g):
        """A state-changing command passes the filter exactly when its sender owns control."""
        m = self.rig.manager
        refusal = m.screen(self.rig.frame(g, STATE_CHANGING))
        assert (refusal is None) == (m.owner == g), f"GCS {g}, owner {m.owner}: {refusal}"
        if refusal is not None:
            (ack,) = refusal.actions
            assert ack.msg.result == d.MAV_RESULT_NOT_IN_CONTROL and ack.to[0] == g

    @precondition(lambda self: self.rig.in_flight)
    @rule(i=st.integers(0, 10_000))
    def deliver_one(self, i):
        self.rig.deliver(i)

    @precondition(lambda self: self.rig.in_flight)
    @rule(stride=st.integers(0, 7))
    def deliver_everything(self, stride):
        """Everything in flight (and whatever it provokes), in a scrambled order."""
        for _ in range(1000):
            if not self.rig.in_flight:
                break
            self.rig.deliver(stride)

    @precondition(lambda self: self.rig.in_flight)
    @rule(i=st.integers(0, 10_000))
    def lose_one(self, i):
        self.rig.in_flight.pop(i % len(self.rig.in_flight))

    @rule(dt=st.floats(0.05, 12.0))
    def time_passes(self, dt):
        self.rig.tick(dt)

    @rule(g=gcs_ids)
    def gcs_falls_silent(self, g):
        self.rig.alive.discard(g)

    @rule(g=gcs_ids)
    def gcs_comes_back(self, g):
        self.rig.alive.add(g)

    @invariant()
    def never_two_owners(self):
        m = self.rig.manager
        may = {g for g in GCS_IDS if m.may_command(g)}
        assert may == ({m.owner} if m.owner else set()), (m.owner, may)
        assert (m.state is S.UNOWNED) == (m.owner == 0)
        assert all(MANAGER_TRANSITIONS[(a, e)] is b for a, e, b in m.stats.history)

    @invariant()
    def every_wait_has_a_deadline(self):
        assert self.rig.manager.next_deadline() is not None
        for c in self.rig.clients.values():
            if c._op is not None:
                assert c.next_deadline() is not None

    def teardown(self):
        """Left alone (all messages delivered, everyone alive), every engine comes to rest."""
        rig = getattr(self, "rig", None)
        if rig is None:
            return
        rig.alive = set(GCS_IDS)
        rig.run(120.0)
        m = rig.manager
        assert m.state in (S.UNOWNED, S.OWNED, S.OWNED_TAKEOVER_ALLOWED), m.state
        for g, c in rig.clients.items():
            assert c._op is None and not c._queue, f"GCS {g} still busy"
            assert c.owner == m.owner, f"GCS {g} believes {c.owner} owns control, the vehicle says {m.owner}"
        for results in rig.results.values():
            assert all(r.finished - r.started <= 120.0 for r in results)


TestOperatorControl = OperatorControl.TestCase
