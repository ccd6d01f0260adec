"""Coverage regions: where each GCS has authority, and how a scenario names one (seed 003, 4.6).

The thesis tried three region methods; a scenario picks one (`RegionMethod`) and each GCS
entry describes its coverage for it, as plain data from a JSON scenario (`coverage_of`):

    {"circle": {"center": [lat, lon], "radius_m": 500}}    a disc, by haversine
    {"polygon": [[lat, lon], [lat, lon], ...]}             an outline, by exact ray casting
    {"waypoints": [0, 1, 2]}                               the mission seqs the GCS owns

Coordinates are [lat, lon] (QGC's order, not GeoJSON's), degrees. A GCS entry may describe
all three, so one scenario runs under each method; only the chosen method's key is read.
The handover region of the geographic methods is the `Intersection` of the coverages;
under the waypoint method, `WaypointOwnership` says whose leg the vehicle is on.
All regions are closed: a position exactly on an edge is inside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import Decimal
from enum import Enum
from fractions import Fraction
from typing import Any, Mapping, Protocol, runtime_checkable

from ..errors import UsageError
from .geo import GeoPoint, haversine_m
from .polygon import Polygon, PolygonError
from .waypoints import SEQ_MAX, OwnedWaypoints, WaypointOwnership

__all__ = ["Circle", "Coverage", "Intersection", "OwnedWaypoints", "Polygon", "PolygonError", "Region",
           "RegionMethod", "WaypointOwnership", "coverage_of"]


@runtime_checkable
class Region(Protocol):
    """A closed set of positions (altitude ignored)."""

    def contains(self, point: GeoPoint) -> bool: ...


@dataclass(frozen=True)
class Circle:
    """A GCS's range as a disc around it (the thesis's first method): in iff distance <= radius.

    The thesis triggers on distance - radius < 0; the edge itself is inside here, like a
    polygon's. On the sphere of `geo`; an ellipsoid-based target differs by up to 0.56 %.
    """

    center: GeoPoint
    radius_m: float

    def __post_init__(self) -> None:
        if not isinstance(self.center, GeoPoint):
            raise TypeError(f"circle center must be a GeoPoint, got {self.center!r}")
        r = self.radius_m
        if isinstance(r, bool) or not isinstance(r, (int, float)) or not math.isfinite(r) or r <= 0:
            raise ValueError(f"circle radius must be a positive finite number of metres, got {r!r}")

    def contains(self, point: GeoPoint) -> bool:
        return haversine_m(self.center, point) <= self.radius_m


@dataclass(frozen=True)
class Intersection:
    """Where every one of the regions holds: the handover region is that of the GCSs' coverages."""

    regions: tuple[Region, ...]

    def __post_init__(self) -> None:
        regions = tuple(self.regions)
        if not regions:
            raise ValueError("an intersection needs at least one region (of none it would be the whole Earth)")
        for i, r in enumerate(regions):
            if not isinstance(r, Region):
                raise TypeError(f"region [{i}] has no contains(point): {r!r}")
        object.__setattr__(self, "regions", regions)

    def contains(self, point: GeoPoint) -> bool:
        return all(r.contains(point) for r in self.regions)


Coverage = Circle | Polygon | OwnedWaypoints


class RegionMethod(Enum):
    """The thesis's three ways to say where a GCS has authority; the value is the spec key."""

    CIRCLE = "circle"
    WAYPOINTS = "waypoints"
    POLYGON = "polygon"

    @classmethod
    def parse(cls, value: object, *, path: str = "region_method") -> RegionMethod:
        """The method a scenario names; a `UsageError` naming `path` for anything else."""
        try:
            return cls(value)
        except ValueError:
            raise UsageError(f"{path}: unknown region method {_show(value)} "
                             f"(expected one of: {', '.join(m.value for m in cls)})") from None


def coverage_of(gcs_spec: Mapping[str, Any], method: RegionMethod | str, *, path: str = "gcs") -> Coverage:
    """One GCS's coverage under `method`, from its scenario entry (plain JSON data).

    Bad data raises `UsageError` (a ValueError): one line naming the field, e.g.
    `gcs[1].circle.center[0]: latitude 95 is outside [-90, 90]`. Keys other than the method's
    are left to the caller (the GCS's id, address, and its other methods' coverage).
    """
    if not isinstance(method, RegionMethod):
        method = RegionMethod.parse(method)
    if not isinstance(gcs_spec, Mapping):
        raise UsageError(f"{path}: expected an object, got {_show(gcs_spec)}")
    key = method.value
    if key not in gcs_spec:
        raise UsageError(f"{path}.{key}: missing (the scenario uses the {key} method)")
    spec, where = gcs_spec[key], f"{path}.{key}"
    if method is RegionMethod.CIRCLE:
        return _circle(spec, where)
    if method is RegionMethod.POLYGON:
        return _polygon(spec, where)
    return _waypoints(spec, where)


def _show(value: object) -> str:
    """A value for a one-line message: its repr, cut short."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _number(value: object, path: str) -> float | Fraction:
    if isinstance(value, Decimal) and value.is_finite():
        return Fraction(value)
    if isinstance(value, bool) or not isinstance(value, (int, float, Fraction)) or not math.isfinite(value):
        raise UsageError(f"{path}: expected a finite number, got {_show(value)}")
    return value


def _list(value: object, path: str) -> list[Any]:
    if not isinstance(value, (list, tuple)):
        raise UsageError(f"{path}: expected a list, got {_show(value)}")
    return list(value)


def _point(value: object, path: str) -> GeoPoint:
    items = _list(value, path)
    if len(items) not in (2, 3):
        raise UsageError(f"{path}: expected [lat, lon] or [lat, lon, alt], got {len(items)} numbers")
    lat, lon = _number(items[0], f"{path}[0]"), _number(items[1], f"{path}[1]")
    alt = float(_number(items[2], f"{path}[2]")) if len(items) == 3 else None
    for i, (name, v, limit) in enumerate((("latitude", lat, 90), ("longitude", lon, 180))):
        if not -limit <= v <= limit:
            raise UsageError(f"{path}[{i}]: {name} {float(v):g} is outside [-{limit}, {limit}]")
    return GeoPoint(lat, lon, alt)


def _circle(spec: object, path: str) -> Circle:
    if not isinstance(spec, Mapping):
        raise UsageError(f"{path}: expected an object with center and radius_m, got {_show(spec)}")
    for field_ in spec:
        if field_ not in ("center", "radius_m"):
            raise UsageError(f"{path}: unknown field {_show(field_)} (expected center, radius_m)")
    for field_ in ("center", "radius_m"):
        if field_ not in spec:
            raise UsageError(f"{path}.{field_}: missing")
    center = _point(spec["center"], f"{path}.center")
    radius = float(_number(spec["radius_m"], f"{path}.radius_m"))
    if radius <= 0:
        raise UsageError(f"{path}.radius_m: must be more than 0 metres, got {radius:g}")
    return Circle(center, radius)


def _polygon(spec: object, path: str) -> Polygon:
    vertices = [_point(v, f"{path}[{i}]") for i, v in enumerate(_list(spec, path))]
    try:
        return Polygon(tuple(vertices))
    except PolygonError as e:
        raise UsageError(f"{path}: {e.problem}") from None


def _waypoints(spec: object, path: str) -> OwnedWaypoints:
    items = _list(spec, path)
    if not items:
        raise UsageError(f"{path}: empty (a GCS must own at least one waypoint)")
    seen: set[int] = set()
    for i, seq in enumerate(items):
        if isinstance(seq, bool) or not isinstance(seq, int) or not 0 <= seq <= SEQ_MAX:
            raise UsageError(f"{path}[{i}]: expected a waypoint seq, an int in [0, {SEQ_MAX}], got {_show(seq)}")
        if seq in seen:
            raise UsageError(f"{path}[{i}]: waypoint {seq} listed twice")
        seen.add(seq)
    return OwnedWaypoints(frozenset(seen))
