"""Mission files: QGroundControl .plan JSON and QGC WPL 110 text, read into and written from `Plan`.

Every problem, from a missing file to a bad field, is a one-line `PlanFileError` (a
`UsageError`) that starts with the path as given, so the CLI can print it as is.
"""

from __future__ import annotations

from pathlib import Path

from mavconform.reference_impl.files.plan import MissionSettings, Plan, PlanFileError, plan_from_items
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType
from mavconform.reference_impl.files.qgc_plan import format_qgc_plan, parse_qgc_plan
from mavconform.reference_impl.files.wpl import HEADER as WPL_HEADER, format_wpl, looks_like_wpl, parse_wpl

__all__ = ["MissionSettings", "Plan", "PlanFileError", "check_writable", "load_plan", "plan_from_items", "plan_types_in",
           "save_plan", "SAMPLES_DIR"]

SAMPLES_DIR = Path(__file__).parent / "samples"
PLAN_SUFFIX = ".plan"
WPL_SUFFIXES = (".waypoints", ".txt", ".mission")


def load_plan(path: str | Path) -> Plan:
    """A .plan file as QGC JSON; any other file as WPL 110 text if its first line says so."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")  # -sig: editors on Windows add a BOM
    except UnicodeDecodeError as error:
        raise PlanFileError(f"{source}: cannot read: not UTF-8 text ({error.reason})") from None
    except OSError as error:
        raise PlanFileError(f"{source}: cannot read: {error.strerror or error}") from None
    if Path(path).suffix.lower() == PLAN_SUFFIX:
        return _sendable(parse_qgc_plan(text, source), source)
    first_line = text.splitlines()[0] if text else ""
    if looks_like_wpl(first_line):
        return _sendable(parse_wpl(text, source), source)
    raise PlanFileError(f"{source}:1: not a mission file: expected a .plan file or the header "
                        f"{WPL_HEADER!r}, found {first_line.strip()[:40]!r}")


MAX_ITEMS = 0xFFFF   # MISSION_COUNT.count is a uint16_t: no plan type holds more on the wire


def _sendable(plan: Plan, source: str) -> Plan:
    """A plan type longer than MISSION_COUNT can say is the file's fault, said up front
    (it used to end in a struct.error while encoding the count)."""
    for t in PLAN_TYPES:
        n = len(plan.items(t))
        if n > MAX_ITEMS:
            raise PlanFileError(f"{source}: the {t.label} plan has {n} items; MAVLink can send at most "
                                f"{MAX_ITEMS} (MISSION_COUNT.count is 16 bits)")
    return plan


def plan_types_in(path: str | Path) -> tuple[MissionType, ...]:
    """The plan types a file of this kind holds: all three in a .plan, the mission in WPL.

    Checks the file name only, so a command can refuse a bad output path before any I/O."""
    suffix = Path(path).suffix.lower()
    if suffix == PLAN_SUFFIX:
        return PLAN_TYPES
    if suffix in WPL_SUFFIXES:
        return (MissionType.MISSION,)
    raise PlanFileError(f"{path}: unknown mission file type {suffix or '(no extension)'!r}; "
                        f"use {PLAN_SUFFIX} or one of {', '.join(WPL_SUFFIXES)}")


def check_writable(path: str | Path) -> None:
    """Refuse an output path whose type is unknown or whose folder does not exist."""
    plan_types_in(path)
    folder = Path(path).resolve().parent
    if not folder.is_dir():
        raise PlanFileError(f"{path}: cannot write: folder {folder} does not exist")


def save_plan(plan: Plan, path: str | Path) -> None:
    """.plan as QGC JSON; .waypoints/.txt/.mission as WPL 110 (mission only: a fence or
    rally that would be dropped is refused instead)."""
    source = str(path)
    suffix = Path(path).suffix.lower()
    if suffix == PLAN_SUFFIX:
        text = format_qgc_plan(plan, source)
    elif suffix in WPL_SUFFIXES:
        text = format_wpl(plan, source)
    else:
        raise PlanFileError(f"{source}: unknown mission file type {suffix or '(no extension)'!r}; "
                            f"use {PLAN_SUFFIX} or one of {', '.join(WPL_SUFFIXES)}")
    try:
        Path(path).write_text(text, encoding="utf-8")
    except OSError as error:
        raise PlanFileError(f"{source}: cannot write: {error.strerror or error}") from None
