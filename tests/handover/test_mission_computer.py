"""The mission computer alone (sans-IO): positions, frames and ControlChanged events scripted in,
virtual time, no network. The end-to-end flights are in test_handover_sequence.py.

The geometry (line_geometry.py) is a line north of HOME: GCS A covers 0..1200 m north, GCS B 800..2300 m, so the
handover region is 800..1200 m, under each of the thesis's three region methods.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.control_results import ControlChanged
from mavconform.reference_impl.handover.gcs_handover import AGENT_TRANSITIONS, AgentEvent, AgentState
from mavconform.reference_impl.handover.hysteresis import (LATCH_TRANSITIONS, Edge, Latch, LatchEvent, Presence,
                                                           Sense, sense_of, signed_distance_m)
from mavconform.reference_impl.handover.mission_computer import (
    HandoverFinished, HandoverStarted, MissionComputer, MissionComputerConfig, WithdrawTakeover,
    critical_path_budget)
from mavconform.reference_impl.handover.mission_computer_transitions import (
    MC_TRANSITIONS, PHASE_TRANSITIONS, HandoverOutcome as Out, HandoverPhase, McEvent, McState, PhaseEvent)
from mavconform.reference_impl.handover.regions import Circle, Intersection, OwnedWaypoints
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.state_table import next_state
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

from .line_geometry import A, B, C, COVERAGES, HOME, VEHICLE, WAYPOINTS, at, rect


def config(method: str = "polygon", **kw) -> MissionComputerConfig:
    return MissionComputerConfig(parent=A, coverages=COVERAGES[method], **kw)


# --- frames as the vehicle would see them (through the real codec) ---------------------------
_enc = {s: FrameEncoder(s, 190) for s in (A, B, C)}
_dec = FrameDecoder()


def frame(sender: int, msg):
    (f,) = _dec.feed(_enc[sender].encode(msg))
    return f


def request(sender: int, action: float = 1.0, allow: bool = False):
    return frame(sender, cm.request_command(VEHICLE, action, allow, 10.0, sender))


def ack(sender: int):
    return frame(sender, cm.command_ack(cm.REQUEST_CONTROL, d.MAV_RESULT_ACCEPTED, VEHICLE))


class Script:
    """Drives one MissionComputer: positions along the line, the manager's events by hand."""

    def __init__(self, cfg: MissionComputerConfig, *, method: str = "polygon", owner: int = A,
                 start: bool = True) -> None:
        self.mc = MissionComputer(*VEHICLE, cfg, record_history=True)
        self.method = method
        self.now = 0.0
        self.out: list = []
        self.owner = 0
        if owner:
            self.change(owner)
        if start:
            self.begin(0.0)

    def begin(self, north: float) -> None:
        """MISSION_STARTED at `north`; the first check there says which regions it starts in."""
        self.mc.observe(at(north), self.now)
        self.mc.start(self.now, WAYPOINTS if self.method == "waypoints" else ())
        self.take(self.mc.poll(self.now))

    def take(self, actions: list) -> list:
        self.out += actions
        return actions

    def change(self, owner: int, allowed: bool = False) -> list:
        previous, self.owner = self.owner, owner
        return self.take(self.mc.control_changed(ControlChanged(owner, previous, allowed, "script"), self.now))

    def handle(self, f) -> list:
        return self.take(self.mc.handle(f, self.now))

    def fly(self, north: float, until: float | None = None, *, dt: float = 0.05) -> None:
        """Hold (or put) the vehicle at `north` and poll every dt until `until` (default: one poll)."""
        end = self.now if until is None else until
        for _ in range(1_000_000):
            self.mc.observe(at(north), self.now)
            self.take(self.mc.poll(self.now))
            if self.now >= end:
                return
            self.now = min(end, round(self.now + dt, 9))
        raise AssertionError("fly: loop bound")

    def started(self) -> list[HandoverStarted]:
        return [a for a in self.out if isinstance(a, HandoverStarted)]

    def results(self):
        return [a.result for a in self.out if isinstance(a, HandoverFinished)]

    def sent_to(self, sysid: int) -> list:
        return [a.msg for a in self.out if isinstance(a, Send) and a.to == (sysid, 0)]

    def complete(self) -> None:
        """A perfect network: the running handover's steps 2-6 happen at once."""
        a = self.mc.attempt
        old, partner = a.commander, a.partner
        self.handle(request(partner))
        self.change(old, allowed=True)
        self.change(partner)
        self.handle(ack(partner))
        self.handle(request(old, action=0.0))


def instantly(script: Script) -> None:
    if script.mc.attempt is not None:
        script.complete()


# --- tables ----------------------------------------------------------------------------------
def test_the_mission_computer_walks_every_transition_of_its_table():
    """ON_LOAD -> ON_MISSION -> (HANDOVER_DUE -> COMPLETED / UNCONFIRMED / ABORTED) -> ON_LOAD,
    with CONTROL_MOVED in on_load and on_mission: every listed move is taken, none other."""
    s = Script(config(), owner=0, start=False)
    s.change(A)                                   # on_load: CONTROL_MOVED
    s.begin(0.0)                                  # MISSION_STARTED
    s.fly(100, 1.0)
    s.change(C)
    s.change(A)                                   # on_mission: CONTROL_MOVED
    s.fly(1000, 3.0)                              # entered: HANDOVER_DUE
    s.complete()                                  # COMPLETED
    s.fly(1500, 6.0)                              # out of the region (B only)
    s.fly(1000, 9.0)                              # back in: B -> A
    s.handle(request(A))
    s.change(A)                                   # granted; 5 and 6 never come: UNCONFIRMED
    s.fly(1000, 9.0 + s.mc.config.bound + 1)
    s.fly(500, s.now + 3)
    s.fly(1000, s.now + 3)                        # A -> B again; never granted: ABORTED
    s.fly(1000, s.now + s.mc.config.commit_timeout + 1)
    s.mc.stop(s.now)                              # MISSION_ENDED
    moves = {(o, e) for o, e, _ in s.mc.history if isinstance(e, McEvent)}
    assert moves == set(MC_TRANSITIONS)
    assert [r.outcome for r in s.results()] == [Out.COMPLETED, Out.UNCONFIRMED, Out.ABORTED]
    assert s.mc.state is McState.ON_LOAD
    assert all(MC_TRANSITIONS[(o, e)] is n for o, e, n in s.mc.history if isinstance(e, McEvent))


def test_a_move_outside_the_tables_is_a_local_protocol_error():
    for table, state, event in ((MC_TRANSITIONS, McState.ON_LOAD, McEvent.HANDOVER_DUE),
                                (MC_TRANSITIONS, McState.ON_HANDOVER, McEvent.MISSION_STARTED),
                                (LATCH_TRANSITIONS, Presence.OUT, LatchEvent.SETTLED),
                                (AGENT_TRANSITIONS, AgentState.IDLE, AgentEvent.PARTNER_TOOK_OVER)):
        with pytest.raises(LocalProtocolError, match="no transition"):
            next_state(table, state, event, "test")


def test_the_phase_table_is_total_and_only_moves_forward():
    """Every observation is listed in every phase (stale ones stay put), and no move goes back
    past the commit: once CONNECTED, only 5 and 6 move the phase."""
    assert set(PHASE_TRANSITIONS) == {(p, e) for p in HandoverPhase for e in PhaseEvent}
    order = list(HandoverPhase)
    for (p, e), n in PHASE_TRANSITIONS.items():
        assert order.index(n) >= order.index(p), (p, e, n)


PATHS = [
    # the six steps in order, and the other orders the network can produce
    [PhaseEvent.PARTNER_REQUESTED, PhaseEvent.COMMANDER_ALLOWED, PhaseEvent.GRANTED,
     PhaseEvent.PARTNER_CONFIRMED, PhaseEvent.COMMANDER_DISCONNECTED],
    [PhaseEvent.COMMANDER_ALLOWED, PhaseEvent.GRANTED, PhaseEvent.COMMANDER_DISCONNECTED, PhaseEvent.PARTNER_CONFIRMED],
    [PhaseEvent.PARTNER_REQUESTED, PhaseEvent.COMMANDER_RELEASED, PhaseEvent.GRANTED,
     PhaseEvent.COMMANDER_DISCONNECTED, PhaseEvent.PARTNER_CONFIRMED],
    [PhaseEvent.COMMANDER_RELEASED, PhaseEvent.GRANTED, PhaseEvent.PARTNER_CONFIRMED,
     PhaseEvent.COMMANDER_DISCONNECTED],
    [PhaseEvent.GRANTED, PhaseEvent.PARTNER_CONFIRMED, PhaseEvent.COMMANDER_DISCONNECTED],
    [PhaseEvent.PARTNER_REQUESTED, PhaseEvent.GRANTED, PhaseEvent.PARTNER_CONFIRMED, PhaseEvent.COMMANDER_DISCONNECTED],
]


@pytest.mark.parametrize("path", PATHS)
def test_every_path_through_the_phases_ends_done(path):
    phase = HandoverPhase.INVITING
    for e in path:
        phase = next_state(PHASE_TRANSITIONS, phase, e, "test")
    assert phase is HandoverPhase.DONE


def test_the_phase_walks_cover_every_moving_transition():
    moving = {k for k, v in PHASE_TRANSITIONS.items() if v is not k[0]}
    seen = set()
    for path in PATHS:
        phase = HandoverPhase.INVITING
        for e in path:
            new = PHASE_TRANSITIONS[(phase, e)]
            if new is not phase:
                seen.add((phase, e))
            phase = new
    assert seen == moving


# --- the latch ------------------------------------------------------------------------------
def test_the_latch_walks_every_transition():
    moves = []
    latch = Latch(1.0, on_move=lambda o, e, n: moves.append((o, e)))
    script = [(Sense.BORDER, 0), (Sense.OUTSIDE, 0.1), (Sense.INSIDE, 0.2), (Sense.INSIDE, 0.3), (Sense.BORDER, 0.4),
              (Sense.INSIDE, 0.5), (Sense.OUTSIDE, 0.6), (Sense.INSIDE, 1.0), (Sense.INSIDE, 2.0),   # IN
              (Sense.INSIDE, 2.1), (Sense.BORDER, 2.2), (Sense.OUTSIDE, 2.3), (Sense.OUTSIDE, 2.4),
              (Sense.INSIDE, 2.5), (Sense.OUTSIDE, 2.6), (Sense.BORDER, 2.7), (Sense.OUTSIDE, 2.8),
              (Sense.OUTSIDE, 3.8)]                                                               # OUT
    edges = [latch.observe(s, t) for s, t in script]
    assert [e for e in edges if e] == [Edge.ENTERED, Edge.EXITED]
    assert set(moves) == set(LATCH_TRANSITIONS)


senses = st.lists(st.tuples(st.sampled_from(list(Sense)), st.floats(0.0, 2.0)), max_size=80)


@given(senses, st.floats(0.0, 3.0))
def test_the_latch_enters_only_after_dwelling_inside_and_leaves_only_after_dwelling_outside(steps, dwell):
    """Edges alternate (ENTERED first); an ENTERED is preceded by INSIDE observations spanning
    at least `dwell` with nothing else between, an EXITED by OUTSIDE ones likewise."""
    latch = Latch(dwell)
    t, edges = 0.0, []
    run_sense, run_start = None, 0.0
    for sense, dt in steps:
        t += dt
        if sense is not run_sense:
            run_sense, run_start = sense, t
        edge = latch.observe(sense, t)
        if edge is Edge.ENTERED:
            assert sense is Sense.INSIDE and t - run_start >= dwell
        elif edge is Edge.EXITED:
            assert sense is Sense.OUTSIDE and t - run_start >= dwell
        if edge:
            edges.append(edge)
    assert edges == [Edge.ENTERED, Edge.EXITED] * (len(edges) // 2) + [Edge.ENTERED] * (len(edges) % 2)


# --- distances and margins --------------------------------------------------------------------
REGIONS = [rect(-300, 1200), Circle(at(2000), 1200.0), Intersection((rect(-300, 1200), rect(800, 2300)))]


@given(st.sampled_from(REGIONS), st.floats(-600, 2600), st.floats(-500, 500), st.floats(0, 100))
def test_the_signed_distance_agrees_with_contains_and_the_margin_with_it(region, north, east, margin):
    p = at(north, east)
    dist = signed_distance_m(region, p)
    assert (dist <= 0) == region.contains(p)
    sense = sense_of(region, p, margin)
    if sense is Sense.INSIDE:
        assert region.contains(p)
    elif sense is Sense.OUTSIDE:
        assert not region.contains(p)


@pytest.mark.parametrize("north, expected", [(1000, -200.0), (1190, -10.0), (1210, 10.0), (1500, 300.0),
                                             (-350, 50.0), (500, -300.0)])
def test_the_distance_to_a_polygon_edge_is_right_to_a_centimetre(north, expected):
    """A 600 m wide strip: the nearest edge is the north or south one, or a side at 300 m."""
    assert signed_distance_m(rect(-300, 1200), at(north)) == pytest.approx(expected, abs=0.05)


# --- the region check, per method -------------------------------------------------------------
@pytest.mark.parametrize("method", ["polygon", "circle", "waypoints"])
def test_out_through_the_region_and_back_hands_over_twice_with_the_right_owner_per_segment(method):
    """Out to 2000 m and back at 20 m/s: A commands short of the region (800 m) on the way out
    and past it (below 800 m) on the way back, B beyond it (1200 m) both ways."""
    s = Script(config(method), method=method)
    owners = []
    for north in list(range(0, 2001, 10)) + list(range(2000, -1, -10)):
        s.fly(north, s.now + 0.5)
        instantly(s)
        owners.append((north, len(owners) > 200, s.owner))
    results = s.results()
    assert [(r.commander, r.partner, r.outcome) for r in results] == [(A, B, Out.COMPLETED), (B, A, Out.COMPLETED)]
    assert all([step for step, _ in r.steps] == [1, 2, 3, 4, 5, 6] for r in results)
    assert {o for n, back, o in owners if n < 800 - 10 and not back} == {A}
    assert {o for n, back, o in owners if n > 1200} == {B}
    assert {o for n, back, o in owners if n < 800 - 50 and back} == {A}


@pytest.mark.parametrize("method", ["polygon", "circle"])
def test_a_flight_that_starts_inside_a_region_does_not_hand_over_until_it_enters_again(method):
    s = Script(config(method), start=False)
    s.begin(1000)
    s.fly(1000, 10.0)
    assert not s.started()
    s.fly(500, 15.0)
    s.fly(1000, 20.0)
    assert [(h.commander, h.partner) for h in s.started()] == [(A, B)]


def test_a_commander_outside_the_pair_starts_nothing():
    cfg = MissionComputerConfig(parent=A, coverages={**COVERAGES["polygon"], C: Circle(at(5000, 5000), 100.0)})
    s = Script(cfg, owner=C)
    s.fly(1000, 5.0)
    assert not s.started()
    s.change(A)                          # the pair's commander now: the entry still counts
    s.fly(1000, 5.1)
    assert [(h.commander, h.partner) for h in s.started()] == [(A, B)]


# --- hysteresis: border jitter ------------------------------------------------------------------
def jitter(s: Script, *, amplitude: float, period: float, seconds: float) -> None:
    """Oscillate across the handover region's south edge (800 m) for `seconds`."""
    start = s.now
    while s.now < start + seconds:
        phase = ((s.now - start) % period) / period
        s.fly(800 + amplitude * math.sin(2 * math.pi * phase), s.now + 0.05)
        instantly(s)


@pytest.mark.parametrize("method", ["polygon", "circle"])
def test_border_jitter_flaps_without_dwell_and_not_with_it(method):
    """The vehicle wavers 20 m either side of the region's edge every 2 s for a minute, then goes
    deep into B's coverage. With no dwell and no margin, every wobble is a region entry, and
    the commander flips back and forth; with a 3 s dwell, or a 30 m margin, one handover."""
    counts = {}
    for name, knobs in {"none": dict(dwell=0.0), "dwell": dict(dwell=3.0),
                        "margin": dict(dwell=0.0, margin_m=30.0)}.items():
        s = Script(config(method, **knobs))
        s.fly(700, 5.0)
        jitter(s, amplitude=20.0, period=2.0, seconds=60.0)
        for north in range(800, 1501, 10):
            s.fly(north, s.now + 0.2)
            instantly(s)
        counts[name] = len(s.results())
        assert s.owner == B
    assert counts["none"] >= 20                       # flaps: ~one handover per crossing
    assert counts["dwell"] == 1 and counts["margin"] == 1


# --- the bound -------------------------------------------------------------------------------
def test_a_commander_that_never_authorises_aborts_at_the_commit_bound_and_keeps_control():
    s = Script(config())
    s.fly(1000, 5.0)
    (started,) = s.started()
    s.handle(request(B))                     # step 2 seen; the commander stays silent
    s.fly(1000, started.at + s.mc.config.bound + 5)
    (r,) = s.results()
    assert r.outcome is Out.ABORTED and r.owner == A and r.commander == A
    assert r.finished == pytest.approx(started.at + s.mc.config.commit_timeout, abs=0.051)
    assert [step for step, _ in r.steps] == [1, 2]
    assert [a for a in s.out if isinstance(a, WithdrawTakeover)] == [WithdrawTakeover(B, r.detail)]
    # the invitation, resent each second until the partner's request came at 5 s: its param3 is
    # the time left to the commit deadline, its param4 the partner itself
    invites = s.sent_to(B)
    assert [m.confirmation for m in invites] == list(range(len(invites))) and 4 <= len(invites) <= 5
    invite = invites[0]
    assert (invite.command, invite.param1, invite.param2, invite.param4) == (cm.REQUEST_CONTROL, 1, 0, B)
    assert invite.param3 == pytest.approx(s.mc.config.commit_timeout)
    assert invites[-1].param3 < invite.param3
    # one handover per entry: staying inside starts no other
    assert len(s.started()) == 1


def test_an_unanswered_invitation_is_resent_a_bounded_number_of_times():
    s = Script(config(resends=3, resend_period=2.0))
    s.fly(1000, 30.0)
    sent = s.sent_to(B)
    assert [m.confirmation for m in sent] == [0, 1, 2, 3]
    s2 = Script(config())
    s2.fly(1000, 2.0)
    s2.handle(ack(B))                        # the partner's client acknowledged it
    s2.fly(1000, 20.0)
    assert len(s2.sent_to(B)) <= 2


def test_a_grant_without_steps_5_and_6_ends_unconfirmed_at_the_bound_with_the_partner_in_control():
    s = Script(config())
    s.fly(1000, 5.0)
    (started,) = s.started()
    invitations = len(s.sent_to(B))
    s.change(B)                              # granted at once (the commander had allowed takeover)
    s.fly(1000, started.at + s.mc.config.bound + 1)
    (r,) = s.results()
    assert r.outcome is Out.UNCONFIRMED and r.owner == B and "5, 6" in r.detail
    assert r.finished == pytest.approx(started.at + s.mc.config.bound, abs=0.051)
    notices = s.sent_to(B)[invitations:]     # the connect notice, resent until the bound
    assert len(notices) == 1 + s.mc.config.resends and notices[0].param4 == B


def test_leaving_the_region_before_the_grant_aborts_and_a_new_entry_is_a_new_handover():
    s = Script(config(dwell=1.0))
    s.fly(1000, 5.0)
    s.fly(600, 8.0)
    (r,) = s.results()
    assert r.outcome is Out.ABORTED and "left region" in r.detail
    s.fly(1000, 12.0)
    assert len(s.started()) == 2


def test_control_going_to_a_third_gcs_aborts():
    s = Script(config())
    s.fly(1000, 5.0)
    s.change(C)
    (r,) = s.results()
    assert r.outcome is Out.ABORTED and r.owner == C


def test_a_commander_that_releases_authorises_and_disconnects_at_once():
    s = Script(config())
    s.fly(1000, 5.0)
    s.handle(request(B))
    s.change(0)                              # "may choose to release control"
    s.change(B)
    s.handle(ack(B))
    (r,) = s.results()
    assert r.outcome is Out.COMPLETED and [step for step, _ in r.steps] == [1, 2, 3, 4, 5, 6]


def test_the_mission_ending_mid_handover_lets_it_finish_first():
    s = Script(config())
    s.fly(1000, 5.0)
    s.mc.stop(s.now)
    assert s.mc.state is McState.ON_HANDOVER
    s.complete()
    assert s.mc.state is McState.ON_LOAD and s.mc.next_deadline() is None


def test_the_default_bound_covers_every_message_getting_through_on_its_last_resend():
    commit, closing = critical_path_budget(ManagerConfig(), ClientConfig())
    cfg = config()
    assert commit <= cfg.commit_timeout and closing <= cfg.closing
    assert cfg.bound == cfg.commit_timeout + cfg.closing == 40.0


@pytest.mark.parametrize("kw, match", [
    (dict(parent=C), "parent"),
    (dict(coverages={A: Circle(HOME, 10.0)}), "at least two"),
    (dict(coverages={A: Circle(HOME, 10.0), B: OwnedWaypoints(frozenset({1}))}), "one region method"),
    (dict(coverages={A: OwnedWaypoints(frozenset({1})), B: OwnedWaypoints(frozenset({1}))}), "owned by both"),
    (dict(coverages=COVERAGES["waypoints"], margin_m=5.0), "margin_m"),
    (dict(dwell=-1.0), "dwell"),
    (dict(check_period=0.0), "check_period"),
    (dict(bound=10.0, closing_timeout=10.0), "closing_timeout"),
])
def test_a_bad_config_is_refused_naming_the_field(kw, match):
    base = dict(parent=A, coverages=COVERAGES["polygon"])
    with pytest.raises(ValueError, match=match):
        MissionComputerConfig(**{**base, **kw})


def test_the_config_is_hashable_and_the_check_period_is_the_thesis_50_ms():
    cfg = config()
    assert hash(cfg) == hash(config()) and cfg.check_period == 0.05
