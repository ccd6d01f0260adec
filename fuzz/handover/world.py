"""A whole delivery flight under faults: the vehicle, its GCSs, their links and behaviours.

A `FlightCase` is data (so Hypothesis can draw and shrink it, and a finding prints as the
case that broke a property): a shipped scenario (reference_impl/handover/scenarios/, its
geography, rally points, battery and timeouts), the seed, the handover bound, a fault model
per link direction, and a behaviour per GCS. `fly(case)` builds the world in virtual time,
sets it up on clean links (the parent takes control, uploads the route, starts the mission),
then turns the faults on and runs until the vehicle is back on the ground (landed at the end
of its route or at a refuge) or the scenario's `max_duration_s` passes, with a `Judge`
(properties.py) watching every step of every node.

GCS behaviours (`Behaviour.kind`):
- `agent`: the reference handover agent (gcs_handover.HandoverAgent): invited, it requests
  control; as commander it allows a partner's request its telemetry expects.
- `refuses`: an agent whose telemetry never expects a handover: it refuses every forward.
- `plain`: a GCS with no agent: it never answers a forward nor an invitation.
- `slow`: an agent whose operator answers forwards `answer_delay` seconds late.
- `releases`: an agent that answers an expected forward by releasing control ("may choose
  to release control"), so steps 3 and 6 are one and control is free for a moment.
Independently, `meddle` lists (time, action, seq): the GCS, when it believes another GCS
commands, sends MISSION_START, a set-current (command or message) or a mission upload, as an
operator who has not noticed it lost control would. `Behaviour.silent` windows cut its link
both ways (the GCS falls silent: owner loss, the emergency). With `retake`, an operator who
sees the vehicle uncontrolled (CONTROL_STATUS gcs_main 0) asks for control, and once granted
resumes the mission (MAV_CMD_MISSION_START): the emergency's takeback, tried from wherever
the vehicle is.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Callable

from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover.control_client import always
from mavconform.reference_impl.handover.control_manager import ControlManager
from mavconform.reference_impl.handover.control_results import Decision, TakeoverRequested
from mavconform.reference_impl.handover.gcs_handover import GcsHandoverConfig, HandoverAgent
from mavconform.reference_impl.handover.mission_computer import MissionComputer
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, Scenario, load_scenario
from mavconform.reference_impl.handover.scenario_fleet import (flight_items, gcs_config, mission_computer_config,
                                                              vehicle_config)
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.net import FaultModel, SimNetwork
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.dialect import mavlink as _d

__all__ = ["Behaviour", "FlightCase", "Link", "SCENARIOS", "World", "build", "fly", "scenario_configs", "vehicle_with"]

# the geographic delivery scenarios (the waypoint method has no region to leave or enter)
SCENARIOS = ("delivery_flight.json", "delivery_flight_circles.json")
SETUP_DELAY = 0.01         # s: one-way latency of every link while the flight is set up
SETUP_LATENCY = FaultModel(delay=SETUP_DELAY)
STEP = 0.5                 # s: the driver loop's step (meddling and late answers fire on it)
MAX_STEPS = 20_000         # the driver loop's bound (a 1160 s scenario needs 2 320)
BEHAVIOURS = ("agent", "refuses", "plain", "slow", "releases")
MEDDLES = ("start", "set_current_cmd", "set_current_msg", "upload")


@dataclass(frozen=True)
class Link:
    """One direction of a GCS's link (FaultModel's fields; partitions relative to take-off)."""

    loss: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    reorder_delay: float = 0.05
    delay: float = 0.01
    jitter: float = 0.0
    partitions: tuple[tuple[float, float], ...] = ()

    @property
    def worst_delay(self) -> float:
        """The longest a datagram that gets through can take (duplicates included)."""
        return self.delay + self.jitter + (self.reorder_delay if self.reorder else 0.0)

    def model(self, offset: float) -> FaultModel:
        return FaultModel(loss=self.loss, duplicate=self.duplicate, reorder=self.reorder,
                          reorder_delay=self.reorder_delay, delay=self.delay, jitter=self.jitter,
                          partitions=tuple((offset + a, offset + b) for a, b in self.partitions))


@dataclass(frozen=True)
class Behaviour:
    kind: str = "agent"
    answer_delay: float = 0.0                               # `slow`: s before the operator answers
    silent: tuple[tuple[float, float], ...] = ()            # windows (from take-off) with the link cut
    meddle: tuple[tuple[float, str, int], ...] = ()         # (time from take-off, MEDDLES entry, item seq)
    retake: bool = False                                    # ask for control of an uncontrolled vehicle


@dataclass(frozen=True)
class FlightCase:
    scenario: str = SCENARIOS[0]
    seed: int = 0
    bound: float | None = None                   # None: the scenario's handover_bound_s
    links: tuple[tuple[str, Link, Link], ...] = ()   # (GCS name, up, down); absent: clean (10 ms)
    behaviours: tuple[tuple[str, Behaviour], ...] = ()
    max_duration: float | None = None            # None: the scenario's max_duration_s

    def link(self, name: str) -> tuple[Link, Link]:
        for n, up, down in self.links:
            if n == name:
                return up, down
        return Link(), Link()

    def behaviour(self, name: str) -> Behaviour:
        return dict(self.behaviours).get(name, Behaviour())


def scenario_configs(s: Scenario, *, bound: float | None = None, emergency: bool = True
                     ) -> tuple[VehicleConfig, dict[str, GcsConfig], dict[int, Any]]:
    """The vehicle and GCS configs a scenario file describes, as the scenario runner builds
    them (scenario_fleet), unsigned: signing is not what these properties are about. `bound`
    overrides the scenario's handover bound; `emergency=False` turns the procedure off."""
    base = mission_computer_config(s)
    mc = replace(base, bound=bound or base.bound, emergency=base.emergency if emergency else None)
    vehicle = replace(vehicle_config(s), handover=mc, roster=None, require_signature=False)
    gcss = {g.name: replace(gcs_config(s, g), signing=None) for g in s.gcs}
    return vehicle, gcss, {g.sysid: g.coverage for g in s.gcs}


@dataclass
class World:
    """A built flight: the network, the vehicle, the GCSs by name, and the judge's probes."""

    case: FlightCase
    scenario: Scenario
    net: SimNetwork
    vehicle: VehicleNode
    gcs: dict[str, GcsNode]
    sysids: dict[str, int]
    judge: Any
    takeoff: float = 0.0
    late_answers: list[tuple[float, str, Decision]] = field(default_factory=list)
    resumed: set[str] = field(default_factory=set)     # retaking GCSs that sent MISSION_START since their grant
    setup_failed: str = ""


class _SlowOperator:
    """The agent decides at once, its operator answers `delay` seconds later."""

    def __init__(self, world: World, name: str, agent: HandoverAgent, delay: float) -> None:
        self.world, self.name, self.agent, self.delay = world, name, agent, delay

    def __call__(self, request: TakeoverRequested) -> Decision | None:
        decision = self.agent.policy(request)
        if decision is not None and decision is not Decision.REFUSE:
            self.world.late_answers.append((request.at + self.delay, self.name, decision))
        return None


def _releasing(agent: HandoverAgent) -> Callable[[TakeoverRequested], Decision | None]:
    def policy(request: TakeoverRequested) -> Decision | None:
        decision = agent.policy(request)
        return Decision.RELEASE if decision is Decision.ALLOW else decision
    return policy


def build(case: FlightCase, *, judge_factory: Callable[..., Any],
          vehicle_factory: Callable[[VehicleConfig, Callable[[], float]], VehicleNode] | None = None) -> World:
    """The world for `case`, set up and flying (faults not yet on: `fly` turns them on)."""
    s = load_scenario(SCENARIOS_DIR / case.scenario)
    vcfg, gcfgs, coverages = scenario_configs(s, bound=case.bound)
    net = SimNetwork(seed=case.seed)
    vehicle = (vehicle_factory or (lambda c, wall: VehicleNode(c, wall_clock=wall)))(vcfg, net.clock.wall)
    sysids = {g.name: g.sysid for g in s.gcs}
    gcss: dict[str, GcsNode] = {}
    for g in s.gcs:
        kind = case.behaviour(g.name).kind
        agent = None
        if kind != "plain":
            max_age = 0.0 if kind == "refuses" else 5.0
            agent = HandoverAgent(g.sysid, GcsHandoverConfig(coverages, telemetry_max_age=max_age))
        gcss[g.name] = GcsNode(gcfgs[g.name], remote="vehicle", wall_clock=net.clock.wall,
                               control_policy=always(None), handover=agent)
    judge = judge_factory(s, vehicle, gcss, sysids, case)
    net.add_node("vehicle", judge.vehicle_probe)
    for name, node in gcss.items():
        net.add_node(name, judge.gcs_probe(name))
        net.connect(name, "vehicle", a_to_b=SETUP_LATENCY, b_to_a=SETUP_LATENCY.copy())
    world = World(case, s, net, vehicle, gcss, sysids, judge)
    sessions = {n: GcsSession(net, node) for n, node in gcss.items()}
    for sess in sessions.values():
        sess.wait_for_target(10.0)
    for name, node in gcss.items():
        b = case.behaviour(name)
        if b.kind == "slow" and node.handover is not None:
            node.control.policy = _SlowOperator(world, name, node.handover, b.answer_delay)
        elif b.kind == "releases" and node.handover is not None:
            node.control.policy = _releasing(node.handover)
    parent = sessions[s.parent]
    if not parent.request_control().ok:
        world.setup_failed = "the parent was not granted control"
        return world
    if not parent.upload(MissionType.MISSION, flight_items(s)).ok:
        world.setup_failed = "the route was not uploaded"
        return world
    gcss[s.parent].send(_d.MAVLink_command_long_message(vcfg.system, vcfg.component, Cmd.MISSION_START,
                                                       0, 0, 0, 0, 0, 0, 0, 0))
    if not net.run_until(lambda: vehicle.flight.flying, timeout=2.0):
        world.setup_failed = "the mission did not start"
        return world
    world.takeoff = net.clock.now()
    for name in gcss:
        up, down = case.link(name)
        windows = case.behaviour(name).silent
        up_m, down_m = up.model(world.takeoff), down.model(world.takeoff)
        if windows:
            shifted = tuple((world.takeoff + a, world.takeoff + b) for a, b in windows)
            up_m = replace(up_m, partitions=up_m.partitions + shifted)
            down_m = replace(down_m, partitions=down_m.partitions + shifted)
        net.connect(name, "vehicle", a_to_b=up_m, b_to_a=down_m)
    judge.take_off(world)
    return world


def _meddle(world: World, name: str, action: str, seq: int) -> None:
    """GCS `name` commands as if it were in control, when it believes another GCS is."""
    gcs = world.gcs[name]
    client = gcs.control
    if client is None or client.owner in (0, gcs.config.system):
        return
    v = world.vehicle.config
    now = world.net.clock.now()
    if action == "start":
        gcs.send(_d.MAVLink_command_long_message(v.system, v.component, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    elif action == "set_current_cmd":
        gcs.send(_d.MAVLink_command_long_message(v.system, v.component, Cmd.DO_SET_MISSION_CURRENT, 0,
                                                 seq, 0, 0, 0, 0, 0, 0))
    elif action == "set_current_msg":
        gcs.send(_d.MAVLink_mission_set_current_message(v.system, v.component, seq))
    elif action == "upload" and not gcs.busy:
        gcs.upload(MissionType.MISSION, flight_items(world.scenario)[:2], now)


def _retake(world: World, name: str) -> None:
    """An operator's answer to an uncontrolled vehicle: ask for control; once granted, resume."""
    gcs = world.gcs[name]
    client = gcs.control
    if client is None or client.busy:
        return
    now = world.net.clock.now()
    if client.in_control:
        if name in world.resumed:
            return
        world.resumed.add(name)
        v = world.vehicle.config
        gcs.send(_d.MAVLink_command_long_message(v.system, v.component, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    elif client.owner == 0:
        world.resumed.discard(name)
        gcs.request_control(now, wait=False)


def fly(case: FlightCase, *, judge_factory: Callable[..., Any],
        vehicle_factory: Callable[[VehicleConfig, Callable[[], float]], VehicleNode] | None = None) -> World:
    """Build and fly `case` to the end; the judge has watched every step."""
    world = build(case, judge_factory=judge_factory, vehicle_factory=vehicle_factory)
    if world.setup_failed:
        return world
    net, vehicle = world.net, world.vehicle
    limit = world.takeoff + (case.max_duration or world.scenario.timeouts.max_duration_s)
    meddles = sorted((world.takeoff + t, name, what, seq) for name, b in case.behaviours for t, what, seq in b.meddle)
    mc = vehicle.mission_computer
    retakers = [name for name, b in case.behaviours if b.retake]
    world.resumed = set(world.gcs)          # nothing to resume before an emergency
    for _ in range(MAX_STEPS):
        now = net.clock.now()
        if now >= limit or (not vehicle.flight.flying and mc.state.value == "on_load"):
            break
        while meddles and meddles[0][0] <= now:
            _, name, what, seq = meddles.pop(0)
            _meddle(world, name, what, seq)
        for name in retakers:
            _retake(world, name)
        due = [x for x in world.late_answers if x[0] <= now]
        for x in due:
            world.late_answers.remove(x)
            world.gcs[x[1]].answer_takeover(x[2], now)
        net.run_for(min(STEP, limit - now))
    world.judge.finish(world)
    return world


def vehicle_with(*, mission_computer: type[MissionComputer] | None = None,
                 manager: type[ControlManager] | None = None
                 ) -> Callable[[VehicleConfig, Callable[[], float]], VehicleNode]:
    """A vehicle factory for `build`: the reference vehicle with its mission computer and/or
    system manager replaced by an instance of the given class (the broken variants)."""
    def make(config: VehicleConfig, wall: Callable[[], float]) -> VehicleNode:
        node = VehicleNode(config, wall_clock=wall, **({"manager_class": manager} if manager else {}))
        if mission_computer is not None:
            old = node.mission_computer
            node.mission_computer = mission_computer(old.system, old.component, old.config)
        return node
    return make
