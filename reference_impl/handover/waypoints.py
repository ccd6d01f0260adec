"""Waypoint ownership: the thesis's second region method (seed 003, 4.6.2).

No geography: the mission planner assigns each waypoint to a GCS. The mission computer
decides a waypoint is reached when the vehicle comes within an acceptance radius of it
(haversine), and the leg the vehicle then flies - from that waypoint to the next - belongs to
the reached waypoint's GCS. Handover is due when that GCS is not the commander. A waypoint
nobody owns has no owner (`None`): the scenario decides what that means, nothing is guessed
from its neighbours.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType
from typing import Mapping

from .geo import GeoPoint, haversine_m

SEQ_MAX = 65535   # mission item seq is a uint16 on the wire


def _check_seq(seq: object) -> int:
    if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq <= SEQ_MAX:
        raise ValueError(f"waypoint seq must be an int in [0, {SEQ_MAX}], got {seq!r}")
    return seq


@dataclass(frozen=True)
class OwnedWaypoints:
    """One GCS's coverage under the waypoint method: the mission seqs it owns."""

    seqs: frozenset[int]

    def __post_init__(self) -> None:
        seqs = frozenset(_check_seq(s) for s in self.seqs)
        if not seqs:
            raise ValueError("a GCS must own at least one waypoint")
        object.__setattr__(self, "seqs", seqs)

    def owns(self, seq: int) -> bool:
        return seq in self.seqs


@dataclass(frozen=True)
class WaypointOwnership:
    """Which GCS owns each waypoint (mission seq -> GCS id), hence the leg that starts there."""

    assignments: Mapping[int, str]

    def __post_init__(self) -> None:
        checked: dict[int, str] = {}
        for seq, gcs in self.assignments.items():
            if not isinstance(gcs, str) or not gcs:
                raise ValueError(f"waypoint {seq}: GCS id must be a non-empty string, got {gcs!r}")
            checked[_check_seq(seq)] = gcs
        object.__setattr__(self, "assignments", MappingProxyType(dict(sorted(checked.items()))))

    def __hash__(self) -> int:
        return hash(tuple(self.assignments.items()))

    @classmethod
    def from_coverages(cls, coverages: Mapping[str, OwnedWaypoints]) -> WaypointOwnership:
        """Join the per-GCS coverages of a scenario; a waypoint owned twice is refused."""
        assignments: dict[int, str] = {}
        for gcs, owned in coverages.items():
            for seq in sorted(owned.seqs):
                if seq in assignments:
                    raise ValueError(f"waypoint {seq} is owned by both {assignments[seq]!r} and {gcs!r}")
                assignments[seq] = gcs
        return cls(assignments)

    @property
    def gcs_ids(self) -> frozenset[str]:
        return frozenset(self.assignments.values())

    def owner(self, seq: int) -> str | None:
        """The GCS that owns waypoint `seq` and the leg leaving it; None when nobody does."""
        return self.assignments.get(seq)


def waypoint_reached(position: GeoPoint, waypoint: GeoPoint, acceptance_radius_m: float) -> bool:
    """The vehicle is within the acceptance radius of the waypoint (edge included, haversine)."""
    if not math.isfinite(acceptance_radius_m) or acceptance_radius_m < 0:
        raise ValueError(f"acceptance radius must be a finite number of metres >= 0, got {acceptance_radius_m!r}")
    return haversine_m(position, waypoint) <= acceptance_radius_m
