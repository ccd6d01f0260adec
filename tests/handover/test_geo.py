"""Points and great-circle distances: published values, and the metric's properties."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.handover.geo import (
    EARTH_MEAN_RADIUS_M, GeoPoint, destination, haversine_m, initial_bearing_deg,
)

R = EARTH_MEAN_RADIUS_M
# Rosetta Code, "Haversine formula": BNA (36.12, -86.67) to LAX (33.94, -118.40).
BNA, LAX = GeoPoint(36.12, -86.67), GeoPoint(33.94, -118.40)


def lats(limit: float = 90.0):
    return st.floats(-limit, limit, allow_nan=False)


def lons():
    return st.floats(-180.0, 180.0, allow_nan=False)


def points(limit: float = 90.0):
    return st.builds(GeoPoint, lats(limit), lons())


def near(origin: GeoPoint, span_deg: float = 0.05):
    """Points within span_deg of origin (a few km, a handover scenario's scale), across the antimeridian too."""
    d = st.floats(-span_deg, span_deg, allow_nan=False)
    return st.builds(lambda dlat, dlon: GeoPoint(origin.lat + dlat, (origin.lon + dlon + 180.0) % 360.0 - 180.0), d, d)


# --- known values --------------------------------------------------------------------

def test_one_degree_of_latitude_is_r_times_pi_over_180() -> None:
    expected = R * math.pi / 180                                    # 111195.08 m
    assert haversine_m(GeoPoint(0.0, 0.0), GeoPoint(1.0, 0.0)) == pytest.approx(expected, rel=1e-12)
    assert haversine_m(GeoPoint(45.0, 8.0), GeoPoint(46.0, 8.0)) == pytest.approx(expected, rel=1e-12)
    assert haversine_m(GeoPoint(0.0, 10.0), GeoPoint(0.0, 11.0)) == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("radius_km, published_km", [
    (6371.0, 2886.44444283798329974715782394574671655),
    (6372.8, 2887.25995060711033944886005029688505340),
])
def test_nashville_to_los_angeles_matches_the_published_distance(radius_km: float, published_km: float) -> None:
    d = haversine_m(BNA, LAX, earth_radius_m=radius_km * 1000)
    assert d == pytest.approx(published_km * 1000, abs=1e-3)
    assert haversine_m(LAX, BNA, earth_radius_m=radius_km * 1000) == d


def test_the_default_sphere_is_the_iugg_mean_radius() -> None:
    assert R == 6371008.8
    thesis = haversine_m(BNA, LAX, earth_radius_m=6371000.0)       # the thesis's 6371 km
    assert haversine_m(BNA, LAX) == pytest.approx(thesis * R / 6371000.0, rel=1e-14)


def test_distance_across_the_antimeridian_is_the_short_way() -> None:
    d = haversine_m(GeoPoint(0.0, 179.9995), GeoPoint(0.0, -179.9995))
    assert d == pytest.approx(R * math.radians(0.001), rel=1e-9)   # 111 m, not 40000 km
    assert haversine_m(GeoPoint(10.0, 180.0), GeoPoint(10.0, -180.0)) == 0.0


def test_coinciding_points_are_zero_apart_and_due_north() -> None:
    p = GeoPoint(47.3977419, 8.5455938)
    assert haversine_m(p, p) == 0.0
    assert initial_bearing_deg(p, p) == 0.0


def test_a_millimetre_is_resolved() -> None:
    p = GeoPoint(47.3977419, 8.5455938)
    q = GeoPoint(47.3977419 + math.degrees(0.001 / R), 8.5455938)
    assert haversine_m(p, q) == pytest.approx(0.001, rel=1e-6)


@pytest.mark.parametrize("to, bearing", [
    (GeoPoint(1.0, 0.0), 0.0), (GeoPoint(0.0, 1.0), 90.0), (GeoPoint(-1.0, 0.0), 180.0), (GeoPoint(0.0, -1.0), 270.0),
])
def test_cardinal_bearings_from_the_origin(to: GeoPoint, bearing: float) -> None:
    assert initial_bearing_deg(GeoPoint(0.0, 0.0), to) == pytest.approx(bearing, abs=1e-12)


def test_destination_500_m_north_moves_latitude_by_500_over_r() -> None:
    start = GeoPoint(47.0, 8.0, 120.0)
    end = destination(start, 0.0, 500.0)
    assert end.lat == pytest.approx(47.0 + math.degrees(500.0 / R), abs=1e-12)
    assert end.lon == pytest.approx(8.0, abs=1e-12)
    assert end.alt == 120.0


def test_straight_edges_stay_within_the_documented_great_circle_bound() -> None:
    """polygon.py: a great circle bulges poleward of a straight lat/lon edge by ~L^2 tan(lat) / 8R."""
    for lat in (15.0, 45.0, 60.0):
        start = GeoPoint(lat, 8.0)
        end = GeoPoint(lat, 8.0 + math.degrees(5000.0 / (R * math.cos(math.radians(lat)))))
        d = haversine_m(start, end)
        mid = destination(start, initial_bearing_deg(start, end), d / 2)
        bulge_m = math.radians(mid.lat - lat) * R
        assert 0 < bulge_m <= 5000.0**2 * math.tan(math.radians(lat)) / (8 * R) * 1.001


# --- GeoPoint ------------------------------------------------------------------------

@pytest.mark.parametrize("lat, lon, alt, error", [
    (90.5, 0.0, None, ValueError), (-91, 0.0, None, ValueError), (0.0, 180.01, None, ValueError),
    (math.nan, 0.0, None, ValueError), (0.0, math.inf, None, ValueError), (0.0, 0.0, math.nan, ValueError),
    (True, 0.0, None, TypeError), ("47.1", 0.0, None, TypeError),
])
def test_bad_coordinates_are_refused(lat, lon, alt, error) -> None:
    with pytest.raises(error):
        GeoPoint(lat, lon, alt)


def test_from_e7_keeps_the_exact_decimal() -> None:
    p = GeoPoint.from_e7(473977419, -85455938, 50.0)
    assert p.lat == Fraction(473977419, 10**7) and p.lon == Fraction(-85455938, 10**7) and p.alt == 50.0
    assert p.lat != 47.3977419                     # the float is a different (binary) number
    assert haversine_m(p, GeoPoint(47.3977419, -8.5455938)) < 1e-6


# --- properties ----------------------------------------------------------------------

@given(points(), points())
def test_haversine_is_symmetric_and_non_negative(a: GeoPoint, b: GeoPoint) -> None:
    d = haversine_m(a, b)
    assert d == haversine_m(b, a)
    assert 0.0 <= d <= math.pi * R * (1 + 1e-15)


@given(points(), lats(), lons())
def test_haversine_is_zero_only_for_the_same_point(a: GeoPoint, lat: float, lon: float) -> None:
    assert haversine_m(a, a) == 0.0
    b = GeoPoint(lat, lon)
    if abs(b.lat - a.lat) >= 1e-7:                 # about a centimetre apart in latitude
        assert haversine_m(a, b) > 0.0
    if haversine_m(a, b) == 0.0:
        assert abs(a.lat - b.lat) < 1e-9


@given(points(), points(), points())
def test_triangle_inequality_anywhere(a: GeoPoint, b: GeoPoint, c: GeoPoint) -> None:
    # Near the antipode haversine loses ~R*sqrt(eps), a few tenths of a metre (geo.py).
    assert haversine_m(a, c) <= haversine_m(a, b) + haversine_m(b, c) + 1.0


@given(st.data(), points(80.0))
def test_triangle_inequality_at_scenario_scale(data: st.DataObject, origin: GeoPoint) -> None:
    a, b, c = (data.draw(near(origin)) for _ in range(3))
    assert haversine_m(a, c) <= haversine_m(a, b) + haversine_m(b, c) + 1e-6


@given(points(80.0), st.floats(0.0, 360.0, exclude_max=True), st.floats(1.0, 10_000.0))
def test_destination_inverts_distance_and_bearing(start: GeoPoint, bearing: float, distance: float) -> None:
    end = destination(start, bearing, distance)
    assert haversine_m(start, end) == pytest.approx(distance, abs=1e-6)
    turn = (initial_bearing_deg(start, end) - bearing + 180.0) % 360.0 - 180.0
    assert abs(turn) < 1e-6


@given(points(), points())
def test_bearing_is_in_range(a: GeoPoint, b: GeoPoint) -> None:
    assert 0.0 <= initial_bearing_deg(a, b) < 360.0
