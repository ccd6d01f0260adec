"""No module-level hand-written copy of a MAVLink enum constant: names take their value from
the dialect module, so a wrong copy (the vehicle once announced MAV_AUTOPILOT_GENERIC_MISSION_FULL
as 4, which is MAV_AUTOPILOT_OPENPILOT) cannot come back.

An AST scan of every package the project installs: a module-level assignment whose target is
a MAVLink enum entry name (as the dialect spells it, or without its `MAV_` prefix) must not
give it a literal value.
"""

from __future__ import annotations

import ast
import sys
from enum import IntEnum
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import common as bundled

from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult, MissionState
from mavconform.reference_impl.wire.dialect import mavlink

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[2]
GENERATED = REPO / "reference_impl" / "wire" / "dialect" / "mavconform_dialect.py"

def _enum_entry_names() -> frozenset[str]:
    names = {entry.name for dialect in (mavlink, bundled)
             for enum in dialect.enums.values() for entry in enum.values()}
    return frozenset(names | {n[len("MAV_"):] for n in names if n.startswith("MAV_")})


ENTRY_NAMES = _enum_entry_names()


def _package_dirs() -> list[Path]:
    """Every folder pyproject.toml installs as a package root (mavconform and its mapped ones)."""
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    mapped = config["tool"]["setuptools"]["package-dir"].values()
    return sorted({REPO / "mavconform", *(REPO / folder for folder in mapped)})


def _is_literal(node: ast.expr) -> bool:
    """A value written out by hand: numbers (and arithmetic on them), no name in sight."""
    if isinstance(node, ast.Constant):
        return isinstance(node.value, (int, float))
    if isinstance(node, ast.UnaryOp):
        return _is_literal(node.operand)
    if isinstance(node, ast.BinOp):
        return _is_literal(node.left) and _is_literal(node.right)
    return False


def _pairs(target: ast.expr, value: ast.expr) -> list[tuple[str, ast.expr]]:
    if isinstance(target, ast.Name):
        return [(target.id, value)]
    if isinstance(target, (ast.Tuple, ast.List)):
        if isinstance(value, (ast.Tuple, ast.List)) and len(value.elts) == len(target.elts):
            return [p for t, v in zip(target.elts, value.elts) for p in _pairs(t, v)]
        return [(t.id, value) for t in target.elts if isinstance(t, ast.Name)]
    return []


def copies_in(source: str) -> list[tuple[int, str]]:
    """(line, name) of each module-level enum entry name given a literal value."""
    out = []
    for node in ast.parse(source).body:
        if isinstance(node, ast.Assign):
            pairs = [p for t in node.targets for p in _pairs(t, node.value)]
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            pairs = _pairs(node.target, node.value)
        else:
            continue
        out += [(node.lineno, name) for name, value in pairs if name in ENTRY_NAMES and _is_literal(value)]
    return out


def _all_copies() -> dict[str, list[tuple[int, str]]]:
    found = {}
    for folder in _package_dirs():
        for path in sorted(folder.rglob("*.py")):
            if path == GENERATED:
                continue
            hits = copies_in(path.read_text(encoding="utf-8"))
            if hits:
                found[path.relative_to(REPO).as_posix()] = hits
    return found


def test_the_scan_sees_a_copy_and_lets_the_dialect_value_pass() -> None:
    assert copies_in("MAV_AUTOPILOT_GENERIC_MISSION_FULL = 4\n") == [(1, "MAV_AUTOPILOT_GENERIC_MISSION_FULL")]
    assert copies_in("MAV_STATE_STANDBY, MAV_STATE_ACTIVE = 3, 4\nFRAME_MISSION: int = 2\n") == [
        (1, "MAV_STATE_STANDBY"), (1, "MAV_STATE_ACTIVE"), (2, "FRAME_MISSION")]
    assert copies_in("MAV_COMP_ID_MISSIONPLANNER = 0x80 | 62\n") == [(1, "MAV_COMP_ID_MISSIONPLANNER")]
    assert copies_in("MAV_TYPE_GCS = _d.MAV_TYPE_GCS\nRETRIES = 5\ndef f():\n    MAV_TYPE_GCS = 6\n") == []


def test_no_package_hand_writes_a_mavlink_enum_constant() -> None:
    assert (REPO / "reference_impl").is_dir() and GENERATED.is_file()
    found = _all_copies()
    assert not found, ("hand-written copies of MAVLink enum constants (take the value from "
                       f"reference_impl.wire.dialect instead): {found}")


# The engines' IntEnums name protocol numbers as words; each member must be the dialect's value.
WORDS = [(MissionResult, "MAV_MISSION_"), (MissionState, "MISSION_STATE_"), (CommandResult, "MAV_RESULT_"),
         (Cmd, "MAV_CMD_")]


@pytest.mark.parametrize("enum, prefix", WORDS, ids=[e.__name__ for e, _ in WORDS])
def test_each_protocol_word_is_the_dialects_number(enum: type[IntEnum], prefix: str) -> None:
    wrong = {member.name: (member.value, getattr(mavlink, prefix + member.name, getattr(bundled, prefix + member.name, None)))
             for member in enum}
    wrong = {name: pair for name, pair in wrong.items() if pair[0] != pair[1]}
    assert not wrong, f"{enum.__name__}: (ours, dialect) differ: {wrong}"
