"""The geometry the mission computer's tests fly: a line north of HOME, GCS A covering
0..1200 m north and GCS B 800..2300 m, so the handover region is 800..1200 m, under each of
the thesis's three region methods (test_mission_computer.py, test_handover_policies.py)."""

from __future__ import annotations

from mavconform.reference_impl.handover.geo import GeoPoint, destination
from mavconform.reference_impl.handover.regions import Circle, OwnedWaypoints, Polygon

VEHICLE = (1, 1)
A, B, C = 201, 202, 203
HOME = GeoPoint(47.397742, 8.545594)


def at(north: float, east: float = 0.0) -> GeoPoint:
    p = destination(HOME, 0.0, north) if north >= 0 else destination(HOME, 180.0, -north)
    return destination(p, 90.0, east) if east else p


def rect(south: float, north: float, half_width: float = 300.0) -> Polygon:
    return Polygon((at(south, -half_width), at(south, half_width), at(north, half_width), at(north, -half_width)))


COVERAGES = {
    "polygon": {A: rect(-300, 1200), B: rect(800, 2300)},
    "circle": {A: Circle(HOME, 1200.0), B: Circle(at(2000), 1200.0)},
    # the round trip below: out to 2000 m and back; B owns the legs from 800 m out and back to 800 m
    "waypoints": {A: OwnedWaypoints(frozenset({0, 1, 6, 7})), B: OwnedWaypoints(frozenset({2, 3, 4, 5}))},
}
WAYPOINTS = ((0, at(0)), (1, at(400)), (2, at(800)), (3, at(1200)), (4, at(2000)), (5, at(1200)), (6, at(800)),
             (7, at(0)))
