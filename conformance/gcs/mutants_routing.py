"""Mutant reference GCSs that break the addressing clauses (MIS.G.RT.*); see mutants.py.

Each changes what the reference GCS takes as addressed to it (`MissionClient._addressed_to_us`)
or where it sends (the peer its mission engine addresses), the bugs of ground stations that
were tried against the suite: an ACK for another GCS taken as their own, and every message
sent to component 0.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.net.node import Address

from .mutants import _MutantGcs, client_mutant, gcs_mutant


class _AckToAnySystem(MissionClient):
    """Compares a MISSION_ACK's target_component only."""

    def _addressed_to_us(self, msg: Any) -> bool:
        if msg._type == "MISSION_ACK":
            return msg.target_component in (0, self.component)
        return super()._addressed_to_us(msg)


class _AckToAnyComponent(MissionClient):
    """Compares a MISSION_ACK's target_system only (this reference GCS did, once)."""

    def _addressed_to_us(self, msg: Any) -> bool:
        if msg._type == "MISSION_ACK":
            return msg.target_system in (0, self.system)
        return super()._addressed_to_us(msg)


class _BroadcastComponentGcs(_MutantGcs):
    """The reference GCS whose mission engine addresses the vehicle's system, component 0."""

    def _make_client(self) -> None:
        super()._make_client()
        self.client.target = (self.target[0], 0)


def _broadcast_component(base: GcsConfig, vehicle: Address) -> GcsNode:
    return _BroadcastComponentGcs(base, vehicle, MissionClient)


gcs_mutant("ack-to-any-system", "takes a MISSION_ACK addressed to another system as its own (checks the "
           "component only)", {"MIS.G.RT.01"}, client_mutant(_AckToAnySystem))
gcs_mutant("ack-to-any-component", "takes a MISSION_ACK addressed to another component of its system as its "
           "own (checks the system only)", {"MIS.G.RT.02"}, client_mutant(_AckToAnyComponent))
gcs_mutant("broadcast-component", "addresses every mission message to component 0 (broadcast), not to the "
           "vehicle's component from its HEARTBEAT", {"MIS.G.RT.03"}, _broadcast_component)
