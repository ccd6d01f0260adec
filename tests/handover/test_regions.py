"""Coverage regions: circles, exact polygons, their intersection, waypoint ownership, scenario data."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.geo import GeoPoint, destination, haversine_m
from mavconform.reference_impl.handover.regions import (
    Circle, Intersection, OwnedWaypoints, Polygon, PolygonError, RegionMethod, WaypointOwnership, coverage_of,
)
from mavconform.reference_impl.handover.waypoints import waypoint_reached


def P(x: float, y: float) -> GeoPoint:
    """A point given as plane (x, y) = (lon, lat), so the drawings below read naturally."""
    return GeoPoint(y, x)


def poly(*xys: tuple[float, float]) -> Polygon:
    return Polygon(tuple(P(x, y) for x, y in xys))


SQUARE = poly((0, 0), (1, 0), (1, 1), (0, 1))
L_SHAPE = poly((0, 0), (4, 0), (4, 2), (2, 2), (2, 4), (0, 4))     # notch above y=2, right of x=2
DIAMOND = poly((0, 1), (1, 0), (2, 1), (1, 2))
U_SHAPE = poly((0, 0), (3, 0), (3, 3), (2, 3), (2, 1), (1, 1), (1, 3), (0, 3))


# --- polygon: boundary and ray cases --------------------------------------------------

@pytest.mark.parametrize("x, y, inside", [
    (0.5, 0.5, True),
    (0, 0, True), (1, 0, True), (1, 1, True), (0, 1, True),           # vertices
    (0.5, 0, True), (1, 0.5, True), (0.5, 1, True), (0, 0.5, True),   # edges, every side
    (-0.5, 0.5, False), (1.5, 0.5, False), (0.5, -1e-9, False), (0.5, 1 + 1e-9, False),
    (-1, 0, False), (2, 1, False),                                   # level with a horizontal edge
])
def test_square_is_closed(x: float, y: float, inside: bool) -> None:
    assert SQUARE.contains(P(x, y)) is inside


@pytest.mark.parametrize("x, y, inside", [
    (-1, 2, False), (1, 2, True), (2, 2, True), (3, 2, True), (4, 2, True), (4.5, 2, False),
    (3, 3, False), (3, 1.999999, True), (1, 3.5, True), (3, 0, True),
])
def test_ray_along_a_horizontal_edge(x: float, y: float, inside: bool) -> None:
    assert L_SHAPE.contains(P(x, y)) is inside


@pytest.mark.parametrize("x, y, inside", [
    (-1, 1, False), (0, 1, True), (0.5, 1, True), (1.5, 1, True), (2, 1, True), (3, 1, False),   # through side vertices
    (0.5, 2, False), (1, 2, True), (1.5, 2, False), (0.5, 0, False), (1, 0, True),               # touching the peaks
])
def test_ray_through_vertices(x: float, y: float, inside: bool) -> None:
    assert DIAMOND.contains(P(x, y)) is inside


@pytest.mark.parametrize("x, y, inside", [
    (0.5, 2, True), (2.5, 2, True), (1.5, 2, False), (1.5, 0.5, True), (1.5, 1, True), (1.5, 3, False),
    (-0.5, 2, False), (1, 2, True), (2, 2, True),
])
def test_concave_notch_is_outside(x: float, y: float, inside: bool) -> None:
    assert U_SHAPE.contains(P(x, y)) is inside


def test_a_point_on_an_edge_is_in_and_a_hair_outside_is_out_exactly() -> None:
    a, b = GeoPoint(47.39774, 8.54559), GeoPoint(47.40211, 8.55123)       # a slanted edge
    tri = Polygon((a, b, GeoPoint(47.39100, 8.56000)))                   # third vertex right of a->b
    mid = GeoPoint((Fraction(a.lat) + Fraction(b.lat)) / 2, (Fraction(a.lon) + Fraction(b.lon)) / 2)
    assert tri.contains(mid)
    hair = Fraction(1, 10**18)                                           # far below a float's resolution
    assert not tri.contains(GeoPoint(mid.lat + hair, mid.lon - hair))    # left of a->b: outside
    assert tri.contains(GeoPoint(mid.lat - hair, mid.lon + hair))


def test_degE7_positions_on_a_degE7_edge_are_inside_exactly() -> None:
    e7 = GeoPoint.from_e7
    area = Polygon((e7(473970000, 85450000), e7(473970000, 85470000), e7(473990000, 85470000)))
    on_hypotenuse = e7(473977419, 85457419)                             # lat - lon is constant on it
    assert area.contains(on_hypotenuse)
    assert not area.contains(e7(473977420, 85457419))
    assert area.contains(e7(473977418, 85457419))


# --- polygon: degenerate outlines ----------------------------------------------------

@pytest.mark.parametrize("xys, problem", [
    ([(0, 0), (1, 1)], "fewer than 3 distinct vertices (2)"),
    ([(0, 0), (0, 0), (1, 1), (1, 1), (0, 0)], "fewer than 3 distinct vertices (2)"),
    ([(0, 0), (1, 1), (2, 2), (3, 3)], "zero area: all 4 distinct vertices lie on one line"),
    ([(0, 0), (2, 0), (1, 0)], "zero area: all 3 distinct vertices lie on one line"),
    ([(0, 0), (1, 0), (1, 2), (1, 1), (0, 1)], "self-intersecting: edges [1]-[2] and [2]-[3] overlap "
                                               "(the outline folds back on itself)"),          # a spike
    ([(0, 0), (1, 0), (1, 1), (0, 1), (1, 1)], "self-intersecting: edges [1]-[2] and [3]-[4] meet"),  # vertex twice
    ([(0, 0), (1, 1), (1, 0), (0, 1)], "self-intersecting: edges [0]-[1] and [2]-[3] meet"),        # bow tie
    ([(0, 0), (1, 0), (1, 1), (2, 1), (2, 2), (1, 2), (1, 1), (0, 1)],                             # figure 8
     "self-intersecting: edges [1]-[2] and [5]-[6] meet"),
    ([(0, 0), (2, 0), (2, 2), (1, 0), (0, 2)],                                       # a vertex on an edge
     "self-intersecting: edges [0]-[1] and [2]-[3] meet"),
    ([(-170, 0), (170, 0), (170, 1)], "spans 340 degrees of longitude, more than 180 (edges are straight "
                                      "in latitude/longitude: split a region across the antimeridian)"),
])
def test_degenerate_outlines_are_refused_naming_the_problem(xys, problem: str) -> None:
    with pytest.raises(PolygonError) as refused:
        poly(*xys)
    assert refused.value.problem == problem
    assert str(refused.value) == f"bad polygon: {problem}"


def test_repeats_a_closing_vertex_and_straight_through_vertices_change_nothing() -> None:
    variants = [
        poly((0, 0), (1, 0), (1, 1), (0, 1), (0, 0)),                     # closed ring (GeoJSON, QGC)
        poly((0, 0), (0, 0), (1, 0), (1, 1), (1, 1), (0, 1)),             # consecutive repeats
        poly((0, 0), (0.5, 0), (1, 0), (1, 1), (0, 1)),                   # a vertex mid-edge
    ]
    probes = [P(x / 4, y / 4) for x in range(-1, 6) for y in range(-1, 6)]
    for v in variants:
        assert [v.contains(p) for p in probes] == [SQUARE.contains(p) for p in probes]


def test_a_vertex_must_be_a_geopoint() -> None:
    with pytest.raises(TypeError, match=r"vertex \[1\]"):
        Polygon((GeoPoint(0, 0), (1, 1), GeoPoint(0, 1)))


# --- polygon: properties -------------------------------------------------------------

def _exact_cross(o, a, b) -> Fraction:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def _xy(p: GeoPoint) -> tuple[Fraction, Fraction]:
    return Fraction(p.lon), Fraction(p.lat)


@st.composite
def star_polygons(draw: st.DrawFn) -> Polygon:
    """Simple polygons, concave ones included: vertices at increasing angles round a centre."""
    cy, cx = draw(st.floats(-60, 60)), draw(st.floats(-170, 170))
    n = draw(st.integers(3, 10))
    gaps = draw(st.lists(st.floats(0.1, 1.0), min_size=n, max_size=n))
    start = draw(st.floats(0, 2 * math.pi))
    angles = [start + 2 * math.pi * sum(gaps[:i]) / sum(gaps) for i in range(n)]
    assume(max(gaps) / sum(gaps) < 0.45)                                 # every gap under pi
    radii = draw(st.lists(st.floats(0.002, 0.05), min_size=n, max_size=n))
    try:
        return Polygon(tuple(GeoPoint(cy + r * math.sin(t), cx + r * math.cos(t)) for r, t in zip(radii, angles)))
    except PolygonError:
        assume(False)
        raise


@st.composite
def convex_polygons(draw: st.DrawFn) -> Polygon:
    """The convex hull (exact monotone chain) of random points near a centre."""
    cy, cx = draw(st.floats(-60, 60)), draw(st.floats(-170, 170))
    d = st.floats(-0.05, 0.05)
    pts = sorted({(Fraction(cx + dx), Fraction(cy + dy)) for dx, dy in draw(st.lists(st.tuples(d, d), min_size=3,
                                                                                        max_size=12))})

    def half(points):
        chain: list = []
        for p in points:
            while len(chain) >= 2 and _exact_cross(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain[:-1]

    hull = half(pts) + half(pts[::-1])
    assume(len(hull) >= 3)
    return Polygon(tuple(GeoPoint(y, x) for x, y in hull))


def probes_for(polygon: Polygon):
    """Random points round the polygon, plus its vertices and the exact midpoints of its edges."""
    lats = [float(v.lat) for v in polygon.vertices]
    lons = [float(v.lon) for v in polygon.vertices]
    margin = 0.01
    around = st.builds(GeoPoint, st.floats(min(lats) - margin, max(lats) + margin),
                       st.floats(min(lons) - margin, max(lons) + margin))
    vs = polygon.vertices
    mids = [GeoPoint((Fraction(a.lat) + Fraction(b.lat)) / 2, (Fraction(a.lon) + Fraction(b.lon)) / 2)
            for a, b in zip(vs, vs[1:] + vs[:1])]
    return st.lists(st.one_of(around, st.sampled_from(vs), st.sampled_from(mids)), min_size=1, max_size=20)


@given(st.data(), star_polygons(), st.integers(0, 9))
def test_rotating_or_reversing_the_vertices_never_changes_an_answer(data: st.DataObject, polygon: Polygon,
                                                                    k: int) -> None:
    vs = polygon.vertices
    k %= len(vs)
    rotated, reversed_ = Polygon(vs[k:] + vs[:k]), Polygon(vs[::-1])
    for p in data.draw(probes_for(polygon)):
        assert polygon.contains(p) == rotated.contains(p) == reversed_.contains(p)


@given(st.data(), star_polygons())
def test_every_vertex_and_edge_point_is_inside(data: st.DataObject, polygon: Polygon) -> None:
    vs = polygon.vertices
    a, b = data.draw(st.sampled_from(list(zip(vs, vs[1:] + vs[:1]))))
    t = data.draw(st.fractions(0, 1))
    assert polygon.contains(a)
    assert polygon.contains(GeoPoint(Fraction(a.lat) + t * (Fraction(b.lat) - Fraction(a.lat)),
                                     Fraction(a.lon) + t * (Fraction(b.lon) - Fraction(a.lon))))


@given(convex_polygons())
def test_a_convex_polygon_contains_its_vertex_centroid(polygon: Polygon) -> None:
    n = len(polygon.vertices)
    centroid = GeoPoint(sum(Fraction(v.lat) for v in polygon.vertices) / n,
                        sum(Fraction(v.lon) for v in polygon.vertices) / n)
    assert polygon.contains(centroid)


@given(star_polygons(), st.floats(1e-9, 1.0), st.sampled_from(["n", "s", "e", "w"]))
def test_a_point_outside_the_bounding_box_is_outside(polygon: Polygon, beyond: float, side: str) -> None:
    lats = [v.lat for v in polygon.vertices]
    lons = [v.lon for v in polygon.vertices]
    mid_lat, mid_lon = (min(lats) + max(lats)) / 2, (min(lons) + max(lons)) / 2
    p = {"n": GeoPoint(max(lats) + beyond, mid_lon), "s": GeoPoint(min(lats) - beyond, mid_lon),
         "e": GeoPoint(mid_lat, max(lons) + beyond), "w": GeoPoint(mid_lat, min(lons) - beyond)}[side]
    assert not polygon.contains(p)


def _distance_to_edges(p: GeoPoint, vs: tuple[GeoPoint, ...]) -> float:
    """Smallest float distance (degrees, in the plane) from p to the outline."""
    px, py = float(p.lon), float(p.lat)
    best = math.inf
    for a, b in zip(vs, vs[1:] + vs[:1]):
        ax, ay, bx, by = float(a.lon), float(a.lat), float(b.lon), float(b.lat)
        dx, dy = bx - ax, by - ay
        t = max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / (dx * dx + dy * dy)))
        best = min(best, math.hypot(px - ax - t * dx, py - ay - t * dy))
    return best


def _winding_number(p: GeoPoint, vs: tuple[GeoPoint, ...]) -> int:
    """Sunday's winding number, in floats: an independent oracle away from the edges."""
    px, py = float(p.lon), float(p.lat)
    wn = 0
    for a, b in zip(vs, vs[1:] + vs[:1]):
        ax, ay, bx, by = float(a.lon), float(a.lat), float(b.lon), float(b.lat)
        left = (bx - ax) * (py - ay) - (px - ax) * (by - ay)
        if ay <= py < by and left > 0:
            wn += 1
        elif by <= py < ay and left < 0:
            wn -= 1
    return wn


def _thesis_listing_4_3(p: GeoPoint, vs: tuple[GeoPoint, ...]) -> bool:
    """The thesis's isInsidePolygon (x = lon, y = lat), in floats as written."""
    x, y = float(p.lon), float(p.lat)
    inside = False
    j = len(vs) - 1
    for i in range(len(vs)):
        xi, yi, xj, yj = float(vs[i].lon), float(vs[i].lat), float(vs[j].lon), float(vs[j].lat)
        if (yi > y) != (yj > y) and x < (xj - xi) * (y - yi) / (yj - yi) + xi:
            inside = not inside
        j = i
    return inside


@given(st.data(), star_polygons())
def test_ray_casting_agrees_with_winding_number_and_the_thesis_away_from_edges(data: st.DataObject,
                                                                               polygon: Polygon) -> None:
    for p in data.draw(probes_for(polygon)):
        if _distance_to_edges(p, polygon.vertices) > 1e-7:
            assert polygon.contains(p) == (_winding_number(p, polygon.vertices) != 0) \
                == _thesis_listing_4_3(p, polygon.vertices)


# --- circle ----------------------------------------------------------------------------

GCS_A = GeoPoint(41.1780, -8.5980)


@pytest.mark.parametrize("distance, inside", [(0.0, True), (499.0, True), (501.0, False), (5000.0, False)])
def test_circle_is_a_haversine_disc(distance: float, inside: bool) -> None:
    assert Circle(GCS_A, 500.0).contains(destination(GCS_A, 37.0, distance)) is inside


def test_circle_edge_is_inside() -> None:
    edge = destination(GCS_A, 123.0, 750.0)
    assert Circle(GCS_A, haversine_m(GCS_A, edge)).contains(edge)


@pytest.mark.parametrize("radius", [0.0, -5.0, math.nan, math.inf, True, "500"])
def test_circle_radius_must_be_positive_metres(radius) -> None:
    with pytest.raises(ValueError, match="radius"):
        Circle(GCS_A, radius)


# --- intersection ----------------------------------------------------------------------

def test_two_circles_make_the_thesis_handover_lens() -> None:
    gcs_b = destination(GCS_A, 90.0, 1500.0)
    lens = Intersection((Circle(GCS_A, 1000.0), Circle(gcs_b, 1000.0)))
    assert lens.contains(destination(GCS_A, 90.0, 750.0))
    assert not lens.contains(destination(GCS_A, 90.0, 400.0))        # A's alone
    assert not lens.contains(destination(GCS_A, 0.0, 800.0))         # A's alone, to the north


def test_an_intersection_needs_regions() -> None:
    with pytest.raises(ValueError, match="at least one region"):
        Intersection(())
    with pytest.raises(TypeError, match=r"region \[1\]"):
        Intersection((Circle(GCS_A, 1.0), OwnedWaypoints(frozenset({1}))))


@st.composite
def regions(draw: st.DrawFn):
    centre = GeoPoint(draw(st.floats(41.17, 41.19)), draw(st.floats(-8.61, -8.59)))
    if draw(st.booleans()):
        return Circle(centre, draw(st.floats(10.0, 2000.0)))
    n = draw(st.integers(3, 6))
    return Polygon(tuple(destination(centre, 360.0 * i / n, draw(st.floats(100.0, 2000.0))) for i in range(n)))


@given(st.lists(regions(), min_size=1, max_size=4), st.floats(41.16, 41.20), st.floats(-8.62, -8.58))
def test_intersection_contains_is_all_of_its_regions(rs, lat: float, lon: float) -> None:
    p = GeoPoint(lat, lon)
    assert Intersection(tuple(rs)).contains(p) == all(r.contains(p) for r in rs)


# --- waypoint ownership ------------------------------------------------------------------

def test_the_owner_of_the_reached_waypoint_owns_the_leg() -> None:
    ownership = WaypointOwnership({0: "A", 1: "A", 2: "A", 3: "B", 4: "B", 5: "A"})
    assert [ownership.owner(s) for s in range(7)] == ["A", "A", "A", "B", "B", "A", None]
    assert ownership.gcs_ids == {"A", "B"}
    assert ownership == WaypointOwnership({5: "A", 4: "B", 3: "B", 2: "A", 1: "A", 0: "A"})
    assert hash(ownership) == hash(WaypointOwnership(dict(ownership.assignments)))


def test_ownership_joins_the_gcs_coverages_and_refuses_a_shared_waypoint() -> None:
    joined = WaypointOwnership.from_coverages({"A": OwnedWaypoints(frozenset({0, 1, 4})),
                                               "B": OwnedWaypoints(frozenset({2, 3}))})
    assert dict(joined.assignments) == {0: "A", 1: "A", 2: "B", 3: "B", 4: "A"}
    with pytest.raises(ValueError, match="waypoint 2 is owned by both 'A' and 'B'"):
        WaypointOwnership.from_coverages({"A": OwnedWaypoints(frozenset({1, 2})),
                                          "B": OwnedWaypoints(frozenset({2, 3}))})


@pytest.mark.parametrize("assignments", [{-1: "A"}, {70000: "A"}, {True: "A"}, {1: ""}, {1: 7}])
def test_bad_assignments_are_refused(assignments) -> None:
    with pytest.raises(ValueError):
        WaypointOwnership(assignments)


def test_owned_waypoints_are_never_empty() -> None:
    with pytest.raises(ValueError, match="at least one"):
        OwnedWaypoints(frozenset())
    assert OwnedWaypoints(frozenset({3})).owns(3) and not OwnedWaypoints(frozenset({3})).owns(4)


def test_a_waypoint_is_reached_within_the_acceptance_radius() -> None:
    wp = GeoPoint(41.18, -8.60)
    assert waypoint_reached(destination(wp, 200.0, 1.9), wp, 2.0)
    assert not waypoint_reached(destination(wp, 200.0, 2.1), wp, 2.0)
    with pytest.raises(ValueError, match="acceptance radius"):
        waypoint_reached(wp, wp, -1.0)


# --- scenario data -----------------------------------------------------------------------

GCS_SPEC = {
    "id": "A",
    "circle": {"center": [41.178, -8.598], "radius_m": 500},
    "polygon": [[41.17, -8.61], [41.17, -8.59], [41.19, -8.59], [41.19, -8.61]],
    "waypoints": [0, 1, 2],
}


def test_each_method_reads_its_own_key() -> None:
    assert coverage_of(GCS_SPEC, RegionMethod.CIRCLE) == Circle(GeoPoint(41.178, -8.598), 500.0)
    square = coverage_of(GCS_SPEC, "polygon")
    assert isinstance(square, Polygon) and square.contains(GeoPoint(41.18, -8.60))
    assert coverage_of(GCS_SPEC, "waypoints") == OwnedWaypoints(frozenset({0, 1, 2}))
    assert coverage_of({"circle": {"center": [41.0, -8.0, 120.0], "radius_m": 1.5}}, "circle").center.alt == 120.0


@pytest.mark.parametrize("spec, method, message", [
    ({}, "hexagon", "region_method: unknown region method 'hexagon' (expected one of: circle, waypoints, polygon)"),
    ([1, 2], "circle", "gcs[1]: expected an object, got [1, 2]"),
    ({"polygon": []}, "circle", "gcs[1].circle: missing (the scenario uses the circle method)"),
    ({"circle": [41.0, -8.0]}, "circle",
     "gcs[1].circle: expected an object with center and radius_m, got [41.0, -8.0]"),
    ({"circle": {"center": [41.0, -8.0], "radius": 5}}, "circle",
     "gcs[1].circle: unknown field 'radius' (expected center, radius_m)"),
    ({"circle": {"center": [41.0, -8.0]}}, "circle", "gcs[1].circle.radius_m: missing"),
    ({"circle": {"center": [41.0], "radius_m": 5}}, "circle",
     "gcs[1].circle.center: expected [lat, lon] or [lat, lon, alt], got 1 numbers"),
    ({"circle": {"center": [95, -8.0], "radius_m": 5}}, "circle",
     "gcs[1].circle.center[0]: latitude 95 is outside [-90, 90]"),
    ({"circle": {"center": [41.0, "-8"], "radius_m": 5}}, "circle",
     "gcs[1].circle.center[1]: expected a finite number, got '-8'"),
    ({"circle": {"center": [41.0, -8.0], "radius_m": 0}}, "circle",
     "gcs[1].circle.radius_m: must be more than 0 metres, got 0"),
    ({"circle": {"center": [41.0, -8.0], "radius_m": True}}, "circle",
     "gcs[1].circle.radius_m: expected a finite number, got True"),
    ({"polygon": {"a": 1}}, "polygon", "gcs[1].polygon: expected a list, got {'a': 1}"),
    ({"polygon": [[41.0, -8.0], [41.0, 181.5], [42.0, -8.0]]}, "polygon",
     "gcs[1].polygon[1][1]: longitude 181.5 is outside [-180, 180]"),
    ({"polygon": [[41.0, -8.0], [42.0, -7.0], [42.0, -8.0], [41.0, -7.0]]}, "polygon",
     "gcs[1].polygon: self-intersecting: edges [0]-[1] and [2]-[3] meet"),
    ({"polygon": [[41.0, -8.0], [42.0, -8.0]]}, "polygon", "gcs[1].polygon: fewer than 3 distinct vertices (2)"),
    ({"waypoints": []}, "waypoints", "gcs[1].waypoints: empty (a GCS must own at least one waypoint)"),
    ({"waypoints": [1, 2.0]}, "waypoints",
     "gcs[1].waypoints[1]: expected a waypoint seq, an int in [0, 65535], got 2.0"),
    ({"waypoints": [1, 2, 1]}, "waypoints", "gcs[1].waypoints[2]: waypoint 1 listed twice"),
])
def test_bad_scenario_data_names_the_field_in_one_line(spec, method: str, message: str) -> None:
    with pytest.raises(UsageError) as refused:
        coverage_of(spec, method, path="gcs[1]")
    assert str(refused.value) == message
    assert isinstance(refused.value, ValueError)


def _near_edge_floats(polygon: Polygon):
    """Float points on or a few ulps either side of an edge (rounded from an exact edge
    point), where a float cross product's sign is least to be trusted."""
    vs = polygon.vertices

    @st.composite
    def near(draw: st.DrawFn) -> GeoPoint:
        a, b = draw(st.sampled_from(list(zip(vs, vs[1:] + vs[:1]))))
        t = draw(st.fractions(0, 1, max_denominator=10**6))
        lat = float(Fraction(a.lat) + t * (Fraction(b.lat) - Fraction(a.lat)))
        lon = float(Fraction(a.lon) + t * (Fraction(b.lon) - Fraction(a.lon)))
        for _ in range(draw(st.integers(0, 3))):
            lat = math.nextafter(lat, draw(st.sampled_from([-math.inf, math.inf])))
        for _ in range(draw(st.integers(0, 3))):
            lon = math.nextafter(lon, draw(st.sampled_from([-math.inf, math.inf])))
        return GeoPoint(lat, lon)
    return near()


@given(st.data(), star_polygons())
def test_the_float_filter_gives_the_exact_answer_even_a_few_ulps_from_an_edge(data: st.DataObject,
                                                                              polygon: Polygon) -> None:
    """`contains` counts crossings in floats when it can; it must answer as the exact test
    does everywhere, edges included (where it must fall back)."""
    points = data.draw(st.lists(st.one_of(_near_edge_floats(polygon), probes_for(polygon).map(lambda ps: ps[0])),
                                min_size=1, max_size=25))
    for p in points:
        assert polygon.contains(p) == polygon._contains_exactly(p), p


def test_the_float_filter_is_used_for_float_points_and_falls_back_on_an_edge() -> None:
    square = Polygon((GeoPoint(0.0, 0.0), GeoPoint(0.0, 1.0), GeoPoint(1.0, 1.0), GeoPoint(1.0, 0.0)))
    assert square._contains_floats(0.5, 0.5) is True and square._contains_floats(1.5, 0.5) is False
    assert square._contains_floats(0.5, 1.0 - 2**-60) is True   # 1 - 2^-60 is 1.0 as a float: on the top edge
    slanted = Polygon((GeoPoint(0.0, 0.0), GeoPoint(0.1, 0.3), GeoPoint(0.7, 0.2)))
    on = GeoPoint(0.05, 0.15)   # rounded from the edge's midpoint: within rounding of the edge
    assert slanted._contains_floats(on.lon, on.lat) is None
    assert slanted.contains(on) == slanted._contains_exactly(on)
    exact_only = Polygon((GeoPoint.from_e7(0, 0), GeoPoint.from_e7(1, 3), GeoPoint.from_e7(7, 2)))
    assert exact_only._float_ring is None   # 1e-7 is no float: the exact test only


def test_near_the_equator_and_prime_meridian_the_error_bound_is_what_keeps_the_float_test_right(
        monkeypatch) -> None:
    """Coordinates of unlike magnitudes (a region across 0 degrees): the float cross product of
    this edge and point has the wrong sign. The bound sends it to the exact test; without the
    bound the float answer would be wrong."""
    from mavconform.reference_impl.handover import polygon as polygon_module
    a = GeoPoint(-0.00044502693323389007, 1.2260584879084768)
    b = GeoPoint(0.0071319430119698305, -0.7760678727123507)
    triangle = Polygon((a, b, GeoPoint(1.0, 0.2)))
    p = GeoPoint(0.001967415984052141, 0.5885984487210691)
    truth = triangle._contains_exactly(p)
    assert triangle.contains(p) == truth
    assert triangle._contains_floats(p.lon, p.lat) is None
    monkeypatch.setattr(polygon_module, "_ORIENT_BOUND", 0.0)
    assert triangle._contains_floats(p.lon, p.lat) == (not truth)
