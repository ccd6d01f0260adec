"""The handover end to end, in virtual time: the reference vehicle with its system manager and
mission computer, two reference GCSs with handover agents, flying the thesis's delivery (seed
003, 4.1: out through the handover region to GCS B's side and back) over SimNetwork.

GCS A (the parent) covers 0..1200 m north of home, GCS B 800..2300 m; the handover region is
800..1200 m, under each region method. What is checked: two handovers, each over the MAVLink
exchange docs/handover.md maps the thesis's six steps to; the right commander on each segment;
a commander that never authorises (or a partner that cannot answer the invitation) costs an
abort at the bound with the old commander kept; border jitter needs the dwell; and under 20 %
loss on every link every handover still ends within the bound, in the outcome it says.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.reference_impl.gcs import GcsConfig
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.control_results import ControlOperation as Op, ControlOutcome as O, Decision
from mavconform.reference_impl.handover.control_transitions import ControlState
from mavconform.reference_impl.handover.gcs_handover import GcsHandoverConfig, HandoverAgent
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.mission_computer import HandoverStarted, MissionComputerConfig
from mavconform.reference_impl.handover.mission_computer_transitions import (HandoverOutcome as Out, McState,
                                                                             render_markdown)
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.net import FaultModel
from mavconform.reference_impl.net.faults import DropWhere
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire import FrameDecoder
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcss
from .test_mission_computer import COVERAGES, HOME, A, B, at

SPEED = 20.0                      # m/s: the 4 km round trip takes 200 s of virtual time
LATENCY = FaultModel(delay=0.02)
DOC = Path(__file__).resolve().parents[2] / "docs" / "handover.md"
# out to 2000 m and back; waypoint seqs as COVERAGES["waypoints"] assigns them
ROUTE = (0, 400, 800, 1200, 2000, 1200, 800, 0)


def item(seq: int, north: float) -> MissionItem:
    p = at(north)
    return MissionItem(seq, 3, int(Cmd.NAV_WAYPOINT), x=round(p.lat * 1e7), y=round(p.lon * 1e7), z=20.0)


def fly_out_and_back(method: str, *, agents: tuple[str, ...] = ("A", "B"), link: FaultModel | None = LATENCY,
                     seed: int = 3, owner_loss: float = 5.0, route=ROUTE, agent_kw: dict | None = None, **mc_kw):
    """The fleet, A in control with the route uploaded and the flight started."""
    cov = COVERAGES[method]
    mc = MissionComputerConfig(parent=A, coverages=cov, **mc_kw)
    vehicle = VehicleConfig(control=ManagerConfig(owner_loss_timeout=owner_loss), handover=mc, speed=SPEED)
    gcss = {n: GcsConfig(system=s, control=ClientConfig()) for n, s in (("A", A), ("B", B))}
    handovers = {n: HandoverAgent(s, GcsHandoverConfig(cov, **(agent_kw or {}).get(n, {})))
                 for n, s in (("A", A), ("B", B)) if n in agents}
    f = vehicle_and_gcss(vehicle, gcss, handovers=handovers, link=link, seed=seed, discovery=20.0)
    session = f.sessions["A"]
    assert session.request_control().ok
    plan = [item(i, n) for i, n in enumerate(route)]
    assert any(session.upload(MissionType.MISSION, plan).ok for _ in range(3))   # setup, even at 20 % loss
    start = d.MAVLink_command_long_message(1, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0)
    for _ in range(10):
        f.gcs("A").send(start)
        if f.net.run_until(lambda: f.vehicle.flight.flying, timeout=2.0):
            break
    assert f.vehicle.flight.flying
    return f


def follow(f, *, limit: float = 400.0, step: float = 1.0) -> list[tuple[float, bool, int]]:
    """Run to the end of the flight, sampling (metres north, on the way back, gcs_main) each step."""
    v = f.vehicle
    samples, far = [], 0.0
    for _ in range(int(limit / step)):
        f.net.run_for(step)
        p = v.flight.where(f.net.clock.now())
        north = haversine_m(HOME, GeoPoint(p.lat, p.lon))
        far = max(far, north)
        samples.append((north, far >= 1990, v.owner))
        if not v.flight.flying and v.mission_computer.state is McState.ON_LOAD:
            return samples
    raise AssertionError("the flight did not end within its bound")


def results(f):
    return f.vehicle.mission_computer.results


# --- the delivery flight, per region method -------------------------------------------------------
@pytest.mark.parametrize("method", ["polygon", "circle", "waypoints"])
def test_the_delivery_flight_hands_over_out_and_back_with_the_right_commander_per_segment(method):
    f = fly_out_and_back(method)
    samples = follow(f)
    assert [(r.commander, r.partner, r.outcome) for r in results(f)] == [(A, B, Out.COMPLETED),
                                                                          (B, A, Out.COMPLETED)]
    for r in results(f):
        assert [step for step, _ in r.steps] == [1, 2, 3, 4, 5, 6], r
        assert r.duration < 1.0                          # a clean link: a few round trips
    assert {o for n, back, o in samples if n < 780 and not back} == {A}
    assert {o for n, back, o in samples if n > 1220} == {B}
    assert {o for n, back, o in samples if n < 750 and back} == {A}
    # each GCS's side: A asks for control, allows B's takeover, lets go; then the same from B
    a_ops = [(r.operation, r.outcome) for r in f.gcs("A").control_results]
    b_ops = [(r.operation, r.outcome) for r in f.gcs("B").control_results]
    assert a_ops == [(Op.REQUEST, O.GRANTED), (Op.ANSWER_ALLOW, O.GRANTED), (Op.RELEASE, O.NOT_IN_CONTROL),
                     (Op.REQUEST, O.GRANTED)]
    assert b_ops == [(Op.REQUEST, O.GRANTED), (Op.ANSWER_ALLOW, O.GRANTED), (Op.RELEASE, O.NOT_IN_CONTROL)]
    assert f.vehicle.owner == A


def test_the_six_steps_are_the_mavlink_exchange_docs_handover_md_maps_them_to():
    """The first handover on the wire, in order: the mapping table of docs/handover.md."""
    f = fly_out_and_back("polygon")
    dec, wire = FrameDecoder(), []

    def capture(rec):
        if rec.kind == "rx":
            for fr in dec.feed(rec.data):
                wire.append((rec.time, rec.src, rec.dst, fr.msg))
    f.net.add_capture(capture)
    follow(f)
    first = results(f)[0]
    during = [(s, t, m) for time, s, t, m in wire if first.started <= time <= first.finished + 0.1]

    def cmd(m, action, allow, gcs):
        return cm.is_request_control(m) and (m.param1, m.param2, m.param4) == (action, allow, gcs)

    def ack(m, result):
        return m._type == "COMMAND_ACK" and m.command == cm.REQUEST_CONTROL and m.result == result

    def status(m, owner, allowed):
        return (m._type == "CONTROL_STATUS" and m.gcs_main == owner
                and bool(m.flags & d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED) == allowed)
    steps = [
        ("1 invitation", "vehicle", "B", lambda m: cmd(m, 1, 0, B) and m.target_system == B),
        ("1 partner's ACK", "B", "vehicle", lambda m: ack(m, d.MAV_RESULT_ACCEPTED)),
        ("2 partner requests", "B", "vehicle", lambda m: cmd(m, 1, 0, B)),
        ("2 refused", "vehicle", "B", lambda m: ack(m, d.MAV_RESULT_FAILED)),
        ("2 forwarded to the commander", "vehicle", "A", lambda m: cmd(m, 1, 0, B) and m.target_system == A),
        ("2 commander's ACK", "A", "vehicle", lambda m: ack(m, d.MAV_RESULT_ACCEPTED)),
        ("3 commander allows takeover", "A", "vehicle", lambda m: cmd(m, 1, 1, A)),
        ("3 CONTROL_STATUS takeover allowed", "vehicle", "B", lambda m: status(m, A, True)),
        ("4 partner requests in the window", "B", "vehicle", lambda m: cmd(m, 1, 0, B)),
        ("4 granted", "vehicle", "B", lambda m: ack(m, d.MAV_RESULT_ACCEPTED)),
        ("4 CONTROL_STATUS gcs_main partner", "vehicle", "A", lambda m: status(m, B, False)),
        ("4 connect notice", "vehicle", "B", lambda m: cmd(m, 1, 0, B) and m.target_system == B),
    ]
    # 5 and 6 run side by side after the commit, each in its own order
    closing = [[("5 partner's ACK of the notice", "B", "vehicle", lambda m: ack(m, d.MAV_RESULT_ACCEPTED))],
               [("6 commander releases", "A", "vehicle", lambda m: cmd(m, 0, 0, A)),
                ("6 vehicle: not in control", "vehicle", "A", lambda m: ack(m, d.MAV_RESULT_NOT_IN_CONTROL))]]

    def in_order(expected, i: int) -> int:
        for name, src, dst, match in expected:
            while i < len(during) and not (during[i][0] == src and during[i][1] == dst and match(during[i][2])):
                i += 1
            assert i < len(during), f"step {name!r} not seen in order"
            i += 1
        return i
    committed = in_order(steps, 0)
    for branch in closing:
        in_order(branch, committed)


# --- a handover that cannot complete ---------------------------------------------------------------
@pytest.mark.parametrize("who", ["commander without agent", "commander refuses", "partner without agent"])
def test_a_handover_nobody_completes_aborts_at_the_bound_and_the_old_commander_keeps_control(who):
    """A plain commander (no policy: it never answers), one whose telemetry never says the
    handover is due, or a partner that only ACKs the invitation: each entry of the region costs
    one abort, exactly `commit_timeout` after its start, and A commands the whole flight. (The
    bound is 20 s here: the vehicle crosses the 400 m region in 20 s, and leaving it first would
    abort the handover for that reason instead.)"""
    agents = {"commander without agent": ("B",), "commander refuses": ("A", "B"),
              "partner without agent": ("A",)}[who]
    agent_kw = {"A": {"telemetry_max_age": 0.0}} if who == "commander refuses" else None
    f = fly_out_and_back("polygon", agents=agents, agent_kw=agent_kw, bound=20.0)
    samples = follow(f)
    cfg = f.vehicle.config.handover
    assert [(r.commander, r.partner, r.outcome) for r in results(f)] == [(A, B, Out.ABORTED)] * 2
    for r in results(f):
        assert r.duration == pytest.approx(cfg.commit_timeout, abs=0.06) and r.owner == A
        assert r.detail == f"control not granted to GCS {B} within {cfg.commit_timeout:g} s"
        assert 4 not in dict(r.steps)
    assert {o for _, _, o in samples} == {A}
    assert f.vehicle.control.state is ControlState.OWNED          # nothing pending, no window open
    started = [e for e in f.vehicle.handover_events if isinstance(e, HandoverStarted)]
    assert len(started) == 2                                       # one per region entry, no retry


def test_a_late_resend_of_the_commanders_allow_does_not_take_control_back():
    """Regression (found at 20 % loss): the vehicle's ACK of A's allow-takeover (step 3) is
    lost, so A's client resends it 1.5 s later, when B already holds control. The manager
    reads it as A requesting control (param2 1) and forwards it to B; B's policy must refuse
    it: allowing opens a takeover window to any GCS, and A's further resends take control
    straight back inside the handover region (seed 32 of the loss test did)."""
    f = fly_out_and_back("polygon")
    acks = DropWhere(lambda m: m.get_type() == "COMMAND_ACK" and m.command == cm.REQUEST_CONTROL
                     and m.result == d.MAV_RESULT_ACCEPTED, limit=1)     # the next one: the allow's
    f.net.connect("A", "vehicle", a_to_b=LATENCY, b_to_a=FaultModel(delay=0.02, rules=(acks,)))
    samples = follow(f)
    assert acks.dropped == 1
    assert [(r.commander, r.partner, r.outcome) for r in results(f)] == [(A, B, Out.COMPLETED),
                                                                          (B, A, Out.COMPLETED)]
    assert {o for n, back, o in samples if n > 1220} == {B}
    assert (A, Decision.REFUSE) in [(g, dec) for g, dec, _ in f.gcs("B").handover.decisions]
    allowed_by_b = [e for e in f.vehicle.events if e.endswith(f"takeover allowed by GCS {B}")]
    assert len(allowed_by_b) == 1                     # the return handover's step 3 only


# --- hysteresis in flight ----------------------------------------------------------------------
def test_a_flight_zigzagging_across_the_border_needs_the_dwell_not_to_flap():
    """Ten zigzags 30 m either side of the region's edge (800 m), 1.5 s inside each time, then on
    to 1600 m. Dwell 0: a handover per crossing into the region; dwell 4 s: one, at the end."""
    zigzag = (0,) + (770, 830) * 10 + (770, 1600)
    counts = {}
    for dwell in (0.0, 4.0):
        f = fly_out_and_back("polygon", route=zigzag, dwell=dwell)
        follow(f)
        counts[dwell] = [(r.commander, r.partner, r.outcome) for r in results(f)]
        assert f.vehicle.owner == B
    assert counts[4.0] == [(A, B, Out.COMPLETED)]
    assert len(counts[0.0]) == 11 and {o for *_, o in counts[0.0]} == {Out.COMPLETED}   # A, B, A, ... B


# --- loss ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("seed", range(8))
def test_under_20_percent_loss_on_every_link_each_handover_ends_within_the_bound_as_it_says(seed):
    """Every link loses 20 % both ways (owner loss at 10 s so a commander is not dropped for
    silence meanwhile). Whatever the losses, each handover ends within the bound; when control
    moved (completed or unconfirmed) the partner holds it, when aborted the old commander
    does, and no handover is started twice for one region entry."""
    f = fly_out_and_back("polygon", link=FaultModel(delay=0.02, loss=0.2), seed=seed, owner_loss=10.0)
    follow(f, limit=500.0)
    cfg = f.vehicle.config.handover
    rs = results(f)
    assert [(r.commander, r.partner) for r in rs] in ([(A, B), (B, A)], [(A, B), (A, B)])
    for r in rs:
        assert r.duration <= cfg.bound + 1e-6, r
        if r.outcome is Out.ABORTED:
            assert r.owner == r.commander and 4 not in dict(r.steps), r
        else:
            assert r.owner == r.partner and 4 in dict(r.steps), r
    assert sum(r.outcome is Out.COMPLETED for r in rs) >= 1


# --- configuration -------------------------------------------------------------------------------
def test_without_the_handover_config_there_is_no_mission_computer_and_it_needs_control():
    assert VehicleNode(VehicleConfig()).mission_computer is None
    mc = MissionComputerConfig(parent=A, coverages=COVERAGES["polygon"])
    with pytest.raises(ValueError, match="needs VehicleConfig.control"):
        VehicleNode(VehicleConfig(handover=mc))


def test_docs_handover_md_has_the_tables_as_the_code_defines_them():
    assert render_markdown() in DOC.read_text(encoding="utf-8")
