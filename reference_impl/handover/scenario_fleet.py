"""A scenario's vehicle and ground stations, as engine configs and nodes (seed 003, 4.3.1).

The scenario file says what the thesis's mission computer was loaded with; this module turns
it into what our engines take, in one place, so `mavconform handover run` (virtual time, every
GCS simulated) and `mavconform vehicle --handover` (real UDP, real GCSs) configure the vehicle
alike:

- the vehicle: its system manager (owner loss = `timeouts.loss_timeout_s`), the mission
  computer (parent, every GCS's coverage, `dwell_s`, `handover_bound_s`, the acceptance
  radius), the roster of the GCSs' signing keys, home and cruise speed;
- each GCS: its system id and key, an operator-control client and a handover agent that
  knows every coverage (the thesis shares it as the "Mission" message);
- the flight as mission items: a `path` as NAV_WAYPOINTs at relative altitude, seq = index,
  so the waypoint method's seqs are the items'; a `.plan` flight as the plan's own mission.

Signing is all or nothing: a roster with some GCSs unsigned would keep those out of control
for good (a system not in the roster never gains it), which no scenario means.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

from ..flight import FlightBattery, Position
from ..gcs import GcsConfig, GcsNode
from ..mission.constants import Cmd
from ..mission.items import MissionItem, MissionType
from ..net import SimNetwork
from ..session import GcsSession
from ..vehicle import VehicleConfig, VehicleNode
from ..wire.dialect import mavlink as _d
from .authenticity import KnownGcs, Roster
from .control_client import ClientConfig
from .control_manager import ManagerConfig
from .emergency_procedure import EmergencyConfig
from .gcs_handover import GcsHandoverConfig, HandoverAgent
from .geo import GeoPoint
from .mission_computer import MissionComputerConfig
from .scenario import GcsSpec, Scenario, ScenarioError

__all__ = ["VEHICLE", "ScenarioFleet", "build_fleet", "flight_items", "gcs_address", "gcs_config",
           "handover_agent", "mission_computer_config", "roster_of", "vehicle_config"]

VEHICLE = "vehicle"                 # the vehicle's node name on the simulated network
FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT   # path altitudes are metres above home


def roster_of(s: Scenario) -> Roster | None:
    """Every GCS's key (None when no GCS signs); a ScenarioError when only some do."""
    signed = [g for g in s.gcs if g.signing is not None]
    if not signed:
        return None
    if len(signed) != len(s.gcs):
        index, unsigned = next((i, g) for i, g in enumerate(s.gcs) if g.signing is None)
        raise ScenarioError(f"{s.source or 'scenario'}: gcs[{index}].signing: missing for {unsigned.name!r}, "
                            f"while {signed[0].name!r} signs: give every GCS a key, or none (the vehicle "
                            f"drops unsigned frames once it knows keys)")
    return Roster(tuple(KnownGcs(g.sysid, g.signing, g.name) for g in s.gcs))  # type: ignore[arg-type]


def mission_computer_config(s: Scenario) -> MissionComputerConfig:
    """The mission computer's load (4.3.1): parent, coverages by system id, the scenario's clock,
    and the emergency procedure (triggers, home, rally points)."""
    return MissionComputerConfig(parent=s.gcs_named(s.parent).sysid,
                                 coverages={g.sysid: g.coverage for g in s.gcs},
                                 dwell=s.timeouts.dwell_s, bound=s.timeouts.handover_bound_s,
                                 acceptance_radius_m=s.flight.acceptance_radius_m,
                                 emergency=EmergencyConfig(policy=s.timeouts.triggers(), rally=s.rally,
                                                           home=GeoPoint(s.home.lat, s.home.lon)))


def vehicle_config(s: Scenario) -> VehicleConfig:
    """The vehicle: system manager, mission computer, roster (signatures required), home, speed,
    and the scenario's battery."""
    roster = roster_of(s)
    # Home altitude 0: the flight model flies the items' z as given, and a path's are above home.
    return VehicleConfig(system=s.vehicle_sysid, home=Position(s.home.lat, s.home.lon, 0.0),
                         speed=s.flight.speed_m_s,
                         control=ManagerConfig(owner_loss_timeout=s.timeouts.loss_timeout_s),
                         handover=mission_computer_config(s), roster=roster,
                         require_signature=roster is not None,
                         battery=FlightBattery(s.battery, s.initial_battery))


def gcs_config(s: Scenario, g: GcsSpec) -> GcsConfig:
    return GcsConfig(system=g.sysid, signing=g.signing, control=ClientConfig())


def handover_agent(s: Scenario, g: GcsSpec) -> HandoverAgent:
    return HandoverAgent(g.sysid, GcsHandoverConfig({x.sysid: x.coverage for x in s.gcs}))


def flight_items(s: Scenario) -> list[MissionItem]:
    """The flight as the mission the parent uploads. A .plan's own mission, with each item the
    scenario flies to put where the scenario reads it (altitude above home, a RETURN_TO_LAUNCH as
    a waypoint at home: our flight model flies positions only), so the seqs stay the plan's."""
    if s.flight.plan is not None:
        from ..files import load_plan
        base = Path(s.source).parent if s.source else Path(".")
        points = {w.seq: w.point for w in s.flight.waypoints}
        items = []
        for item in load_plan(base / s.flight.plan).mission:
            p = points.get(item.seq)
            if p is not None:
                command = Cmd.NAV_WAYPOINT if item.command == Cmd.NAV_RETURN_TO_LAUNCH else item.command
                item = replace(item, frame=FRAME_GLOBAL_RELATIVE_ALT, command=int(command), x=round(p.lat * 1e7),
                               y=round(p.lon * 1e7), z=float(p.alt or 0.0))
            items.append(item)
        return items
    return [MissionItem(w.seq, FRAME_GLOBAL_RELATIVE_ALT, int(Cmd.NAV_WAYPOINT), x=round(w.point.lat * 1e7),
                        y=round(w.point.lon * 1e7), z=float(w.point.alt or 0.0), mission_type=MissionType.MISSION)
            for w in s.flight.waypoints]


def gcs_address(g: GcsSpec) -> str:
    """A GCS's node name: its scenario name (so captures read "A -> vehicle")."""
    return g.name if g.name != VEHICLE else f"GCS {g.name}"


@dataclass
class ScenarioFleet:
    """The scenario's nodes on one simulated network, each GCS with a blocking session."""

    scenario: Scenario
    net: SimNetwork
    vehicle: VehicleNode
    sessions: dict[str, GcsSession]       # by GCS name, in scenario order

    def gcs(self, name: str) -> GcsNode:
        return self.sessions[name].gcs


def build_fleet(s: Scenario, *, seed: int | None = None,
                node_of: Callable[[VehicleNode], Any] | None = None) -> ScenarioFleet:
    """The vehicle and one GCS per scenario GCS, each on its own link with the scenario's faults
    (fresh models: rule counters never carry over); nothing has run yet (virtual time 0).
    `node_of(vehicle)`: the node the network runs in the vehicle's place (a wrapper that watches it)."""
    net = SimNetwork(seed=s.seed if seed is None else seed)
    vehicle = VehicleNode(vehicle_config(s), wall_clock=net.clock.wall)
    net.add_node(VEHICLE, node_of(vehicle) if node_of is not None else vehicle)
    sessions: dict[str, GcsSession] = {}
    for g in s.gcs:
        node = GcsNode(gcs_config(s, g), remote=VEHICLE, wall_clock=net.clock.wall, handover=handover_agent(s, g))
        net.add_node(gcs_address(g), node)
        net.connect(gcs_address(g), VEHICLE, a_to_b=g.up.model(), b_to_a=g.down.model())
        sessions[g.name] = GcsSession(net, node)
    return ScenarioFleet(s, net, vehicle, sessions)
