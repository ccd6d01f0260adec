"""Small valid plans the checks upload: a few waypoints, a fence polygon, rally points.

Positions sit within metres of the target's home (taken from its GLOBAL_POSITION_INT when
it sends one), so a check that flies the plan finishes in seconds. Every plan is distinct
from every other (`variant`), so "the stored plan is still the old one" is never an accident.
"""

from __future__ import annotations

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT   # x/y degE7 in the INT form

STEP = 40                          # degE7 between waypoints: about half a metre
DEFAULT_HOME = (473977420, 85455940)


def mission(n: int, variant: int = 0, home: tuple[int, int] = DEFAULT_HOME) -> list[MissionItem]:
    lat, lon = home
    return [MissionItem(seq=i, frame=FRAME_GLOBAL_RELATIVE_ALT, command=Cmd.NAV_WAYPOINT,
                        x=lat + STEP * (i + 1), y=lon + STEP * (variant + 1), z=10.0 + variant,
                        mission_type=MissionType.MISSION) for i in range(n)]


def fence(variant: int = 0, home: tuple[int, int] = DEFAULT_HOME) -> list[MissionItem]:
    lat, lon = home
    d = 2000 + 100 * variant
    corners = [(-d, -d), (-d, d), (d, d), (d, -d)]
    return [MissionItem(seq=i, frame=FRAME_GLOBAL_RELATIVE_ALT, command=Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                        param1=4.0, x=lat + dy, y=lon + dx, mission_type=MissionType.FENCE)
            for i, (dy, dx) in enumerate(corners)]


def rally(n: int = 2, variant: int = 0, home: tuple[int, int] = DEFAULT_HOME) -> list[MissionItem]:
    lat, lon = home
    return [MissionItem(seq=i, frame=FRAME_GLOBAL_RELATIVE_ALT, command=Cmd.NAV_RALLY_POINT,
                        x=lat - 300 * (i + 1), y=lon + 300 * (variant + 1), z=20.0,
                        mission_type=MissionType.RALLY) for i in range(n)]


def plan(mission_type: MissionType, variant: int = 0, home: tuple[int, int] = DEFAULT_HOME) -> list[MissionItem]:
    if mission_type is MissionType.FENCE:
        return fence(variant, home)
    if mission_type is MissionType.RALLY:
        return rally(2, variant, home)
    return mission(3, variant, home)
