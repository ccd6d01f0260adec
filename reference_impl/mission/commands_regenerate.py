"""Regenerate `commands_data.py`, the MAV_CMD facts, from the upstream common.xml.

    python -m mavconform.reference_impl.mission.commands_regenerate           # rewrite the module
    python -m mavconform.reference_impl.mission.commands_regenerate --check   # exit 1 if stale
    ... --xml PATH                                                            # another common.xml

The facts are committed because the installed package must work without the upstream XML
(it lives beside the repository, in ../shared/mavlink-upstream/, and is not shipped). Only
facts are taken: each MAV_CMD entry's value and name, its `hasLocation` / `isDestination` /
`missionOnly` attributes, whether it is deprecated, superseded or work in progress, and each
param's index, label and `reserved` flag. No description text is copied.

Standard library only, no package-relative imports: it runs as a file too
(`python reference_impl/mission/commands_regenerate.py`) if the package cannot import.
"""

from __future__ import annotations

import argparse
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
PY_PATH = HERE / "commands_data.py"
# Beside the repository, wherever it is cloned: <repo_root>.parent / "shared".
DEFAULT_XML = HERE.parents[2] / "shared" / "mavlink-upstream" / "common.xml"
SOURCE = "mavlink/mavlink message_definitions/v1.0/common.xml (commit de1e078), enum MAV_CMD"
PREFIX = "MAV_CMD_"


def _status(entry: ET.Element) -> str:
    for tag in ("deprecated", "superseded", "wip"):
        if entry.find(tag) is not None:
            return tag
    return ""


def _row(entry: ET.Element) -> str:
    name = entry.get("name", "")
    if not name.startswith(PREFIX):
        raise ValueError(f"MAV_CMD entry {name!r} does not start with {PREFIX}")
    params = tuple(
        (int(p.get("index", "0")), p.get("label", ""), p.get("reserved", "false") == "true")
        for p in entry.findall("param"))
    flags = tuple(entry.get(attr, "false") == "true" for attr in ("hasLocation", "isDestination", "missionOnly"))
    return (f"    ({int(entry.get('value', '-1'))}, {name[len(PREFIX):]!r}, {flags[0]}, {flags[1]}, "
            f"{flags[2]}, {_status(entry)!r}, {params!r}),")


def render(xml_path: Path) -> str:
    """The module text for the MAV_CMD enum of `xml_path`."""
    root = ET.parse(xml_path).getroot()
    enums = [e for e in root.iter("enum") if e.get("name") == "MAV_CMD"]
    if len(enums) != 1:
        raise ValueError(f"{xml_path}: expected one MAV_CMD enum, found {len(enums)}")
    rows = sorted(enums[0].findall("entry"), key=lambda e: int(e.get("value", "-1")))
    lines = [
        '"""MAV_CMD facts from the upstream MAVLink XML. GENERATED: do not edit.',
        "",
        "Written by commands_regenerate.py; `--check` (and tests/mission/test_commands.py)",
        "fails when it no longer matches the XML. Read it through `commands.py`.",
        '"""',
        "",
        f"SOURCE = {SOURCE!r}",
        "",
        "# (value, name without MAV_CMD_, hasLocation, isDestination, missionOnly,",
        "#  '' | 'deprecated' | 'superseded' | 'wip', ((param index, label, reserved), ...))",
        "ROWS = (",
        *(_row(entry) for entry in rows),
        ")",
        "",
    ]
    return "\n".join(lines)


def check(xml_path: Path = DEFAULT_XML) -> str:
    """"identical", "differs" or "missing" (the committed module)."""
    if not PY_PATH.is_file():
        return "missing"
    return "identical" if render(xml_path) == PY_PATH.read_text(encoding="utf-8") else "differs"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="exit 1 if the committed module is out of date")
    parser.add_argument("--xml", type=Path, default=DEFAULT_XML, metavar="PATH",
                        help=f"the upstream common.xml (default: {DEFAULT_XML})")
    args = parser.parse_args(argv)
    if not args.xml.is_file():
        print(f"{args.xml}: no such file (the upstream common.xml; see --xml)", file=sys.stderr)
        return 2
    if args.check:
        verdict = check(args.xml)
        if verdict != "identical":
            print(f"{PY_PATH.name} is {'missing' if verdict == 'missing' else 'out of date'}: it does not "
                  f"match {args.xml}. Run: python -m mavconform.reference_impl.mission.commands_regenerate",
                  file=sys.stderr)
            return 1
        print(f"{PY_PATH.name} is up to date with {args.xml}")
        return 0
    PY_PATH.write_text(render(args.xml), encoding="utf-8")
    print(f"regenerated {PY_PATH}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
