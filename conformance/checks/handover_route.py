"""The handover the HO.SEQ clauses fly, worked out of a handover scenario (`route_of`): the
parent GCS (A, the commander), the partner (B: the GCS whose region with A the scenario's path
enters first), that region, and the point the flight holds at (the middle of the path's first
stretch inside it). conformance/checks/handover_sequence.py says how the clauses use it."""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Any, Iterator

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.hysteresis import signed_distance_m
from mavconform.reference_impl.handover.regions import Intersection, RegionMethod
from mavconform.reference_impl.handover.scenario import Scenario

from ..outcome import PreconditionFailed
from ..session import Session
from ..target_uri import handover_config

SAMPLE_M = 2.0           # m between the points the path is sampled at


# --- what the scenario says the flights are ---------------------------------------------------

@dataclass(frozen=True)
class Route:
    """The handover the tester plays out of a scenario (`route_of`)."""

    scenario: str
    parent: int                      # the commander, A
    partner: int                     # B: the GCS whose region with A the path enters first
    parent_coverage: Any
    regions: tuple[tuple[int, Intersection], ...]   # every handover region of the parent, by the other GCS
    hold: GeoPoint                   # the middle of the path's first stretch inside A and B's region
    alt: float                       # m above home, the path's there
    dwell: float
    bound: float
    commit: float                    # s from a handover's start by which control must have moved

    @property
    def region(self) -> Intersection:
        return dict(self.regions)[self.partner]

    def inside(self, point: GeoPoint) -> bool:
        return self.region.contains(point)

    def where(self, point: GeoPoint) -> str:
        d = signed_distance_m(self.region, point)
        return f"{-d:.0f} m inside" if d <= 0 else f"{d:.0f} m outside"

    @property
    def pair(self) -> str:
        return f"GCSs {self.parent} and {self.partner}"


def route_of(scenario: Scenario, *, option: str = "") -> Route:
    """The handover the clauses fly for `scenario`, or a `UsageError` saying why there is none."""
    where = option or (scenario.source or scenario.name)
    if scenario.region_method is RegionMethod.WAYPOINTS:
        raise UsageError(f"{where}: the handover clauses need a circle or polygon scenario: under the waypoint "
                         "method a handover follows the mission's seqs, and the clauses fly a mission of their own")
    parent = scenario.gcs_named(scenario.parent)
    regions = tuple((g.sysid, Intersection((parent.coverage, g.coverage))) for g in scenario.gcs
                    if g.sysid != parent.sysid)
    run: list[GeoPoint] = []
    partner = None
    for point in sampled_path([w.point for w in scenario.flight.waypoints]):
        inside = [sysid for sysid, region in regions if region.contains(point)]
        if partner is None and inside:
            partner = inside[0]
        if partner is not None:
            if partner not in inside:
                break
            run.append(point)
    if partner is None:
        raise UsageError(f"{where}: the flight's path never enters a handover region of the parent GCS "
                         f"{scenario.parent!r} (where its coverage meets another GCS's)")
    lengths = [0.0]
    for a, b in zip(run, run[1:]):
        lengths.append(lengths[-1] + haversine_m(a, b))
    middle = run[bisect.bisect_left(lengths, lengths[-1] / 2)] if len(run) > 1 else run[0]
    config = handover_config(scenario)
    return Route(scenario.name, parent.sysid, partner, parent.coverage, regions,
                 GeoPoint(middle.lat, middle.lon), float(middle.alt or 0.0), config.dwell, config.bound,
                 config.commit_timeout)


def sampled_path(points: list[GeoPoint]) -> Iterator[GeoPoint]:
    """Points along the path every SAMPLE_M or less, straight in lat/lon (as a flight model
    interpolates a leg), altitudes too."""
    for a, b in zip(points, points[1:]):
        n = max(1, math.ceil(haversine_m(a, b) / SAMPLE_M))
        alt_a, alt_b = a.alt or 0.0, b.alt or 0.0
        for k in range(n):
            f = k / n
            yield GeoPoint(float(a.lat) + (float(b.lat) - float(a.lat)) * f,
                           float(a.lon) + (float(b.lon) - float(a.lon)) * f, alt_a + (alt_b - alt_a) * f)
    last = points[-1]
    yield GeoPoint(float(last.lat), float(last.lon), last.alt or 0.0)


def route_for(s: Session) -> Route:
    cached = s.cache.get("ho.route")
    if cached is None:
        try:
            cached = s.cache["ho.route"] = route_of(s.uri.handover_scenario)
        except UsageError as exc:
            raise PreconditionFailed(str(exc)) from None
    return cached


