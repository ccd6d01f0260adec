"""The reference vehicle and the reference GCS on one in-memory network, in virtual time.

Most engine-level tests start from this pair; one builder keeps them alike (the vehicle's
wall clock is the network's, so a seed repeats exactly).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from mavconform.reference_impl.gcs import GcsNode
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
