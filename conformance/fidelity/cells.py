"""The cells of the fidelity survey's frame matrix: every MAV_FRAME × each plan type's item kinds.

A cell is one item kind of one plan type written in one frame (issue 26): a mission waypoint
(MAV_CMD_NAV_WAYPOINT), a fence's polygon vertex (a triangle of MAV_CMD_NAV_FENCE_POLYGON_
VERTEX_INCLUSION: a polygon needs three), inclusion circle and return point, a rally point.
The frames are the dialect's MAV_FRAME enum, reserved values (13-19) included: a vehicle
should refuse them, and whether it does is a cell too. Coordinates are exact integers near
the reference home and altitudes exact in float32, so any difference on the way back is the
vehicle's, not rounding of ours.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

FRAMES: tuple[int, ...] = tuple(sorted(k for k, v in _d.enums["MAV_FRAME"].items() if not v.name.endswith("ENUM_END")))
FRAME_NAMES = {k: _d.enums["MAV_FRAME"][k].name.removeprefix("MAV_FRAME_") for k in FRAMES}
HOME_X, HOME_Y = 473977420, 85455940          # degE7 (the reference vehicle's home)

FENCE_VERTEX, FENCE_CIRCLE, FENCE_RETURN, RALLY_POINT = 5001, 5003, 5000, 5100


@dataclass(frozen=True)
class Cell:
    plan_type: MissionType
    frame: int
    command: int
    items: tuple[MissionItem, ...]        # what the cell uploads (seq from 0; renumbered in a batch)
    probe: str = ""                       # the command matrix's probe (probes.py); "" in the frame matrix

    @property
    def key(self) -> tuple[str, int, int, str]:
        return (self.plan_type.label, self.frame, self.command, self.probe)


def entry_key(entry: dict) -> tuple[str, int, int, str]:
    """A run.json cell's key, as `Cell.key`."""
    return (entry["plan_type"], entry["frame"], entry["command"], entry.get("probe") or "")


def _near(i: int, k: int) -> tuple[int, int]:
    """A point a few hundred metres from home, distinct for each (cell, corner)."""
    return HOME_X + 997 * i + 131 * k, HOME_Y + 1009 * i - 97 * k


def frame_cells() -> list[Cell]:
    cells: list[Cell] = []
    for i, frame in enumerate(FRAMES):
        x, y = _near(i, 0)
        cells.append(Cell(MissionType.MISSION, frame, int(Cmd.NAV_WAYPOINT), (
            MissionItem(0, frame, Cmd.NAV_WAYPOINT, 0.0, 0.0, 0.0, 0.0, x, y, 30.0 + i, 0, 1),)))
        triangle = tuple(MissionItem(0, frame, FENCE_VERTEX, 3.0, 0.0, 0.0, 0.0, *_near(i, k), 0.0, 0, 1,
                                     MissionType.FENCE) for k in range(3))
        cells.append(Cell(MissionType.FENCE, frame, FENCE_VERTEX, triangle))
        cells.append(Cell(MissionType.FENCE, frame, FENCE_CIRCLE, (
            MissionItem(0, frame, FENCE_CIRCLE, 150.25 + i, 0.0, 0.0, 0.0, x, y, 0.0, 0, 1, MissionType.FENCE),)))
        cells.append(Cell(MissionType.FENCE, frame, FENCE_RETURN, (
            MissionItem(0, frame, FENCE_RETURN, 0.0, 0.0, 0.0, 0.0, x, y, 20.0 + i, 0, 1, MissionType.FENCE),)))
        cells.append(Cell(MissionType.RALLY, frame, RALLY_POINT, (
            MissionItem(0, frame, RALLY_POINT, 0.0, 0.0, 0.0, 0.0, x, y, 40.0 + i, 0, 1, MissionType.RALLY),)))
    return cells


def numbered(items: list[MissionItem], start: int = 0) -> list[MissionItem]:
    return [replace(it, seq=start + n) for n, it in enumerate(items)]
