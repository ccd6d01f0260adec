import pytest

from mavconform.reference_impl.mission.items import MissionItem, MissionType


def waypoint(seq: int, mission_type: MissionType = MissionType.MISSION, **kw) -> MissionItem:
    base = dict(frame=3, command=16, x=473977420 + 1000 * seq, y=85455940 - 700 * seq, z=50.0 + seq)
    if mission_type is MissionType.FENCE:
        base.update(frame=0, command=5003, param1=100.0 + seq)      # fence circle, radius
    elif mission_type is MissionType.RALLY:
        base.update(command=5100)
    base.update(kw)
    return MissionItem(seq=seq, mission_type=mission_type, **base)


def plan(n: int, mission_type: MissionType = MissionType.MISSION, **kw) -> list[MissionItem]:
    return [waypoint(i, mission_type, **kw) for i in range(n)]


@pytest.fixture
def make_plan():
    return plan
