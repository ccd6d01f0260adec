"""The handover map: renders every shipped scenario, colours each leg by its owner, same bytes twice."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import pytest

from mavconform.reference_impl.handover.geo import GeoPoint, destination, haversine_m
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, load_scenario, scenario_from_dict
from mavconform.reports.handover_map import NO_OWNER_COLOUR, Mark, TrackSample, handover_map, owner_colours

SVG = "{http://www.w3.org/2000/svg}"
# the delivery flight in its three region methods (the conformance scenario is a short hop with
# no rally points, flown by the HO.SEQ clauses: tests/conformance/test_handover_sequence_clauses.py)
SHIPPED = sorted(p.name for p in SCENARIOS_DIR.glob("delivery_flight*.json"))


def parse(svg: str) -> ET.Element:
    root = ET.fromstring(svg)
    assert root.tag == f"{SVG}svg"
    return root


def flown(scenario, owner_at) -> list[TrackSample]:
    """A track along the route, a sample every ~25 m, 2 s apart; owner_at(index, point) names the owner."""
    pts = [w.point for w in scenario.flight.waypoints]
    track: list[TrackSample] = []
    for a, b in zip(pts, pts[1:]):
        n = max(1, int(haversine_m(a, b) / 25))
        for k in range(n):
            p = GeoPoint(a.lat + (b.lat - a.lat) * k / n, a.lon + (b.lon - a.lon) * k / n)
            track.append(TrackSample(2.0 * len(track), p.lat, p.lon, owner_at(len(track), p)))
    return track


def geographic_owner(scenario):
    """The commander as the thesis hands it over: switch when the vehicle is covered by the other GCS only."""
    state = {"owner": scenario.parent}

    def owner_at(_: int, p: GeoPoint) -> str:
        covering = scenario.covering(p)
        if len(covering) == 1:
            state["owner"] = covering[0]
        return state["owner"]
    return owner_at


def runs(track: list[TrackSample]) -> list[str | None]:
    return [s.owner for i, s in enumerate(track) if i == 0 or s.owner != track[i - 1].owner]


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_scenario_renders(name: str) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    root = parse(handover_map(s))
    assert root.findall(f".//{SVG}polyline[@class='leg']") == []            # no flight yet: the plan only
    assert len(root.findall(f".//{SVG}line[@class='planned']")) == len(s.flight.waypoints) - 1
    assert len(root.findall(f".//{SVG}g[@class='rally']")) == len(s.rally) == 3
    assert len(root.findall(f".//{SVG}g[@class='home']")) == 1
    coverage = root.findall(f".//{SVG}polygon[@class='coverage']")
    regions = root.findall(f".//{SVG}g[@class='handover-region']")
    if s.geographic:
        assert [c.get("data-gcs") for c in coverage] == ["A", "B"]
        assert [r.get("data-gcs") for r in regions] == ["A B"]
        assert regions[0].get("clip-path") == "url(#hmap-cov-0)"
        assert root.find(f".//{SVG}clipPath[@id='hmap-cov-0']") is not None
    else:
        assert coverage == [] and regions == []
        owners = [line.get("data-owner") for line in root.findall(f".//{SVG}line[@class='planned']")]
        assert owners == ["A", "A", "B", "B", "B", "B", "A", "A"]         # the planned legs by ownership
    labels = "".join(root.itertext())
    assert "GCS A" in labels and "GCS B" in labels and "R2" in labels


@pytest.mark.parametrize("name", SHIPPED)
def test_each_leg_is_drawn_in_its_owners_colour(name: str) -> None:
    s = load_scenario(SCENARIOS_DIR / name)
    if s.geographic:
        track = flown(s, geographic_owner(s))
    else:
        seq_owner = s.ownership()
        reached = {"owner": s.parent}
        wps = s.flight.waypoints

        def owner_at(_: int, p: GeoPoint) -> str:
            for w in wps:
                if haversine_m(p, w.point) <= s.flight.acceptance_radius_m:
                    reached["owner"] = seq_owner.owner(w.seq) or reached["owner"]
            return reached["owner"]
        track = flown(s, owner_at)
    assert runs(track) == ["A", "B", "A"]
    root = parse(handover_map(s, track))
    colours = owner_colours(s)
    legs = root.findall(f".//{SVG}polyline[@class='leg']")
    assert [leg.get("data-owner") for leg in legs] == ["A", "B", "A"]
    for leg in legs:
        assert leg.get("stroke") == colours[leg.get("data-owner")]
    assert colours["A"] != colours["B"]
    # Each leg ends where the next begins, so the line is unbroken at a handover.
    ends = [(leg.get("points").split()[0], leg.get("points").split()[-1]) for leg in legs]
    assert all(ends[i][1] == ends[i + 1][0] for i in range(len(ends) - 1))
    points = root.findall(f".//{SVG}g[@class='handover-point']")
    assert [p.get("data-n") for p in points] == ["1", "2"]
    titles = [p.find(f"{SVG}title").text for p in points]
    assert titles[0].startswith("handover 1: A -> B at t = ") and titles[1].startswith("handover 2: B -> A at t = ")
    entries = ["".join(e.itertext()) for e in root.findall(f".//{SVG}text[@class='handover-entry']")]
    assert [e.split("  ")[0] for e in entries] == ["1. A \u2192 B", "2. B \u2192 A"]


def test_no_owner_and_an_unknown_owner_get_their_own_colours() -> None:
    s = load_scenario(SCENARIOS_DIR / "delivery_flight.json")
    owners = [None] * 5 + ["A"] * 30 + ["Z"] * 30 + [None] * 10

    track = flown(s, lambda i, _: owners[min(i, len(owners) - 1)])
    root = parse(handover_map(s, track))
    legs = root.findall(f".//{SVG}polyline[@class='leg']")
    assert [leg.get("data-owner") for leg in legs] == ["none", "A", "Z", "none"]
    assert legs[0].get("stroke") == NO_OWNER_COLOUR and legs[0].get("stroke-dasharray") == "2 3"
    colours = owner_colours(s, ["Z"])
    assert legs[2].get("stroke") == colours["Z"] not in (colours["A"], colours["B"], NO_OWNER_COLOUR)
    text = "".join(root.itertext())
    assert "Z (not in the scenario)" in text and "no GCS in command" in text


def test_the_same_input_gives_the_same_bytes() -> None:
    s = load_scenario(SCENARIOS_DIR / "delivery_flight.json")
    track = flown(s, geographic_owner(s))
    marks = [Mark(47.41, 8.58, "emergency: rally point 1")]
    first = handover_map(s, track, marks=marks)
    again = handover_map(load_scenario(SCENARIOS_DIR / "delivery_flight.json"), [tuple(t) for t in track],
                         marks=[tuple(m) for m in marks])
    assert first == again
    other = handover_map(s, track, marks=marks, id_prefix="second")
    assert other.replace("second-", "hmap-") == first               # only the ids differ
    root = parse(first)
    (mark,) = root.findall(f".//{SVG}g[@class='mark']")
    assert mark.find(f"{SVG}title").text == "emergency: rally point 1"


def _north_flight(length_m: float) -> object:
    start = GeoPoint(47.397742, 8.545594)
    end = destination(start, 0.0, length_m)
    return scenario_from_dict({
        "seed": 1, "region_method": "circle", "parent": "A",
        "gcs": [{"name": "A", "sysid": 250, "coverage": {"circle": {"center": [start.lat, start.lon],
                                                                     "radius_m": length_m * 2}}}],
        "flight": {"speed_m_s": 10, "path": [[start.lat, start.lon, 10], [end.lat, end.lon, 10]]},
        "battery": {"capacity_wh": 50, "consumption_wh_per_m": 0.01},
    }, source="north.json")


@pytest.mark.parametrize("length_m", [150.0, 1000.0, 7300.0, 42000.0])
def test_the_scale_bar_matches_the_drawing(length_m: float) -> None:
    s = _north_flight(length_m)
    root = parse(handover_map(s))
    circles = root.findall(f".//{SVG}circle[@class='waypoint']")
    y0, y1 = (float(c.get("cy")) for c in circles)
    px_per_m = (y0 - y1) / length_m                                       # due north: true length
    bar = root.find(f".//{SVG}g[@class='scale-bar']")
    metres = float(bar.get("data-metres"))
    mantissa = metres / 10 ** math.floor(math.log10(metres))
    assert mantissa in (1.0, 2.0, 5.0)
    width = sum(float(r.get("width")) for r in bar.findall(f"{SVG}rect"))
    assert width / metres == pytest.approx(px_per_m, rel=0.005)


def test_names_are_escaped() -> None:
    data = json.loads((SCENARIOS_DIR / "delivery_flight.json").read_text())
    data["gcs"][1]["name"] = 'B <"&">'
    s = scenario_from_dict(data, source="x.json")
    track = flown(s, geographic_owner(s))
    root = parse(handover_map(s, track, title="a <title> & more"))
    assert 'GCS B <"&">' in "".join(root.itertext())
    assert 'B <"&">' in [leg.get("data-owner") for leg in root.findall(f".//{SVG}polyline[@class='leg']")]


def test_a_track_sample_that_is_not_a_place_is_refused() -> None:
    s = load_scenario(SCENARIOS_DIR / "delivery_flight.json")
    with pytest.raises(ValueError, match=r"track\[1\]\.lat must be a finite number"):
        handover_map(s, [(0.0, 47.4, 8.55, "A"), (1.0, math.nan, 8.55, "A")])
    with pytest.raises(ValueError, match=r"track\[0\]\.owner must be a GCS name or None"):
        handover_map(s, [(0.0, 47.4, 8.55, 3)])


def test_a_long_track_is_thinned_but_keeps_its_ends() -> None:
    s = load_scenario(SCENARIOS_DIR / "delivery_flight.json")
    start = s.flight.waypoints[0].point
    track = [TrackSample(i * 0.01, start.lat + i * 1e-8, start.lon, "A") for i in range(5000)]   # 5.6 m in all
    root = parse(handover_map(s, track))
    (leg,) = root.findall(f".//{SVG}polyline[@class='leg']")
    assert len(leg.get("points").split()) < 20
