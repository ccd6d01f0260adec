"""The reference vehicle and the reference GCS on one in-memory network, in virtual time.

Most engine-level tests start from this pair; one builder keeps them alike (the vehicle's
wall clock is the network's, so a seed repeats exactly).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover.control_client import Policy
from mavconform.reference_impl.handover.gcs_handover import HandoverAgent
from mavconform.reference_impl.net import FaultModel, SimNetwork
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode


@dataclass
class Rig:
    net: SimNetwork
    vehicle: VehicleNode
    gcs: GcsNode
    session: GcsSession


def vehicle_and_gcs(vehicle: VehicleConfig | Callable[[Callable[[], float]], VehicleNode] | None = None, *,
                    seed: int = 0, up: FaultModel | None = None, down: FaultModel | None = None,
                    discovery: float = 5.0) -> Rig:
    """A vehicle (a config, or a builder given the network's wall clock) linked to a GCS
    that has heard its HEARTBEAT; `up`/`down` are the link's faults (GCS to vehicle, back)."""
    net = SimNetwork(seed=seed)
    node = vehicle(net.clock.wall) if callable(vehicle) else VehicleNode(vehicle, wall_clock=net.clock.wall)
    gcs = GcsNode(remote="vehicle", wall_clock=net.clock.wall)
    net.add_node("vehicle", node)
    net.add_node("gcs", gcs)
    net.connect("gcs", "vehicle", a_to_b=up, b_to_a=down)
    session = GcsSession(net, gcs)
    session.wait_for_target(discovery)
    return Rig(net, node, gcs, session)


@dataclass
class Fleet:
    """One vehicle and several GCSs, each on its own link (see `vehicle_and_gcss`)."""

    net: SimNetwork
    vehicle: VehicleNode
    sessions: dict[str, GcsSession]

    def gcs(self, name: str) -> GcsNode:
        return self.sessions[name].gcs

    def silence(self, name: str) -> None:
        """Cut GCS `name`'s link both ways (its HEARTBEATs stop reaching the vehicle)."""
        gone = FaultModel(loss=1.0)
        self.net.connect(name, "vehicle", a_to_b=gone, b_to_a=gone.copy())


def vehicle_and_gcss(vehicle: VehicleConfig | None, gcss: dict[str, GcsConfig], *,
                     policies: dict[str, Policy] | None = None, link: FaultModel | None = None,
                     seed: int = 0, discovery: float = 5.0,
                     handovers: dict[str, HandoverAgent] | None = None) -> Fleet:
    """A vehicle and one GCS per entry of `gcss` (name -> config; `policies` answers
    forwarded requests for control; `handovers` gives a GCS a handover agent, whose policy
    then answers them; `link` is every link's faults, both ways), every GCS having heard the
    vehicle's HEARTBEAT."""
    net = SimNetwork(seed=seed)
    node = VehicleNode(vehicle, wall_clock=net.clock.wall)
    net.add_node("vehicle", node)
    sessions = {}
    for name, config in gcss.items():
        policy = (policies or {}).get(name)
        gcs = GcsNode(config, remote="vehicle", wall_clock=net.clock.wall,
                      **({"control_policy": policy} if policy is not None else {}),
                      handover=(handovers or {}).get(name))
        net.add_node(name, gcs)
        net.connect(name, "vehicle", a_to_b=link, b_to_a=link.copy() if link is not None else None)
        sessions[name] = GcsSession(net, gcs)
    for session in sessions.values():
        session.wait_for_target(discovery)
    return Fleet(net, node, sessions)
