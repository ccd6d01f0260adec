"""Hypothesis strategies for plans each file format can hold exactly, and a scratch directory."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import strategies as st

from mavconform.reference_impl.files import Plan, plan_from_items
from mavconform.reference_impl.files.plan import MissionSettings
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import INT32_MAX, INT32_MIN, MissionItem

# Frames whose x/y scale differs (global degE7, local metres*1e4, raw), then anything.
frames = st.one_of(st.sampled_from([0, 1, 2, 3, 4, 6, 10, 12]), st.integers(0, 255))
int32s = st.integers(INT32_MIN, INT32_MAX)
float32s = st.floats(width=32)  # NaN and infinities included: WPL text holds them
json_float32s = st.floats(width=32, allow_infinity=False)  # JSON has null for NaN, no infinity
latitudes_e7 = st.integers(-900_000_000, 900_000_000)
longitudes_e7 = st.integers(-1_800_000_000, 1_800_000_000)


@st.composite
def mission_items(draw, params=float32s, currents=st.integers(0, 1)) -> MissionItem:
    return MissionItem(
        seq=0, frame=draw(frames), command=draw(st.integers(0, 65535)),
        param1=draw(params), param2=draw(params), param3=draw(params), param4=draw(params),
        x=draw(int32s), y=draw(int32s), z=draw(params),
        current=draw(currents), autocontinue=draw(st.integers(0, 1)),
    )


def _position(command: int, frame: int, lat: int, lon: int, param1: float = 0.0, z: float = 0.0) -> MissionItem:
    return MissionItem(seq=0, frame=frame, command=command, param1=param1, x=lat, y=lon, z=z, autocontinue=0)


@st.composite
def fence_items(draw) -> list[MissionItem]:
    """Fence items in the form a .plan file reads into: polygons, circles, return point."""
    items = []
    for inclusion, vertices in draw(st.lists(st.tuples(
            st.booleans(), st.lists(st.tuples(latitudes_e7, longitudes_e7), min_size=3, max_size=6)),
            max_size=3)):
        command = Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION if inclusion else Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION
        items += [_position(command, 0, lat, lon, param1=float(len(vertices))) for lat, lon in vertices]
    positive_radii = st.floats(width=32, min_value=0.0009765625, max_value=1e6)
    for inclusion, lat, lon, radius in draw(st.lists(
            st.tuples(st.booleans(), latitudes_e7, longitudes_e7, positive_radii), max_size=3)):
        command = Cmd.NAV_FENCE_CIRCLE_INCLUSION if inclusion else Cmd.NAV_FENCE_CIRCLE_EXCLUSION
        items.append(_position(command, 0, lat, lon, param1=radius))
    if draw(st.booleans()):
        alt = draw(st.floats(width=32, allow_nan=False, allow_infinity=False))
        items.append(_position(Cmd.NAV_FENCE_RETURN_POINT, 3, draw(latitudes_e7), draw(longitudes_e7), z=alt))
    return items


rally_items = st.lists(st.builds(
    lambda lat, lon, alt: _position(Cmd.NAV_RALLY_POINT, 3, lat, lon, z=alt),
    latitudes_e7, longitudes_e7, st.floats(width=32, allow_nan=False, allow_infinity=False)), max_size=4)

homes = st.one_of(st.none(), st.tuples(
    st.floats(-90, 90), st.floats(-180, 180), st.floats(allow_nan=False, allow_infinity=False)))


settings = st.builds(
    MissionSettings, st.integers(0, 255), st.integers(0, 255),
    st.floats(0, 100, allow_nan=False), st.floats(0, 100, allow_nan=False))


@st.composite
def qgc_plans(draw) -> Plan:
    """Plans a .plan file holds exactly (no `current` flags, no infinite params; a DO_JUMP's
    target is an item of the mission, as a .plan names it by that item's doJumpId)."""
    mission = draw(st.lists(mission_items(json_float32s, st.just(0)).filter(
        lambda item: item.command != Cmd.DO_JUMP), max_size=6))
    if mission and draw(st.booleans()):
        where = draw(st.integers(0, len(mission)))
        target = draw(st.integers(0, len(mission)))   # the list grows by the jump itself
        mission.insert(where, MissionItem(seq=0, frame=2, command=Cmd.DO_JUMP, param1=float(target),
                                          param2=float(draw(st.integers(-1, 10)))))
    return plan_from_items(mission, draw(fence_items()), draw(rally_items), draw(homes), draw(settings))


@st.composite
def wpl_plans(draw) -> Plan:
    """Plans a WPL file holds exactly: a mission only."""
    return plan_from_items(draw(st.lists(mission_items(), max_size=6)))


@pytest.fixture(scope="module")
def scratch_dir(tmp_path_factory) -> Path:
    """Module-scoped so Hypothesis examples may share it (each example overwrites its file)."""
    return tmp_path_factory.mktemp("plans")
