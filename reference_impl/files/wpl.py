"""QGC WPL 110: the tab-separated waypoint text of QGroundControl, Mission Planner and MAVProxy.

    QGC WPL 110
    INDEX CURRENT FRAME COMMAND P1 P2 P3 P4 X(lat) Y(lon) Z(alt) AUTOCONTINUE   (TAB separated)

Rows are read literally as mission items 0..n-1: row 0 is *not* taken to be home (ArduPilot
tools put home there, PX4 tools do not; a conformance suite must upload exactly what the
file says). The format holds no fence, rally or home position.
"""

from __future__ import annotations

import re
from decimal import Decimal
from typing import NoReturn

from mavconform.reference_impl.files.plan import (
    Plan, PlanFileError, float32_from_decimal, float32_text, parse_decimal, xy_from_decimal,
    xy_text,
)
from mavconform.reference_impl.mission.items import MissionItem, MissionType

HEADER = "QGC WPL 110"
COLUMNS = ("INDEX", "CURRENT", "FRAME", "COMMAND", "PARAM1", "PARAM2", "PARAM3", "PARAM4",
           "X", "Y", "Z", "AUTOCONTINUE")
_INTEGER = re.compile(r"[+-]?\d+")
_INTEGER_MAX_CHARS = 19  # longer is outside every range here (and may exceed int()'s limit)
_FRAME_MAX = 255  # MISSION_ITEM_INT.frame is uint8
_COMMAND_MAX = 65535  # MISSION_ITEM_INT.command is uint16


def looks_like_wpl(first_line: str) -> bool:
    """Whether a file says it is WPL text (any version: the parser names a wrong one)."""
    return first_line.strip().startswith("QGC WPL")


def parse_wpl(text: str, source: str) -> Plan:
    """The mission in WPL text; `source` names the file in errors ("FILE:LINE: problem")."""
    lines = text.splitlines()
    header = lines[0].strip() if lines else ""
    if header != HEADER:
        found = f"{header!r}" if header else "an empty first line"
        raise PlanFileError(f"{source}:1: expected the header {HEADER!r}, found {found}")
    items: list[MissionItem] = []
    for line_number, line in enumerate(lines[1:], start=2):
        if line.strip():
            items.append(_parse_row(line, source, line_number, seq=len(items)))
    return Plan(mission=items)


def _parse_row(line: str, source: str, line_number: int, seq: int) -> MissionItem:
    def fail(problem: str) -> NoReturn:
        raise PlanFileError(f"{source}:{line_number}: {problem}")

    # Any whitespace separates, as pymavlink reads it: files edited by hand often lose tabs.
    columns = line.split()
    if len(columns) != len(COLUMNS):
        fail(f"expected {len(COLUMNS)} columns ({' '.join(COLUMNS)}), found {len(columns)}")
    fields = dict(zip(COLUMNS, columns))

    def integer(column: str, low: int, high: int) -> int:
        text = fields[column]
        if not _INTEGER.fullmatch(text):
            fail(f"{column} {text!r} is not an integer")
        value = int(text) if len(text) <= _INTEGER_MAX_CHARS else None
        if value is None or not low <= value <= high:
            fail(f"{column} {text} is outside {low}..{high}")
        return value

    def number(column: str) -> Decimal:
        value = parse_decimal(fields[column])
        if value is None:
            fail(f"{column} {fields[column]!r} is not a number")
        return value

    index = integer("INDEX", 0, 2**31 - 1)
    if index != seq:
        fail(f"INDEX {index} out of order: rows must be numbered 0, 1, 2, ... (expected {seq})")
    frame = integer("FRAME", 0, _FRAME_MAX)
    xy = []
    for column in ("X", "Y"):
        scaled = xy_from_decimal(frame, number(column))
        if scaled is None:
            fail(f"{column} {fields[column]!r} does not fit MISSION_ITEM_INT's int32 "
                 f"in frame {frame}")
        xy.append(scaled)
    return MissionItem(
        seq=seq,
        current=integer("CURRENT", 0, 1),
        frame=frame,
        command=integer("COMMAND", 0, _COMMAND_MAX),
        param1=float32_from_decimal(number("PARAM1")),
        param2=float32_from_decimal(number("PARAM2")),
        param3=float32_from_decimal(number("PARAM3")),
        param4=float32_from_decimal(number("PARAM4")),
        x=xy[0],
        y=xy[1],
        z=float32_from_decimal(number("Z")),
        autocontinue=integer("AUTOCONTINUE", 0, 1),
        mission_type=MissionType.MISSION,
    )


def format_wpl(plan: Plan, source: str) -> str:
    """WPL text for the plan's mission; refuses a plan whose fence or rally would be lost."""
    if plan.fence or plan.rally:
        raise PlanFileError(
            f"{source}: a QGC WPL 110 file holds only the mission, not this plan's "
            f"{len(plan.fence)} fence and {len(plan.rally)} rally items; save it as .plan instead")
    rows = [HEADER]
    for index, item in enumerate(plan.mission):
        _check_writable(item, index, source)
        rows.append("\t".join((
            str(index), str(item.current), str(item.frame), str(item.command),
            float32_text(item.param1), float32_text(item.param2),
            float32_text(item.param3), float32_text(item.param4),
            xy_text(item.frame, item.x), xy_text(item.frame, item.y),
            float32_text(item.z), str(item.autocontinue),
        )))
    return "\n".join(rows) + "\n"


def _check_writable(item: MissionItem, index: int, source: str) -> None:
    """Refuse what the reader would refuse, so a written file always loads again."""
    for name, value, high in (
            ("current", item.current, 1), ("autocontinue", item.autocontinue, 1),
            ("frame", item.frame, _FRAME_MAX), ("command", item.command, _COMMAND_MAX)):
        if not 0 <= value <= high:
            raise PlanFileError(
                f"{source}: mission item {index}: {name} {value} is outside 0..{high}")
