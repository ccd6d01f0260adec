"""A handover scenario and its flight drawn as one self-contained SVG map.

Drawn by hand, like sequence_svg, so a report stays one file that reads without scripts or
map tiles: each GCS's coverage (semi-transparent, labelled), the handover region (where two
coverages overlap: the second coverage hatched inside the first's clip path, so the region
is drawn exactly, with no polygon clipping here to get wrong), the planned route dashed, the
flown track coloured by the GCS in command on each segment, every handover numbered, home
and rally points, a legend and a scale bar. Styling is by presentation attributes, so the
file looks the same opened alone or inlined in a page; ids carry `id_prefix`, so several
maps can share a page. Same input, same bytes: every number is printed with fixed decimals
and nothing depends on set or hash order.

Projection: equirectangular about the centre (lat0, lon0) of everything drawn,
x = R * dlon * cos(lat0), y = R * dlat, on the sphere of `geo` (R = 6371008.8 m). North is
up. Distances north-south are true; east-west they are scaled by cos(lat) / cos(lat0), which
is off by about tan|lat0| * dlat (radians): 0.04 % (1 m) at 2.5 km from the centre at 47 N,
0.4 % at 25 km; near the poles use a smaller map. Polygon edges are straight lines in
(lon, lat), exactly as the polygon test treats them, and stay straight and exact here;
circles are drawn through points on the sphere (`geo.destination`), so only the scaling
above distorts them. The scale bar is true at the centre's latitude.
"""

from __future__ import annotations

import math
from html import escape
from typing import NamedTuple, Sequence

from mavconform.reference_impl.handover.geo import EARTH_MEAN_RADIUS_M, GeoPoint, destination
from mavconform.reference_impl.handover.regions import Circle, Polygon, RegionMethod
from mavconform.reference_impl.handover.scenario import Scenario, seq_ranges

__all__ = ["GCS_COLOURS", "NO_OWNER_COLOUR", "Mark", "TrackSample", "handover_map", "owner_colours"]

# Primer's (html.py's) strong colours, one per GCS in scenario order; more GCSs wrap round.
GCS_COLOURS = ("#0969da", "#bc4c00", "#8250df", "#1a7f37", "#bf3989", "#1b7c83", "#9a6700", "#cf222e")
NO_OWNER_COLOUR = "#6e7781"      # no GCS in command (before the start, during an emergency)
INK, MUTED, PAPER = "#1f2328", "#57606a", "#ffffff"
COVERAGE_OPACITY = 0.14
CIRCLE_STEPS = 96                # outline points of a coverage circle
MIN_SPAN_M = 200.0               # a map of a single point still shows 200 m around it
PAD = 0.06                       # of the span, around everything drawn
MARGIN, TITLE_H, FOOT_H, LEGEND_W = 14, 30, 30, 230
MIN_PX_STEP = 0.5                # track points closer than this to the last one drawn are skipped
MAX_LISTED = 12                  # handovers listed in the legend; the rest are counted


class TrackSample(NamedTuple):
    """Where the vehicle was at time `t` and which GCS was in command (None: none)."""

    t: float
    lat: float
    lon: float
    owner: str | None


class Mark(NamedTuple):
    """An extra labelled point (an emergency's start, a refuge chosen), drawn as a diamond."""

    lat: float
    lon: float
    label: str


class _Projection:
    """Equirectangular about (lat0, lon0), metres east/north, then pixels (see the module doc)."""

    def __init__(self, lat0: float, lon0: float) -> None:
        self.lat0, self.lon0 = lat0, lon0
        self.k = EARTH_MEAN_RADIUS_M * math.pi / 180.0
        self.kx = self.k * math.cos(math.radians(lat0))
        self.scale, self.ox, self.oy = 1.0, 0.0, 0.0

    def metres(self, lat: float, lon: float) -> tuple[float, float]:
        dlon = (float(lon) - self.lon0 + 540.0) % 360.0 - 180.0
        return dlon * self.kx, (float(lat) - self.lat0) * self.k

    def fit(self, east: tuple[float, float], north: tuple[float, float], left: float, top: float,
            width: float, height: float) -> None:
        """Map the box [east] x [north] (metres) into the pixel box, centred, north up."""
        self.scale = min(width / (east[1] - east[0]), height / (north[1] - north[0]))
        self.ox = left + (width - (east[1] - east[0]) * self.scale) / 2 - east[0] * self.scale
        self.oy = top + (height - (north[1] - north[0]) * self.scale) / 2 + north[1] * self.scale

    def px(self, lat: float, lon: float) -> tuple[float, float]:
        e, n = self.metres(lat, lon)
        return self.ox + e * self.scale, self.oy - n * self.scale


def _f(v: float) -> str:
    """A pixel coordinate, fixed to 0.1 px ('-0.0' never appears)."""
    text = f"{v:.1f}"
    return "0.0" if text == "-0.0" else text


def _pts(points: Sequence[tuple[float, float]]) -> str:
    return " ".join(f"{_f(x)},{_f(y)}" for x, y in points)


def _outline(coverage: Circle | Polygon) -> list[GeoPoint]:
    if isinstance(coverage, Circle):
        return [destination(coverage.center, 360.0 * i / CIRCLE_STEPS, coverage.radius_m)
                for i in range(CIRCLE_STEPS)]
    return list(coverage.vertices)


def _label_anchor(coverage: Circle | Polygon) -> tuple[float, float]:
    if isinstance(coverage, Circle):
        return float(coverage.center.lat), float(coverage.center.lon)
    vs = coverage.vertices
    return (sum(float(v.lat) for v in vs) / len(vs), sum(float(v.lon) for v in vs) / len(vs))


def owner_colours(scenario: Scenario, owners: Sequence[str | None] = ()) -> dict[str | None, str]:
    """The colour of each owner: GCSs in scenario order, then unknown names in order of first
    appearance, None grey. The legend and the tests read the same table."""
    colours: dict[str | None, str] = {None: NO_OWNER_COLOUR}
    for i, g in enumerate(scenario.gcs):
        colours[g.name] = GCS_COLOURS[i % len(GCS_COLOURS)]
    for owner in owners:
        if owner not in colours:
            colours[owner] = GCS_COLOURS[(len(colours) - 1) % len(GCS_COLOURS)]
    return colours


def _nice_length(max_m: float) -> float:
    """The largest 1, 2 or 5 x 10^k metres not over max_m."""
    k = 10 ** math.floor(math.log10(max_m))
    for step in (5, 2, 1):
        if step * k <= max_m:
            return step * k
    return k


def _distance_text(metres: float) -> str:
    return f"{metres / 1000:g} km" if metres >= 1000 else f"{metres:g} m"


def _text(x: float, y: float, content: str, *, size: int = 12, anchor: str = "start", weight: str = "normal",
          fill: str = INK, halo: bool = False, cls: str = "") -> str:
    extra = (f' stroke="{PAPER}" stroke-width="3" stroke-linejoin="round" paint-order="stroke"' if halo else "")
    klass = f' class="{cls}"' if cls else ""
    bold = f' font-weight="{weight}"' if weight != "normal" else ""
    return (f'<text{klass} x="{_f(x)}" y="{_f(y)}" font-size="{size}" text-anchor="{anchor}"{bold} '
            f'fill="{fill}"{extra}>{escape(content)}</text>')


def _samples(track: Sequence[TrackSample | tuple]) -> list[TrackSample]:
    out = []
    for i, s in enumerate(track):
        t, lat, lon, owner = s
        for name, v in (("t", t), ("lat", lat), ("lon", lon)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"track[{i}].{name} must be a finite number, got {v!r}")
        if owner is not None and not isinstance(owner, str):
            raise ValueError(f"track[{i}].owner must be a GCS name or None, got {owner!r}")
        out.append(TrackSample(float(t), float(lat), float(lon), owner))
    return out


def handover_map(scenario: Scenario, track: Sequence[TrackSample | tuple] = (), *,
                 marks: Sequence[Mark | tuple] = (), title: str | None = None, width: int = 960,
                 id_prefix: str = "hmap") -> str:
    """The scenario (and the flight, if `track` is given) as an <svg> document string.

    `track`: (t, lat, lon, owner) samples in time order; each segment between two samples is
    drawn in the colour of the first sample's owner, and every change of owner is a numbered
    handover point where the new owner's first sample is.
    """
    samples = _samples(track)
    extra = [Mark(float(m[0]), float(m[1]), str(m[2])) for m in marks]
    geographic = scenario.region_method is not RegionMethod.WAYPOINTS
    outlines = {g.name: _outline(g.coverage) for g in scenario.gcs} if geographic else {}  # type: ignore[arg-type]
    route = [w.point for w in scenario.flight.waypoints]

    # Extent of everything drawn, and the projection about its centre.
    lats = [float(p.lat) for ps in outlines.values() for p in ps] + [float(p.lat) for p in route]
    lons = [float(p.lon) for ps in outlines.values() for p in ps] + [float(p.lon) for p in route]
    lats += [float(pt.lat) for pt in (scenario.home, *scenario.rally)]
    lons += [float(pt.lon) for pt in (scenario.home, *scenario.rally)]
    lats += [s.lat for s in samples] + [m.lat for m in extra]
    lons += [s.lon for s in samples] + [m.lon for m in extra]
    proj = _Projection((min(lats) + max(lats)) / 2, (min(lons) + max(lons)) / 2)
    xy = [proj.metres(la, lo) for la, lo in zip(lats, lons)]
    east = [min(x for x, _ in xy), max(x for x, _ in xy)]
    north = [min(y for _, y in xy), max(y for _, y in xy)]
    for box in (east, north):
        span = max(box[1] - box[0], MIN_SPAN_M)
        mid = (box[0] + box[1]) / 2
        box[0], box[1] = mid - span * (0.5 + PAD), mid + span * (0.5 + PAD)
    map_w = width - LEGEND_W - 3 * MARGIN
    aspect = (north[1] - north[0]) / (east[1] - east[0])
    map_h = max(320.0, min(map_w * aspect, 1.4 * map_w))
    left, top = MARGIN, TITLE_H + MARGIN
    proj.fit((east[0], east[1]), (north[0], north[1]), left, top, map_w, map_h)
    height = int(math.ceil(top + map_h + FOOT_H + MARGIN))

    owners_seen = [s.owner for s in samples]
    colours = owner_colours(scenario, owners_seen)
    p = escape(id_prefix, quote=True)
    out: list[str] = []
    heading = title if title is not None else scenario.name
    out.append(f'<svg class="handover-map" xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
               f'viewBox="0 0 {width} {height}" font-family="system-ui, sans-serif" role="img" '
               f'aria-label="{escape("map: " + heading, quote=True)}">')
    out.append(f'<rect x="0" y="0" width="{width}" height="{height}" fill="{PAPER}"/>')

    # Definitions: the hatch of the handover region, and each coverage as a clip path.
    out.append("<defs>")
    out.append(f'<pattern id="{p}-hatch" patternUnits="userSpaceOnUse" width="8" height="8" '
               f'patternTransform="rotate(45)"><rect width="8" height="8" fill="{INK}" fill-opacity="0.10"/>'
               f'<line x1="0" y1="0" x2="0" y2="8" stroke="{INK}" stroke-width="2.2" stroke-opacity="0.45"/></pattern>')
    shape_pts = {name: _pts([proj.px(float(v.lat), float(v.lon)) for v in ps]) for name, ps in outlines.items()}
    for i, g in enumerate(scenario.gcs):
        if g.name in shape_pts:
            out.append(f'<clipPath id="{p}-cov-{i}"><polygon points="{shape_pts[g.name]}"/></clipPath>')
    out.append("</defs>")
    out.append(_text(MARGIN, TITLE_H - 6, heading, size=16, weight="600"))
    out.append(f'<rect x="{_f(left)}" y="{_f(top)}" width="{_f(map_w)}" height="{_f(map_h)}" fill="#f6f8fa" '
               f'stroke="#d0d7de"/>')

    # Coverage, then the handover regions over it.
    for i, g in enumerate(scenario.gcs):
        if g.name in shape_pts:
            c = colours[g.name]
            out.append(f'<polygon class="coverage" data-gcs="{escape(g.name, quote=True)}" '
                       f'points="{shape_pts[g.name]}" fill="{c}" fill-opacity="{COVERAGE_OPACITY}" '
                       f'stroke="{c}" stroke-width="1.5"/>')
    gcs_index = {g.name: i for i, g in enumerate(scenario.gcs)}
    for a, b, _ in scenario.handover_regions():
        out.append(f'<g class="handover-region" data-gcs="{escape(a, quote=True)} {escape(b, quote=True)}" '
                   f'clip-path="url(#{p}-cov-{gcs_index[a]})"><polygon points="{shape_pts[b]}" '
                   f'fill="url(#{p}-hatch)"/></g>')

    # The planned route (dashed; under the waypoint method each leg in its owner's colour).
    ownership = scenario.ownership()
    wps = scenario.flight.waypoints
    for k in range(len(wps) - 1):
        owner = ownership.owner(wps[k].seq) if ownership is not None else None
        colour = colours.get(owner, NO_OWNER_COLOUR) if ownership is not None else MUTED
        (x1, y1), (x2, y2) = proj.px(wps[k].point.lat, wps[k].point.lon), proj.px(wps[k + 1].point.lat,
                                                                                  wps[k + 1].point.lon)
        owner_attr = f' data-owner="{escape(owner, quote=True)}"' if owner is not None else ""
        out.append(f'<line class="planned"{owner_attr} x1="{_f(x1)}" y1="{_f(y1)}" x2="{_f(x2)}" y2="{_f(y2)}" '
                   f'stroke="{colour}" stroke-width="1.5" stroke-dasharray="6 4" stroke-opacity="0.9"/>')

    # The flown track: one polyline per run of one owner, joined to the next run's first point.
    handovers: list[tuple[int, TrackSample, str | None, str | None]] = []
    start = 0
    for i in range(1, len(samples) + 1):
        if i < len(samples) and samples[i].owner == samples[start].owner:
            continue
        run = samples[start:i + 1] if i < len(samples) else samples[start:i]
        owner = samples[start].owner
        pts: list[tuple[float, float]] = []
        for s in run:
            q = proj.px(s.lat, s.lon)
            if pts and s is not run[-1] and math.hypot(q[0] - pts[-1][0], q[1] - pts[-1][1]) < MIN_PX_STEP:
                continue
            pts.append(q)
        if len(pts) == 1:
            pts.append(pts[0])
        name = "none" if owner is None else owner
        dash = ' stroke-dasharray="2 3"' if owner is None else ""
        out.append(f'<polyline class="leg" data-owner="{escape(name, quote=True)}" '
                   f'data-t0="{samples[start].t:.3f}" points="{_pts(pts)}" fill="none" '
                   f'stroke="{colours[owner]}" stroke-width="3.5" stroke-linecap="round" '
                   f'stroke-linejoin="round"{dash}/>')
        if i < len(samples):
            handovers.append((len(handovers) + 1, samples[i], owner, samples[i].owner))
            start = i

    # GCS names (and sites, for circles), then waypoints, rally points, home, handover points and
    # extra marks, on top of the lines.
    for label_lat_lon, g in ((_label_anchor(g.coverage), g) for g in scenario.gcs if g.name in shape_pts):  # type: ignore[arg-type]
        x, y = proj.px(*label_lat_lon)
        if isinstance(g.coverage, Circle):
            out.append(f'<circle class="gcs-site" cx="{_f(x)}" cy="{_f(y)}" r="4" fill="{colours[g.name]}"/>')
            y -= 14
        out.append(_text(x, y, f"GCS {g.name}", size=14, anchor="middle", weight="700", fill=colours[g.name],
                         halo=True, cls="gcs-label"))
    at: dict[tuple[str, str], list[int]] = {}        # waypoints drawn on one spot share a label
    for w in wps:
        x, y = proj.px(w.point.lat, w.point.lon)
        at.setdefault((_f(x), _f(y)), []).append(w.seq)
    for (x_text, y_text), seqs in at.items():
        names = ", ".join(map(str, seqs))
        out.append(f'<circle class="waypoint" cx="{x_text}" cy="{y_text}" r="3" fill="{PAPER}" stroke="{MUTED}" '
                   f'stroke-width="1.2"><title>waypoint {names}</title></circle>')
        out.append(_text(float(x_text) + 5, float(y_text) - 5, names, size=10, fill=MUTED, halo=True,
                         cls="waypoint-label"))
    for i, r in enumerate(scenario.rally):
        x, y = proj.px(r.lat, r.lon)
        out.append(f'<g class="rally"><title>rally point {i}</title>'
                   f'<polygon points="{_pts([(x, y - 8), (x + 7, y + 5), (x - 7, y + 5)])}" fill="#2da44e" '
                   f'stroke="{INK}" stroke-width="1"/></g>')
        out.append(_text(x + 9, y + 4, f"R{i}", size=11, weight="600", halo=True, cls="rally-label"))
    hx, hy = proj.px(scenario.home.lat, scenario.home.lon)
    out.append(f'<g class="home"><title>home (launch point)</title><rect x="{_f(hx - 7)}" y="{_f(hy - 7)}" '
               f'width="14" height="14" fill="{INK}"/>{_text(hx, hy + 4, "H", size=11, anchor="middle", weight="700", fill=PAPER)}</g>')
    for n, s, before, after in handovers:
        x, y = proj.px(s.lat, s.lon)
        what = f"handover {n}: {before or 'none'} -> {after or 'none'} at t = {s.t:.1f} s"
        out.append(f'<g class="handover-point" data-n="{n}"><title>{escape(what)}</title>'
                   f'<circle cx="{_f(x)}" cy="{_f(y)}" r="9" fill="{PAPER}" stroke="{INK}" stroke-width="2"/>'
                   f'{_text(x, y + 4, str(n), size=11, anchor="middle", weight="700")}</g>')
    for m in extra:
        x, y = proj.px(m.lat, m.lon)
        out.append(f'<g class="mark"><title>{escape(m.label)}</title><polygon points="'
                   f'{_pts([(x, y - 7), (x + 7, y), (x, y + 7), (x - 7, y)])}" fill="#cf222e" stroke="{INK}"/>'
                   f'{_text(x + 10, y + 4, m.label, size=11, halo=True)}</g>')

    # Below the map, so they never hide what is drawn: the scale bar, and north.
    foot = top + map_h + FOOT_H - 6
    out += _scale_bar(proj, left, foot, map_w)
    nx = left + map_w - 8
    out.append(f'<g class="north"><polygon points="{_pts([(nx, foot - 16), (nx + 5, foot - 4), (nx - 5, foot - 4)])}" '
               f'fill="{MUTED}"/>{_text(nx - 9, foot - 4, "N", size=12, anchor="end", weight="700", fill=MUTED)}</g>')
    out += _legend(scenario, colours, owners_seen, handovers, extra, geographic, p,
                   left + map_w + 2 * MARGIN, top)
    out.append("</svg>")
    return "\n".join(out) + "\n"


def _scale_bar(proj: _Projection, left: float, y0: float, map_w: float) -> list[str]:
    """A bar of a round length (1, 2 or 5 x 10^k m) at most 30 % of the map's width."""
    metres = _nice_length(map_w * 0.3 / proj.scale)
    px = metres * proj.scale
    x0 = left + 6
    half = px / 2
    return [f'<g class="scale-bar" data-metres="{metres:g}">',
            f'<rect x="{_f(x0)}" y="{_f(y0 - 5)}" width="{_f(half)}" height="5" fill="{INK}"/>',
            f'<rect x="{_f(x0 + half)}" y="{_f(y0 - 5)}" width="{_f(half)}" height="5" fill="{PAPER}" stroke="{INK}"/>',
            _text(x0 + px + 6, y0, _distance_text(metres), size=11),
            "</g>"]


def _legend(scenario: Scenario, colours: dict[str | None, str], owners_seen: Sequence[str | None],
            handovers: list[tuple[int, TrackSample, str | None, str | None]], extra: list[Mark],
            geographic: bool, prefix: str, x: float, y: float) -> list[str]:
    out = ['<g class="legend">', _text(x, y + 12, "Legend", size=13, weight="700")]
    row = y + 34
    ownership = scenario.ownership()

    def line(label: str, swatch: str) -> None:
        nonlocal row
        out.append(swatch)
        out.append(_text(x + 34, row + 4, label, size=12))
        row += 22

    for g in scenario.gcs:
        c = colours[g.name]
        if geographic:
            swatch = (f'<rect x="{_f(x)}" y="{_f(row - 7)}" width="26" height="14" fill="{c}" '
                      f'fill-opacity="{COVERAGE_OPACITY * 2}" stroke="{c}"/>'
                      f'<line x1="{_f(x)}" y1="{_f(row)}" x2="{_f(x + 26)}" y2="{_f(row)}" stroke="{c}" stroke-width="3.5"/>')
            line(f"GCS {g.name} (sysid {g.sysid})", swatch)
        else:
            assert ownership is not None
            seqs = [seq for seq, owner in ownership.assignments.items() if owner == g.name]
            line(f"GCS {g.name} (sysid {g.sysid})", f'<line x1="{_f(x)}" y1="{_f(row)}" x2="{_f(x + 26)}" '
                                                   f'y2="{_f(row)}" stroke="{c}" stroke-width="3.5"/>')
            out.append(_text(x + 34, row - 6, f"owns waypoints {seq_ranges(seqs, '-') or 'none'}", size=11, fill=MUTED))
            row += 12
    out.append(_text(x, row, "area: coverage; line: in command" if geographic else "line: in command",
                     size=11, fill=MUTED))
    row += 20
    for owner in dict.fromkeys(o for o in owners_seen if o is not None and o not in {g.name for g in scenario.gcs}):
        line(f"{owner} (not in the scenario)",
             f'<line x1="{_f(x)}" y1="{_f(row)}" x2="{_f(x + 26)}" y2="{_f(row)}" stroke="{colours[owner]}" '
             f'stroke-width="3.5"/>')
    if None in owners_seen:
        line("no GCS in command", f'<line x1="{_f(x)}" y1="{_f(row)}" x2="{_f(x + 26)}" y2="{_f(row)}" '
                                  f'stroke="{NO_OWNER_COLOUR}" stroke-width="3.5" stroke-dasharray="2 3"/>')
    if geographic and len(scenario.gcs) > 1:
        line("handover region (overlap)", f'<rect x="{_f(x)}" y="{_f(row - 7)}" width="26" height="14" '
                                          f'fill="url(#{prefix}-hatch)" stroke="{INK}" stroke-width="0.5"/>')
    line("planned route", f'<line x1="{_f(x)}" y1="{_f(row)}" x2="{_f(x + 26)}" y2="{_f(row)}" stroke="{MUTED}" '
                          f'stroke-width="1.5" stroke-dasharray="6 4"/>')
    line("home (launch point)", f'<rect x="{_f(x + 6)}" y="{_f(row - 7)}" width="14" height="14" fill="{INK}"/>')
    if scenario.rally:
        line(f"rally point ({len(scenario.rally)})",
             f'<polygon points="{_pts([(x + 13, row - 8), (x + 20, row + 5), (x + 6, row + 5)])}" fill="#2da44e" '
             f'stroke="{INK}" stroke-width="1"/>')
    if handovers:
        line("handover point, numbered", f'<circle cx="{_f(x + 13)}" cy="{_f(row)}" r="8" fill="{PAPER}" '
                                         f'stroke="{INK}" stroke-width="2"/>')
    if extra:
        line("marked event", f'<polygon points="{_pts([(x + 13, row - 7), (x + 20, row), (x + 13, row + 7), (x + 6, row)])}" '
                             f'fill="#cf222e" stroke="{INK}"/>')
    if handovers:
        row += 8
        out.append(_text(x, row, "Handovers", size=13, weight="700"))
        row += 18
        for n, s, before, after in handovers[:MAX_LISTED]:
            out.append(_text(x, row, f"{n}. {before or 'none'} \u2192 {after or 'none'}  t = {s.t:.1f} s",
                             size=12, cls="handover-entry"))
            row += 17
        if len(handovers) > MAX_LISTED:
            out.append(_text(x, row, f"\u2026 {len(handovers) - MAX_LISTED} more", size=12, fill=MUTED))
    out.append("</g>")
    return out

