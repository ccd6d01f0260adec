"""Hysteresis for region checks: a margin and a dwell time, so border jitter cannot flap a handover.

The thesis's mission computer checks every 50 ms whether the vehicle is in the handover region
and starts the handover when it is (seed 003, 4.3.2, 4.6). A position estimate that wanders
across the edge (GNSS noise, a path along the border) would then start and undo handovers
as fast as it wanders. Two knobs stop that, each usable alone:

- a margin (metres): a position counts as `INSIDE` only when it is at least `margin_m` inside
  the edge and as `OUTSIDE` only when more than `margin_m` outside; in between it is
  `BORDER`, which never changes the latch (a Schmitt trigger);
- a dwell (seconds): the latch enters only after `INSIDE` has been seen continuously for
  `dwell` seconds, and leaves only after `OUTSIDE` continuously for `dwell` seconds.

`Latch` is a sans-IO state machine (observations with their times in, edges out) that moves
only through `LATCH_TRANSITIONS`, as the other engines do. Margins need a distance to the
edge: `signed_distance_m` gives it for circles (haversine), polygons (a local tangent plane,
metres) and intersections of them.
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Callable

from ..state_table import next_state
from .geo import EARTH_MEAN_RADIUS_M, GeoPoint, haversine_m
from .polygon import Polygon
from .regions import Circle, Intersection, Region

__all__ = ["LATCH_TRANSITIONS", "Edge", "Latch", "LatchEvent", "Presence", "Sense", "sense_of", "sense_when",
           "signed_distance_m"]


# --- distance to a region's edge -------------------------------------------------------------
def signed_distance_m(region: Region, point: GeoPoint) -> float:
    """Metres from `point` to the edge of `region`: negative inside, positive outside.

    Circle: haversine to the centre minus the radius (exact on the sphere of `geo`).
    Polygon: the distance to the nearest edge in a tangent plane at the point (edges are
    straight in lat/lon, as `Polygon` draws them; the planar error is under 0.1 % within a
    few km), negative when `contains` (exact) says inside, so the sign always agrees with it.
    Intersection: the largest of its parts' distances: "at least m inside every part" is
    exactly "the m-disc lies in the intersection".
    """
    if isinstance(region, Circle):
        return haversine_m(region.center, point) - region.radius_m
    if isinstance(region, Polygon):
        d = _distance_to_outline_m(region, point)
        return -d if region.contains(point) else max(d, math.ulp(0.0))
    if isinstance(region, Intersection):
        return max(signed_distance_m(r, point) for r in region.regions)
    raise TypeError(f"no distance to the edge of {type(region).__name__}: a margin needs a "
                    "Circle, Polygon or Intersection of them")


def _distance_to_outline_m(polygon: Polygon, point: GeoPoint) -> float:
    """Distance to the nearest edge, in a local east/north plane (metres) centred on the point."""
    lat0 = float(point.lat)
    k = math.pi / 180.0 * EARTH_MEAN_RADIUS_M
    kx = k * math.cos(math.radians(lat0))

    def local(v: GeoPoint) -> tuple[float, float]:
        dlon = float(v.lon) - float(point.lon)
        dlon = dlon - 360.0 if dlon > 180.0 else dlon + 360.0 if dlon < -180.0 else dlon
        return dlon * kx, (float(v.lat) - lat0) * k

    pts = [local(v) for v in polygon.vertices]
    best = math.inf
    for (ax, ay), (bx, by) in zip(pts, pts[1:] + pts[:1]):
        dx, dy = bx - ax, by - ay
        span = dx * dx + dy * dy
        t = 0.0 if span == 0.0 else min(1.0, max(0.0, -(ax * dx + ay * dy) / span))
        best = min(best, math.hypot(ax + t * dx, ay + t * dy))
    return best


# --- one observation ---------------------------------------------------------------------------
class Sense(Enum):
    """Where one position lies relative to a region, given the margin."""

    INSIDE = "inside by at least the margin"
    BORDER = "within the margin of the edge"
    OUTSIDE = "outside by more than the margin"


def sense_of(region: Region, point: GeoPoint, margin_m: float) -> Sense:
    """Classify `point`. With no margin only `contains` is asked (exact, any Region; a point
    on the edge is inside, as regions are closed)."""
    if margin_m <= 0:
        return Sense.INSIDE if region.contains(point) else Sense.OUTSIDE
    d = signed_distance_m(region, point)
    return Sense.INSIDE if d <= -margin_m else Sense.OUTSIDE if d > margin_m else Sense.BORDER


def sense_when(condition: bool) -> Sense:
    """A yes/no condition (the waypoint method's "this leg is G's") as an observation."""
    return Sense.INSIDE if condition else Sense.OUTSIDE


# --- the latch ---------------------------------------------------------------------------------
class Presence(Enum):
    OUT = "out"
    ENTERING = "inside, dwelling before it counts"
    IN = "in"
    LEAVING = "outside, dwelling before it counts"


class LatchEvent(Enum):
    INSIDE = "observed inside (beyond the margin)"
    BORDER = "observed within the margin"
    OUTSIDE = "observed outside (beyond the margin)"
    SETTLED = "the dwell time passed without a contrary observation"


_P, _L = Presence, LatchEvent
LATCH_TRANSITIONS: dict[tuple[Presence, LatchEvent], Presence] = {
    (_P.OUT, _L.INSIDE): _P.ENTERING,
    (_P.OUT, _L.BORDER): _P.OUT,
    (_P.OUT, _L.OUTSIDE): _P.OUT,
    (_P.ENTERING, _L.INSIDE): _P.ENTERING,
    (_P.ENTERING, _L.BORDER): _P.OUT,        # not inside any more: the dwell starts again
    (_P.ENTERING, _L.OUTSIDE): _P.OUT,
    (_P.ENTERING, _L.SETTLED): _P.IN,
    (_P.IN, _L.INSIDE): _P.IN,
    (_P.IN, _L.BORDER): _P.IN,
    (_P.IN, _L.OUTSIDE): _P.LEAVING,
    (_P.LEAVING, _L.INSIDE): _P.IN,
    (_P.LEAVING, _L.BORDER): _P.IN,          # not outside any more: the dwell starts again
    (_P.LEAVING, _L.OUTSIDE): _P.LEAVING,
    (_P.LEAVING, _L.SETTLED): _P.OUT,
}
_BY_SENSE = {Sense.INSIDE: _L.INSIDE, Sense.BORDER: _L.BORDER, Sense.OUTSIDE: _L.OUTSIDE}


class Edge(Enum):
    ENTERED = "entered"
    EXITED = "exited"


class Latch:
    """One region's debounced presence. `observe(sense, at)` returns ENTERED or EXITED on the
    observation that settles an entry or an exit, else None. Times are the positions' own;
    they must not go backwards (a stale position is the caller's to drop)."""

    def __init__(self, dwell: float, *, initial: Presence = Presence.OUT,
                 on_move: Callable[[Presence, LatchEvent, Presence], None] | None = None) -> None:
        if not (math.isfinite(dwell) and dwell >= 0):
            raise ValueError(f"dwell must be a finite number of seconds >= 0, got {dwell!r}")
        if initial not in (Presence.OUT, Presence.IN):
            raise ValueError("a latch starts OUT or IN")
        self.dwell = dwell
        self.state = initial
        self.since: float | None = None      # when the current ENTERING / LEAVING began
        self._on_move = on_move

    @property
    def inside(self) -> bool:
        """Counted as in (IN, or LEAVING but not yet out)."""
        return self.state in (Presence.IN, Presence.LEAVING)

    def observe(self, sense: Sense, at: float) -> Edge | None:
        before = self.state
        self._move(_BY_SENSE[sense])
        if self.state in (Presence.ENTERING, Presence.LEAVING):
            if self.state is not before:
                self.since = at
            if at - self.since >= self.dwell:
                self._move(LatchEvent.SETTLED)
        if self.state not in (Presence.ENTERING, Presence.LEAVING):
            self.since = None
        if self.state is Presence.IN and before in (Presence.OUT, Presence.ENTERING):
            return Edge.ENTERED
        if self.state is Presence.OUT and before in (Presence.IN, Presence.LEAVING):
            return Edge.EXITED
        return None

    def _move(self, event: LatchEvent) -> None:
        old = self.state
        self.state = next_state(LATCH_TRANSITIONS, old, event, "region latch")
        if self._on_move is not None:
            self._on_move(old, event, self.state)
