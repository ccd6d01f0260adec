"""The emergency procedure on the reference vehicle (seed 003, 4.7), in virtual time.

The geometry of test_mission_computer: a line north of HOME, GCS A covering 0..1200 m (300 m
either side), GCS B 800..2300 m, the handover region 800..1200 m. Two rally points: R0 east of
the line at 700 m north, R1 west of it at 1500 m. The flight goes out to 2000 m and back at
20 m/s. What is checked: the commander falling silent starts the emergency exactly when the
system manager drops it (within the loss timeout plus one check period), announced by
STATUSTEXT and CONTROL_STATUS with no owner; the vehicle diverts straight to the refuge
`choose_refuge` picks with the battery the flight has left, and lands there; flying out of
every coverage starts it after the grace and not before; a normal handover never does; no GCS
command ends the refuge flight except a known GCS covering the vehicle taking control back.
"""

from __future__ import annotations

import pytest

from mavconform.reference_impl.flight import DESCENT_SPEED, FlightBattery, FlightSim, Position
from mavconform.reference_impl.gcs import GcsConfig
from mavconform.reference_impl.handover.control_client import ClientConfig
from mavconform.reference_impl.handover.control_manager import ControlManager, ManagerConfig
from mavconform.reference_impl.handover.control_results import ControlChanged, ControlOutcome as O, OwnerLost
from mavconform.reference_impl.handover.emergency import (BatteryModel, BatteryState, RefugeKind, TriggerKind,
                                                          TriggerPolicy, choose_refuge)
from mavconform.reference_impl.handover.emergency_procedure import (EmergencyConfig, EmergencyEnded,
                                                                    EmergencyStarted, revoke_owner)
from mavconform.reference_impl.handover.gcs_handover import GcsHandoverConfig, HandoverAgent
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.mission_computer import (HandoverFinished, HandoverStarted, MissionComputer,
                                                                 MissionComputerConfig, RevokeControl)
from mavconform.reference_impl.handover.mission_computer_transitions import (
    EMERGENCY_TRANSITIONS, MC_TABLE, MC_TRANSITIONS, HandoverOutcome as Out, McEvent, McState)
from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.progress import MissionProgress
from mavconform.reference_impl.mission.store import MissionStore
from mavconform.reference_impl.net import FaultModel
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcss
from .test_mission_computer import COVERAGES, HOME, A, B, at, request

SPEED = 20.0
LOSS = 5.0
CHECK = 0.05
LATENCY = FaultModel(delay=0.02)
R0, R1 = at(700, 150), at(1500, -250)
LAUNCH = GeoPoint(HOME.lat, HOME.lon, 0.0)          # home for RTL: where the flight started, as the vehicle saw it
RALLY = (R0, R1)
MODEL = BatteryModel(capacity_wh=100.0, consumption_wh_per_m=0.01, reserve_wh=20.0)   # 1 km per 10 Wh
ROUTE = (0, 400, 800, 1200, 2000, 1200, 800, 0)


def item(seq: int, north: float, east: float = 0.0) -> MissionItem:
    p = at(north, east)
    return MissionItem(seq, 3, int(Cmd.NAV_WAYPOINT), x=round(p.lat * 1e7), y=round(p.lon * 1e7), z=20.0)


def emergency_config(*, grace: float | None = None, takeback: bool = True, **kw) -> EmergencyConfig:
    return EmergencyConfig(TriggerPolicy(LOSS, grace or 0.0), RALLY, outside=grace is not None, takeback=takeback,
                           **kw)


def launch(*, route=ROUTE, plan: list[MissionItem] | None = None, battery_wh: float = 100.0,
           grace: float | None = None, takeback: bool = True, open_when_unowned: bool = False, agents: bool = True,
           emergency: bool = True, seed: int = 5):
    """The fleet, A in control, the route uploaded and flown; the emergency procedure on."""
    cov = COVERAGES["polygon"]
    mc = MissionComputerConfig(parent=A, coverages=cov, check_period=CHECK,
                               emergency=emergency_config(grace=grace, takeback=takeback) if emergency else None)
    vehicle = VehicleConfig(control=ManagerConfig(owner_loss_timeout=LOSS, open_when_unowned=open_when_unowned),
                            handover=mc, speed=SPEED,
                            battery=FlightBattery(MODEL, BatteryState(battery_wh)))
    gcss = {n: GcsConfig(system=s, control=ClientConfig()) for n, s in (("A", A), ("B", B))}
    handovers = {n: HandoverAgent(s, GcsHandoverConfig(cov)) for n, s in (("A", A), ("B", B))} if agents else None
    f = vehicle_and_gcss(vehicle, gcss, handovers=handovers, link=LATENCY, seed=seed, discovery=20.0)
    assert f.sessions["A"].request_control().ok
    plan = plan if plan is not None else [item(i, n) for i, n in enumerate(route)]
    assert f.sessions["A"].upload(MissionType.MISSION, plan).ok
    start = d.MAVLink_command_long_message(1, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0)
    f.gcs("A").send(start)
    assert f.net.run_until(lambda: f.vehicle.flight.flying, timeout=2.0)
    return f


def north(f) -> float:
    p = f.vehicle.flight.where(f.net.clock.now())
    return haversine_m(HOME, GeoPoint(p.lat, p.lon))


def emergencies(f) -> list[EmergencyStarted]:
    return [e for e in f.vehicle.handover_events if isinstance(e, EmergencyStarted)]


def texts(gcs) -> list[tuple[int, str]]:
    return [(m.severity, m.text) for m in gcs.received if m._type == "STATUSTEXT"]


def land(f, limit: float = 400.0) -> None:
    assert f.net.run_until(lambda: not f.vehicle.flight.flying, timeout=limit)
    f.net.run_for(0.1)


# --- the commander falls silent -------------------------------------------------------------------
def test_a_silent_commander_starts_the_emergency_at_the_loss_timeout_announced_and_diverts_to_the_rally_point():
    f = launch()
    assert f.net.run_until(lambda: north(f) >= 500, timeout=60)
    f.gcs("B").received.clear()
    f.silence("A")
    silenced = f.net.clock.now()
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    (e,) = emergencies(f)
    (lost,) = [x for x in f.vehicle.control_events if isinstance(x, OwnerLost)]
    # exactly when the manager dropped A: its last HEARTBEAT (at most 1 s before the silence) + the timeout
    assert e.at == lost.at and e.at - lost.last_heard == pytest.approx(LOSS)
    assert silenced - 1.0 - 0.03 <= lost.last_heard <= silenced
    assert e.at - lost.last_heard <= LOSS + CHECK
    assert e.trigger.kind is TriggerKind.COMMANDER_LOST and e.commander == A
    assert f.vehicle.mission_computer.state is McState.ON_EMERGENCY and f.vehicle.owner == 0
    # the refuge: what choose_refuge says with the battery the flight has left there
    assert e.refuge == choose_refuge(e.position, LAUNCH, RALLY, BatteryState(e.battery_wh), MODEL)
    assert e.refuge.kind is RefugeKind.RALLY and e.refuge.rally_index == 0
    assert e.battery_wh == pytest.approx(100.0 - haversine_m(HOME, e.position) * MODEL.consumption_wh_per_m)
    # announced to the GCS that hears the vehicle: CONTROL_STATUS with no owner, STATUSTEXT naming both
    f.net.run_for(0.1)
    b = f.gcs("B")
    assert [m.gcs_main for m in b.received if m._type == "CONTROL_STATUS"][-1] == 0
    assert (d.MAV_SEVERITY_CRITICAL, f"Emergency: GCS {A} lost; rally 0 {e.refuge.distance_m:.0f} m") in texts(b)
    assert any(x.startswith("emergency: commander silent for 5.0 s") and "; rally point 0: " in x
               for x in f.vehicle.events)
    # straight there (the distance to R0 only shrinks), then down, then the flight ends
    left = []
    for _ in range(100):
        f.net.run_for(1.0)
        p = f.vehicle.flight.where(f.net.clock.now())
        left.append(haversine_m(R0, GeoPoint(p.lat, p.lon)))
        if not f.vehicle.flight.flying:
            break
    assert all(x >= y - 1e-6 for x, y in zip(left, left[1:])) and left[-1] < 1e-3
    land(f)
    assert f.vehicle.flight.position.alt == 0.0 and f.vehicle.flight.landed_at is not None
    assert f.vehicle.mission_computer.state is McState.ON_LOAD
    assert (d.MAV_SEVERITY_NOTICE, "Emergency: landed at the refuge") in texts(b)
    assert [x for x in f.vehicle.handover_events if isinstance(x, EmergencyEnded)][-1].owner == 0
    assert not [x for x in f.vehicle.handover_events if isinstance(x, HandoverStarted)]   # no handover meanwhile


@pytest.mark.parametrize("silent_at, battery_wh, kind", [
    (500.0, 100.0, RefugeKind.RALLY),        # plenty: the nearest refuge, rally point 0
    (500.0, 27.0, RefugeKind.LAND_HERE),     # about 100 m of range left at the trigger: R0 (~180 m) is out
    (50.0, 100.0, RefugeKind.HOME),          # near the start: home is the nearest refuge (RTL)
    (50.0, 21.0, RefugeKind.LAND_HERE),      # home ~150 m away, range ~ -50 m: land where it is
])
def test_the_refuge_is_what_choose_refuge_says_with_the_battery_drained_by_distance(silent_at, battery_wh, kind):
    f = launch(battery_wh=battery_wh)
    assert f.net.run_until(lambda: north(f) >= silent_at, timeout=60)
    f.silence("A")
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    (e,) = emergencies(f)
    flown = f.vehicle.flight.distance_flown(e.at)
    assert flown == pytest.approx(haversine_m(HOME, e.position), abs=1e-6)
    assert e.battery_wh == pytest.approx(max(0.0, battery_wh - flown * MODEL.consumption_wh_per_m))
    assert e.refuge == choose_refuge(e.position, LAUNCH, RALLY, BatteryState(e.battery_wh), MODEL)
    assert e.refuge.kind is kind
    severity = d.MAV_SEVERITY_EMERGENCY if kind is RefugeKind.LAND_HERE else d.MAV_SEVERITY_CRITICAL
    f.net.run_for(0.1)
    assert [s for s, t in texts(f.gcs("B")) if t.startswith("Emergency: GCS")] == [severity]
    land(f)
    end = f.vehicle.flight.position
    assert haversine_m(GeoPoint(end.lat, end.lon), e.refuge.point) < 1e-3    # landed where it decided
    if kind is RefugeKind.LAND_HERE:                                          # straight down: descent time only
        assert f.vehicle.flight.landed_at - e.at == pytest.approx(20.0 / DESCENT_SPEED, abs=0.1)


# --- outside every coverage -----------------------------------------------------------------------
def _first_outside(f, limit: float = 120.0, dt: float = 0.01) -> float:
    """Run in small steps until the vehicle is outside every coverage; the time it was first seen so."""
    cov = COVERAGES["polygon"].values()
    for _ in range(int(limit / dt)):
        p = f.vehicle.flight.where(f.net.clock.now())
        if not any(c.contains(GeoPoint(p.lat, p.lon)) for c in cov):
            return f.net.clock.now()
        f.net.run_for(dt)
    raise AssertionError("the vehicle never left the coverage")


def test_flying_out_of_every_coverage_starts_the_emergency_after_the_grace_and_revokes_control():
    grace = 2.0
    # a dogleg: north to 400 m, then east, out of A's 300 m half-width
    f = launch(plan=[item(0, 0), item(1, 400), item(2, 400, 900)], grace=grace)
    out_at = _first_outside(f)
    f.gcs("A").received.clear()
    assert f.net.run_until(lambda: emergencies(f), timeout=grace + 1)
    (e,) = emergencies(f)
    assert e.trigger.kind is TriggerKind.OUTSIDE_COVERAGE and e.commander == A
    assert out_at + grace - 0.02 <= e.at <= out_at + grace + 2 * CHECK     # after the grace, not before
    f.net.run_for(0.1)
    a = f.gcs("A")
    assert f.vehicle.owner == 0 and a.control.owner == 0 and not a.control.in_control
    assert [m.gcs_main for m in a.received if m._type == "CONTROL_STATUS"][-1] == 0
    assert any(t.startswith("Emergency: outside coverage; ") for _, t in texts(a))
    assert e.refuge == choose_refuge(e.position, LAUNCH, RALLY, BatteryState(e.battery_wh), MODEL)
    assert any(x.startswith("control: gcs_main 0 (was 201)") and "emergency: outside-coverage" in x
               for x in f.vehicle.events)


def test_a_short_excursion_out_of_coverage_within_the_grace_is_no_emergency():
    # out to 340 m east and straight back: about 4 s outside A's coverage, less than the grace
    f = launch(plan=[item(0, 0), item(1, 400), item(2, 400, 340), item(3, 400), item(4, 0)], grace=10.0)
    _first_outside(f)
    land(f)
    assert not emergencies(f) and f.vehicle.owner == A


def test_a_normal_handover_is_no_emergency_the_region_is_covered_by_both():
    """Grace 0: the first sample outside every coverage would fire. The delivery out and back
    never is: two completed handovers, no emergency."""
    f = launch(grace=0.0)
    land(f, limit=400.0)
    results = [x.result for x in f.vehicle.handover_events if isinstance(x, HandoverFinished)]
    assert [(r.commander, r.partner, r.outcome) for r in results] == [(A, B, Out.COMPLETED), (B, A, Out.COMPLETED)]
    assert not emergencies(f) and f.vehicle.owner == A


# --- who may command the refuge flight ------------------------------------------------------------
def test_no_gcs_command_moves_the_refuge_flight_even_with_the_filter_open():
    """`open_when_unowned`: the manager would take anyone's commands while nobody owns control;
    during the emergency the vehicle refuses them all the same."""
    f = launch(open_when_unowned=True, agents=False)
    assert f.net.run_until(lambda: north(f) >= 300, timeout=60)
    f.silence("A")
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    b, s = f.gcs("B"), f.sessions["B"]
    version, seq, target = f.vehicle.store.version, f.vehicle.server.progress.seq, f.vehicle.flight.divert_target
    b.received.clear()
    for cmd in (Cmd.MISSION_START, Cmd.DO_SET_MISSION_CURRENT):
        b.send(d.MAVLink_command_long_message(1, 1, cmd, 0, 1, 0, 0, 0, 0, 0, 0))
    b.send(d.MAVLink_mission_set_current_message(1, 1, 1))
    f.net.run_for(0.5)
    upload = s.upload(MissionType.MISSION, [item(0, 0), item(1, 100)])
    clear = s.clear(MissionType.MISSION)
    acks = [(m.command, m.result) for m in b.received if m._type == "COMMAND_ACK"]
    assert acks == [(Cmd.MISSION_START, d.MAV_RESULT_TEMPORARILY_REJECTED),
                    (Cmd.DO_SET_MISSION_CURRENT, d.MAV_RESULT_TEMPORARILY_REJECTED)]
    assert (d.MAV_SEVERITY_WARNING, "Set current refused: emergency") in texts(b)
    assert not upload.ok and upload.nack == MissionResult.DENIED
    assert not clear.ok and clear.nack == MissionResult.DENIED
    assert (f.vehicle.store.version, f.vehicle.server.progress.seq) == (version, seq)
    assert f.vehicle.flight.diverting and f.vehicle.flight.divert_target == target
    assert f.vehicle.mission_computer.state is McState.ON_EMERGENCY


def test_a_known_gcs_covering_the_vehicle_may_take_control_back_and_then_resumes_the_mission():
    """B's coverage does not hold the vehicle (at ~400 m north): refused, TEMPORARILY_REJECTED.
    A, heard again and covering it, is granted control: on_mission, the refuge flight goes on
    until A sends MISSION_START, then the mission resumes and hands over to B at the region."""
    f = launch()
    assert f.net.run_until(lambda: north(f) >= 300, timeout=60)
    f.silence("A")
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    refused = f.sessions["B"].request_control(wait=False)
    assert refused.outcome is O.REJECTED and refused.result == d.MAV_RESULT_TEMPORARILY_REJECTED
    assert f.vehicle.owner == 0 and f.vehicle.mission_computer.state is McState.ON_EMERGENCY
    f.net.connect("A", "vehicle", a_to_b=LATENCY, b_to_a=LATENCY.copy())
    f.net.run_for(1.5)
    assert not f.gcs("A").control.in_control                        # it heard CONTROL_STATUS: no owner
    assert f.sessions["A"].request_control().ok
    assert f.vehicle.owner == A and f.vehicle.mission_computer.state is McState.ON_MISSION
    (ended,) = [x for x in f.vehicle.handover_events if isinstance(x, EmergencyEnded)]
    assert ended.owner == A
    f.net.run_for(0.1)
    assert (d.MAV_SEVERITY_NOTICE, f"Emergency over: GCS {A} in control") in texts(f.gcs("B"))
    assert f.vehicle.flight.diverting                                 # taking control moves nothing
    f.gcs("A").send(d.MAVLink_command_long_message(1, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    assert f.net.run_until(lambda: not f.vehicle.flight.diverting, timeout=2.0)
    land(f)
    results = [x.result for x in f.vehicle.handover_events if isinstance(x, HandoverFinished)]
    assert [(r.commander, r.partner, r.outcome) for r in results] == [(A, B, Out.COMPLETED), (B, A, Out.COMPLETED)]
    assert len(emergencies(f)) == 1 and f.vehicle.owner == A


def test_without_takeback_nobody_gets_control_until_the_vehicle_has_landed():
    f = launch(takeback=False)
    assert f.net.run_until(lambda: north(f) >= 300, timeout=60)
    f.silence("A")
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    f.net.connect("A", "vehicle", a_to_b=LATENCY, b_to_a=LATENCY.copy())
    f.net.run_for(1.5)
    got = f.sessions["A"].request_control(wait=False)
    assert got.outcome is O.REJECTED and got.result == d.MAV_RESULT_TEMPORARILY_REJECTED
    land(f)
    assert f.vehicle.mission_computer.state is McState.ON_LOAD
    assert f.sessions["A"].request_control().ok                       # on the ground: the manager's rules again


def test_the_commander_lost_mid_handover_ends_it_and_the_waiting_partner_takes_control_back():
    """A falls silent as the handover starts: at the loss timeout the handover is ABORTED (the
    emergency's), the emergency starts; B, whose request waits and whose coverage holds the
    vehicle, is granted control when CONTROL_STATUS says nobody owns it: taken back."""
    f = launch()
    assert f.net.run_until(lambda: any(isinstance(x, HandoverStarted) for x in f.vehicle.handover_events),
                           timeout=80)
    f.silence("A")
    assert f.net.run_until(lambda: emergencies(f), timeout=LOSS + 2)
    (r,) = [x.result for x in f.vehicle.handover_events if isinstance(x, HandoverFinished)]
    assert r.outcome in (Out.ABORTED, Out.UNCONFIRMED) and r.detail.startswith("emergency: commander-lost")
    if r.outcome is Out.ABORTED:
        assert f.net.run_until(lambda: f.vehicle.owner == B, timeout=15.0)
        assert f.vehicle.mission_computer.state is McState.ON_MISSION
    assert len([x for x in f.vehicle.handover_events if isinstance(x, HandoverStarted)]) == 1


def test_off_by_default_an_owner_lost_in_flight_changes_nothing_else():
    f = launch(emergency=False)
    assert f.net.run_until(lambda: north(f) >= 300, timeout=60)
    f.silence("A")
    assert f.net.run_until(lambda: f.vehicle.owner == 0, timeout=LOSS + 2)
    f.net.run_for(5.0)
    assert not emergencies(f) and not f.vehicle.flight.diverting and f.vehicle.flight.flying
    assert f.vehicle.mission_computer.state is McState.ON_MISSION


# --- the table, sans-IO ---------------------------------------------------------------------------
def test_the_mission_computer_walks_every_emergency_transition():
    """on_mission -> EMERGENCY -> TAKEN_BACK -> (handover) -> EMERGENCY from on_handover -> LANDED."""
    cfg = MissionComputerConfig(parent=A, coverages=COVERAGES["polygon"], emergency=emergency_config(grace=1.0))
    mc = MissionComputer(1, 1, cfg, record_history=True)
    mc.control_changed(ControlChanged(A, 0, False, "t"), 0.0)
    mc.observe(at(0), 0.0)
    mc.start(0.0)
    mc.poll(0.0)
    mc.observe(at(300), 10.0)
    out = mc.owner_lost(OwnerLost(A, 5.0, 10.0), 10.0)
    (e,) = [x for x in out if isinstance(x, EmergencyStarted)]
    assert [type(x) for x in out] == [EmergencyStarted, type(out[1]), RevokeControl]
    assert e.refuge.kind is RefugeKind.HOME and mc.next_deadline() is None
    assert mc.screen(request(B)) is not None and mc.screen(request(A)) is None   # A covers 300 m; B does not
    mc.control_changed(ControlChanged(0, A, False, "lost"), 10.0)
    assert mc.state is McState.ON_EMERGENCY
    mc.control_changed(ControlChanged(A, 0, False, "granted"), 11.0)
    assert mc.state is McState.ON_MISSION and mc.emergency is None
    mc.poll(11.0)                                  # every region seen afresh, from 300 m north
    for t in range(12, 20):
        mc.observe(at(1000), float(t))
        mc.poll(float(t))
    assert mc.state is McState.ON_HANDOVER
    out = mc.owner_lost(OwnerLost(A, 15.0, 20.0), 20.0)
    (fin,) = [x for x in out if isinstance(x, HandoverFinished)]
    assert fin.result.outcome is Out.ABORTED and mc.state is McState.ON_EMERGENCY
    mc.stop(30.0)
    assert mc.state is McState.ON_LOAD
    moves = {(o, ev) for o, ev, _ in mc.history if isinstance(ev, McEvent)}
    assert set(EMERGENCY_TRANSITIONS) <= moves
    assert moves <= set(MC_TABLE) and not set(EMERGENCY_TRANSITIONS) & set(MC_TRANSITIONS)


def test_the_outside_trigger_waits_for_the_grace_and_restarts_on_return():
    cfg = MissionComputerConfig(parent=A, coverages=COVERAGES["polygon"], emergency=emergency_config(grace=1.0))
    mc = MissionComputer(1, 1, cfg)
    mc.control_changed(ControlChanged(A, 0, False, "t"), 0.0)
    mc.observe(at(0), 0.0)
    mc.start(0.0)

    def check(east: float) -> tuple[float, list]:
        t = mc.next_deadline()
        mc.observe(at(100, east), t)
        return t, mc.poll(t)
    first, _ = check(400)
    for _ in range(14):                             # 0.7 s outside A's 300 m half-width: less than the grace
        t, out = check(400)
        assert not out
    check(0)                                        # back inside: the grace starts again
    since, _ = check(400)
    for _ in range(100):
        t, out = check(400)
        if out:
            break
    (e,) = [x for x in out if isinstance(x, EmergencyStarted)]
    assert e.trigger.kind is TriggerKind.OUTSIDE_COVERAGE and e.trigger.due_at == pytest.approx(since + 1.0)
    assert since + 1.0 <= e.at < since + 1.0 + CHECK + 1e-9


def test_the_emergency_needs_one_loss_clock_and_a_policy():
    cfg = MissionComputerConfig(parent=A, coverages=COVERAGES["polygon"], emergency=emergency_config())
    with pytest.raises(ValueError, match="must be the system manager's owner_loss_timeout"):
        VehicleNode(VehicleConfig(control=ManagerConfig(owner_loss_timeout=3.0), handover=cfg))
    with pytest.raises(TypeError, match="policy must be a TriggerPolicy"):
        EmergencyConfig(5.0)
    with pytest.raises(TypeError, match=r"rally\[0\] must be a GeoPoint"):
        EmergencyConfig(TriggerPolicy(5.0), ((47.0, 8.0),))


def test_revoking_drops_the_owner_with_control_status_and_is_a_no_op_unowned():
    m = ControlManager(1, 1)
    assert revoke_owner(m, "x", 0.0) == []
    m.handle(request(A), 0.0)
    out = revoke_owner(m, "emergency: outside-coverage", 1.0)
    assert m.owner == 0 and [type(x).__name__ for x in out] == ["Send", "ControlChanged"]
    assert out[0].msg.gcs_main == 0 and out[1].reason == "emergency: outside-coverage"


# --- the flight model: divert and battery ---------------------------------------------------------
def _flight(battery: FlightBattery | None = None) -> FlightSim:
    store = MissionStore()
    store.commit(MissionType.MISSION, (item(0, 0), item(1, 1000)))
    home = Position(float(HOME.lat), float(HOME.lon), 0.0)
    return FlightSim(store, MissionProgress(store, 1.0), home=home, speed=10.0, battery=battery)


def test_divert_flies_straight_at_cruise_then_descends_and_land_here_only_descends():
    f = _flight(FlightBattery(MODEL, BatteryState(50.0)))
    f.start(0.0)
    f.poll(2.0)                                            # item 0 (20 m above home) reached: on north
    assert f.flying
    here = f.where(30.1)                                   # about 280 m north, 20 m up
    target = at(300, 400)                                  # 400 m east of it
    f.divert(Position(float(target.lat), float(target.lon), 0.0), 30.1)
    assert f.flying and f.diverting and not f.progress.running
    arrive = 30.1 + haversine_m(GeoPoint(here.lat, here.lon), target) / 10.0
    assert f.next_deadline() == pytest.approx(arrive)
    f.retarget(35.0)                                       # a set-current: the divert goes on
    assert f.next_deadline() == pytest.approx(arrive)
    f.poll(arrive)
    p = f.where(arrive)
    assert (p.lat, p.lon, p.alt) == pytest.approx((target.lat, target.lon, here.alt))
    landing = arrive + here.alt / DESCENT_SPEED
    f.poll(landing)
    assert not f.flying and f.landed_at == pytest.approx(landing) and f.position.alt == 0.0
    flown = haversine_m(LAUNCH, GeoPoint(here.lat, here.lon)) + haversine_m(GeoPoint(here.lat, here.lon), target)
    assert f.distance_flown(landing) == pytest.approx(flown, rel=1e-6)
    assert f.battery_at(landing).remaining_wh == pytest.approx(50.0 - flown * 0.01, rel=1e-6)


def test_mission_start_ends_a_divert_and_resumes_from_where_the_vehicle_is():
    f = _flight()
    f.start(0.0)
    f.poll(2.0)
    f.divert(Position(float(HOME.lat), float(HOME.lon), 0.0), 20.1, land=False)
    f.poll(100.0)
    assert f.flying and f.diverting and f.next_deadline() is None    # holding at home
    assert f.battery_at(100.0) is None
    f.start(100.0)
    assert not f.diverting and f.progress.running
    assert f.next_deadline() == pytest.approx(100.0 + 1000.0 / 10.0, rel=1e-3)
