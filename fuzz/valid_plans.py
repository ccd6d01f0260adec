"""Plans the reference vehicle accepts, and link fault models: what the tool's own property
tests draw (tests/strategies.py), and the valid items of the fuzzers' plans (wire_items.py).
Float32-exact values, so a round trip compares exactly."""

from __future__ import annotations

import math

from hypothesis import strategies as st

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.net import FaultModel

from .seeded import cached_strategy_builder


f32 = st.floats(width=32, allow_nan=False, allow_infinity=False)
lat = st.integers(-900_000_000, 900_000_000)
lon = st.integers(-1_800_000_000, 1_800_000_000)
alt = st.floats(-500, 10_000, width=32)
GLOBAL = st.sampled_from([0, 3, 5, 6, 10, 11])
# One NaN object for good: Hypothesis labels `just(x)` by hash(x), and a NaN's hash is its
# identity, so a NaN made per draw gave the draw a label that depended on where it was
# allocated, and moving code elsewhere changed what a seed explored (fuzz/seeded.py).
param4 = st.one_of(f32, st.just(math.nan))


@cached_strategy_builder   # drawn inside composites, for every item: built once, not per draw
@st.composite
def mission_item(draw, mission_type: MissionType) -> MissionItem:
    """An item of `mission_type` the spec vehicle accepts (seq 0: the upload renumbers)."""
    if mission_type is MissionType.FENCE:
        command = draw(st.sampled_from([Cmd.NAV_FENCE_RETURN_POINT, Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                                        Cmd.NAV_FENCE_CIRCLE_EXCLUSION]))
        p1 = {Cmd.NAV_FENCE_RETURN_POINT: 0.0, Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION: float(draw(st.integers(3, 20))),
              Cmd.NAV_FENCE_CIRCLE_EXCLUSION: draw(st.floats(1, 5000, width=32))}[command]
        return MissionItem(0, draw(GLOBAL), int(command), param1=p1, x=draw(lat), y=draw(lon), z=draw(alt),
                           mission_type=mission_type)
    if mission_type is MissionType.RALLY:
        return MissionItem(0, draw(GLOBAL), int(Cmd.NAV_RALLY_POINT), x=draw(lat), y=draw(lon), z=draw(alt),
                           mission_type=mission_type)
    command = draw(st.sampled_from([Cmd.NAV_WAYPOINT, Cmd.NAV_LOITER_TIME, Cmd.NAV_LAND, Cmd.NAV_TAKEOFF,
                                    Cmd.DO_CHANGE_SPEED, Cmd.CONDITION_DELAY]))
    positional = command in (Cmd.NAV_WAYPOINT, Cmd.NAV_LOITER_TIME, Cmd.NAV_LAND, Cmd.NAV_TAKEOFF)
    p1 = draw(st.floats(0, 600, width=32)) if command == Cmd.NAV_WAYPOINT else draw(f32)
    return MissionItem(
        0, draw(GLOBAL) if positional else 2, int(command),
        param1=p1, param2=draw(f32), param3=draw(f32),
        param4=draw(param4),
        x=draw(lat), y=draw(lon), z=draw(alt) if positional else draw(f32),
        current=0, autocontinue=draw(st.sampled_from([0, 1])), mission_type=mission_type)


def plan_items(mission_type: MissionType, max_size: int = 20) -> st.SearchStrategy[list[MissionItem]]:
    return st.lists(mission_item(mission_type), min_size=0, max_size=max_size)


partition = st.tuples(st.floats(0, 30), st.floats(0.5, 12)).map(lambda p: (p[0], p[0] + p[1]))


@st.composite
def fault_models(draw, max_loss: float = 0.3) -> FaultModel:
    """Loss, duplication, reordering, delay and jitter, and sometimes a partition in time."""
    return FaultModel(
        partitions=tuple(sorted(draw(st.lists(partition, max_size=2)))),
        loss=draw(st.floats(0, max_loss)),
        duplicate=draw(st.floats(0, 0.2)),
        reorder=draw(st.floats(0, 0.2)),
        reorder_delay=draw(st.floats(0.0, 0.1)),
        delay=draw(st.floats(0, 0.05)),
        jitter=draw(st.floats(0, 0.05)),
    )
