"""Mutant reference vehicles: each breaks named clauses, to prove the suite can fail.

A mutant is the spec vehicle with one behaviour changed, usually by overriding one method
of `MissionServer` or turning one `ServerBehaviour` knob. `breaks` lists every clause the
change is meant to break; the negative-control tests assert that each such clause fails on
the mutant, that no other clause does, and that every clause is broken by some mutant.
Mutants are also targets (`mutant:NAME`), so a user can see what a failing report looks like.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable

from mavconform.reference_impl.mission.behaviour import ServerBehaviour
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

from ..registry import import_submodules


@dataclass(frozen=True)
class Mutant:
    name: str
    description: str
    breaks: frozenset[str]
    build: Callable[[VehicleConfig], VehicleNode]


MUTANTS: dict[str, Mutant] = {}


def mutant(name: str, description: str, breaks: set[str] | frozenset[str],
           build: Callable[[VehicleConfig], VehicleNode]) -> Mutant:
    if name in MUTANTS:
        raise ValueError(f"duplicate mutant {name!r}")
    made = Mutant(name, description, frozenset(breaks), build)
    MUTANTS[name] = made
    return made


def server_mutant(server_cls: type[MissionServer], **knobs: Any) -> Callable[[VehicleConfig], VehicleNode]:
    """A builder for a vehicle whose mission server is `server_cls` (and knobs changed)."""
    def build(config: VehicleConfig) -> VehicleNode:
        if knobs:
            config = dataclasses.replace(config, behaviour=dataclasses.replace(config.behaviour, **knobs))
        return VehicleNode(config, server_class=server_cls)
    return build


def knob_mutant(**knobs: Any) -> Callable[[VehicleConfig], VehicleNode]:
    """A builder for a vehicle with `ServerBehaviour` knobs changed."""
    return server_mutant(MissionServer, **knobs)


def vehicle_mutant(vehicle_cls: type[VehicleNode], **config: Any) -> Callable[[VehicleConfig], VehicleNode]:
    def build(base: VehicleConfig) -> VehicleNode:
        return vehicle_cls(dataclasses.replace(base, **config) if config else base)
    return build


import_submodules(__path__, __name__)

__all__ = ["MUTANTS", "Mutant", "mutant", "server_mutant", "knob_mutant", "vehicle_mutant",
           "ServerBehaviour"]
