"""Exact predicates in the (longitude, latitude) plane, for the polygon test.

Why exact: a position on a coverage edge must be classified the same way whatever the order
or starting vertex of the outline, and a point 1e-12 degrees outside an edge must be outside.
Float cross products cannot promise either, and an epsilon only moves the problem to the
epsilon. Every coordinate is turned into a `Fraction` (exact for float, int and Fraction
input: a float is a binary rational), so the signs below are the true signs, with no
tolerance to choose.
"""

from __future__ import annotations

from fractions import Fraction

from .geo import GeoPoint

XY = tuple[Fraction, Fraction]   # (x, y) = (longitude, latitude), exact


def xy(point: GeoPoint) -> XY:
    """The point in the plane the polygon test works in: x east (longitude), y north (latitude)."""
    return Fraction(point.lon), Fraction(point.lat)


def cross(o: XY, a: XY, b: XY) -> Fraction:
    """(a - o) x (b - o): positive when o -> a -> b turns left (counter-clockwise)."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def orientation(o: XY, a: XY, b: XY) -> int:
    """+1 left turn, -1 right turn, 0 collinear."""
    c = cross(o, a, b)
    return (c > 0) - (c < 0)


def in_box(p: XY, a: XY, b: XY) -> bool:
    """p lies in the axis-aligned box spanned by a and b (edges included)."""
    return min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= p[1] <= max(a[1], b[1])


def on_segment(p: XY, a: XY, b: XY) -> bool:
    """p lies on the closed segment ab (ab may be a single point)."""
    return orientation(a, b, p) == 0 and in_box(p, a, b)


def segments_meet(a: XY, b: XY, c: XY, d: XY) -> bool:
    """The closed segments ab and cd share at least one point (crossing, touching or overlapping)."""
    if not (min(a[0], b[0]) <= max(c[0], d[0]) and min(c[0], d[0]) <= max(a[0], b[0])
            and min(a[1], b[1]) <= max(c[1], d[1]) and min(c[1], d[1]) <= max(a[1], b[1])):
        return False
    o1, o2 = orientation(a, b, c), orientation(a, b, d)
    o3, o4 = orientation(c, d, a), orientation(c, d, b)
    if o1 * o2 < 0 and o3 * o4 < 0:
        return True
    return ((o1 == 0 and in_box(c, a, b)) or (o2 == 0 and in_box(d, a, b))
            or (o3 == 0 and in_box(a, c, d)) or (o4 == 0 and in_box(b, c, d)))
