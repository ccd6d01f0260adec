"""QGroundControl's SimpleItem: a mission item in a .plan, read in every form QGC's loader
reads and written in the form QGC writes.

Read as QGC reads it (MissionItem::load, SimpleMissionItem::load, MissionController::
_loadJsonMissionFileV2):
- `params` holds param1-4, x, y, z (null is NaN); the legacy forms are read too: `param1`
  .. `param4` keys instead of the first four params (MissionItem::_convertJsonV1ToV2) and
  a `coordinate` [lat, lon, alt] instead of the last three (_convertJsonV2ToV3).
- `AltitudeMode`, `Altitude`, `AMSLAltAboveTerrain` come together or not at all. When the
  altitude param is null, it is resolved as QGC keeps it: from `AMSLAltAboveTerrain` for an
  item QGC computes above terrain (param7 = terrain height + Altitude), from `Altitude` in
  every other mode (SimpleMissionItem::_altitudeChanged / _terrainAltChanged); if that is
  null too the file is refused, naming the item (QGC saved it before it had terrain data).
- A DO_JUMP's param1 names its target by `doJumpId`, not by position; it is read as the
  target's index in the mission (the wire seq on a vehicle that keeps no home at seq 0),
  and a target no item has is refused, as QGC refuses it ("Could not find doJumpId").

Written as QGC writes it: `params` (7), `doJumpId` = position + 1 (QGC numbers its items
from 1, home being 0), and the altitude keys for items with a location (the upstream XML's
hasLocation) in a global frame.
"""

from __future__ import annotations

import math
from dataclasses import replace
from decimal import Decimal
from typing import Any

from mavconform.reference_impl.files.plan import (
    float32_from_decimal, xy_decimals, xy_from_decimal, xy_to_decimal,
)
from mavconform.reference_impl.files.qgc_json import JsonReader, JsonWriter
from mavconform.reference_impl.mission.commands import LOCATION_COMMANDS
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

PARAM_COUNT = 7
LEGACY_PARAM_KEYS = ("param1", "param2", "param3", "param4")
ALTITUDE_KEYS = ("AltitudeMode", "Altitude", "AMSLAltAboveTerrain")
# QGroundControlQmlGlobal::AltMode (QGroundControlQmlGlobal.h): Mixed, Relative, Absolute,
# CalcAboveTerrain, TerrainFrame, None.
ALT_MODE_MIXED, ALT_MODE_RELATIVE, ALT_MODE_ABSOLUTE = 0, 1, 2
ALT_MODE_CALC_ABOVE_TERRAIN, ALT_MODE_TERRAIN_FRAME, ALT_MODE_NONE = 3, 4, 5
# The altitude mode an item's frame says (QGC's SimpleMissionItem::_altitudeModeChanged, the
# other way round; the *_INT frames are the same altitudes).
ALT_MODE_OF_FRAME = {
    _d.MAV_FRAME_GLOBAL: ALT_MODE_ABSOLUTE, _d.MAV_FRAME_GLOBAL_INT: ALT_MODE_ABSOLUTE,
    _d.MAV_FRAME_GLOBAL_RELATIVE_ALT: ALT_MODE_RELATIVE,
    _d.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: ALT_MODE_RELATIVE,
    _d.MAV_FRAME_GLOBAL_TERRAIN_ALT: ALT_MODE_TERRAIN_FRAME,
    _d.MAV_FRAME_GLOBAL_TERRAIN_ALT_INT: ALT_MODE_TERRAIN_FRAME,
}


# --- reading -------------------------------------------------------------------------------

def read_items(reader: JsonReader, values: list, path: str) -> list[MissionItem]:
    """The mission items of `$.mission.items`, DO_JUMP targets turned into positions."""
    read = [_read_item(reader, value, f"{path}[{index}]") for index, value in enumerate(values)]
    positions: dict[int, int] = {}
    for index, (_, jump_id, _) in enumerate(read):
        if jump_id is not None:
            positions.setdefault(jump_id, index)   # QGC takes the first item with that id
    return [_jump_by_position(reader, item, positions, param1_path) for item, _, param1_path in read]


def _read_item(reader: JsonReader, value: Any, path: str) -> tuple[MissionItem, int | None, str]:
    """The item, its doJumpId (None if absent) and the JSON path of its param1."""
    obj = reader.check(value, path, "object")
    item_type = reader.member(obj, "type", path, "string")
    if item_type == "ComplexItem":
        name = obj.get("complexItemType")
        what = f"ComplexItem ({name})" if isinstance(name, str) else "ComplexItem"
        reader.fail(path, f"{what} is not supported; "
                          "convert it to simple items in QGroundControl first")
    if item_type != "SimpleItem":
        reader.fail(f"{path}.type", f"unknown item type {item_type!r} (expected 'SimpleItem')")
    command = reader.integer_in(obj, "command", path, 65535)
    frame = reader.integer_in(obj, "frame", path, 255)
    autocontinue = reader.member(obj, "autoContinue", path, "bool")
    jump_id = reader.optional(obj, "doJumpId", path, "integer")
    params, paths = _read_params(reader, obj, path)
    params[6] = _altitude(reader, obj, path, params[6], paths[6])
    xy = [xy_from_decimal(frame, params[4]), xy_from_decimal(frame, params[5])]
    for index, scaled in zip((4, 5), xy):
        if scaled is None:
            reader.fail(paths[index], f"{params[index]} does not fit "
                        f"MISSION_ITEM_INT's int32 {'xy'[index - 4]} in frame {frame}")
    p1, p2, p3, p4, z = (float32_from_decimal(params[i]) for i in (0, 1, 2, 3, 6))
    item = MissionItem(seq=0, frame=frame, command=command, param1=p1, param2=p2, param3=p3,
                       param4=p4, x=xy[0], y=xy[1], z=z, autocontinue=int(autocontinue),
                       mission_type=MissionType.MISSION)
    return item, jump_id, paths[0]


def _read_params(reader: JsonReader, obj: dict, path: str) -> tuple[list[Decimal], list[str]]:
    """The seven params (NaN for null) and the JSON path each came from, in any form QGC reads."""
    if "params" in obj:
        raw = reader.member(obj, "params", path, "array")
        paths = [f"{path}.params[{i}]" for i in range(len(raw))]
        expected = len(LEGACY_PARAM_KEYS) if "coordinate" in obj else PARAM_COUNT
        if len(raw) != expected:
            beside = " beside 'coordinate'" if "coordinate" in obj else ""
            reader.fail(f"{path}.params", f"expected {expected} params{beside}, found {len(raw)}")
    else:   # the oldest form: param1..param4 keys
        missing = [k for k in LEGACY_PARAM_KEYS if k not in obj]
        if missing:
            reader.fail(f"{path}.params", "missing required key (and no "
                        f"{'/'.join(LEGACY_PARAM_KEYS)} keys of the older form)")
        raw = [obj[k] for k in LEGACY_PARAM_KEYS]
        paths = [f"{path}.{k}" for k in LEGACY_PARAM_KEYS]
        if "coordinate" not in obj:
            reader.fail(f"{path}.coordinate", "missing required key (an item with "
                        "param1..param4 keys carries x, y, z in 'coordinate')")
    if "coordinate" in obj:
        coordinate = reader.member(obj, "coordinate", path, "array")
        if len(coordinate) != 3:
            reader.fail(f"{path}.coordinate", f"expected [lat, lon, alt], found {len(coordinate)} values")
        raw = [*raw, *coordinate]
        paths += [f"{path}.coordinate[{i}]" for i in range(3)]
    return [reader.number_or_null(value, p) for value, p in zip(raw, paths)], paths


def _altitude(reader: JsonReader, obj: dict, path: str, param7: Decimal, param7_path: str) -> Decimal:
    """param7, or when it is null, the altitude QGC's altitude keys say it stands for."""
    present = [k for k in ALTITUDE_KEYS if k in obj]
    if not present:
        return param7
    for key in ALTITUDE_KEYS:
        if key not in obj:
            reader.fail(f"{path}.{key}", f"missing required key ({', '.join(ALTITUDE_KEYS)} "
                                         "come together)")
    mode = reader.integer_in(obj, "AltitudeMode", path, ALT_MODE_NONE)
    altitude = reader.number_or_null(obj["Altitude"], f"{path}.Altitude")
    amsl = reader.number_or_null(obj["AMSLAltAboveTerrain"], f"{path}.AMSLAltAboveTerrain")
    if not param7.is_nan():
        return param7
    key, value = (("AMSLAltAboveTerrain", amsl) if mode == ALT_MODE_CALC_ABOVE_TERRAIN
                  else ("Altitude", altitude))
    if value.is_nan():
        why = (" (QGC saved it before it had the terrain height: open the plan in QGC with "
               "terrain data and save it again)" if mode == ALT_MODE_CALC_ABOVE_TERRAIN else "")
        reader.fail(param7_path, f"the altitude is null and so is {key}{why}")
    return value


def _jump_by_position(reader: JsonReader, item: MissionItem, positions: dict[int, int],
                      param1_path: str) -> MissionItem:
    if item.command != Cmd.DO_JUMP:
        return item
    target = item.param1
    if not (math.isfinite(target) and target == int(target) and int(target) in positions):
        reader.fail(param1_path, f"DO_JUMP target {target:g} is no item's doJumpId")
    return replace(item, param1=float(positions[int(target)]))


# --- writing -------------------------------------------------------------------------------

def items_json(writer: JsonWriter, items: list[MissionItem]) -> list[dict]:
    return [_item_json(writer, item, index, len(items)) for index, item in enumerate(items)]


def _item_json(writer: JsonWriter, item: MissionItem, index: int, count: int) -> dict:
    where = f"mission item {index}"
    params = [writer.float32(p, where) for p in (item.param1, item.param2, item.param3, item.param4)]
    if item.command == Cmd.DO_JUMP:
        params[0] = _jump_id(writer, item.param1, count, where)
    for value in (item.x, item.y):  # the exact decimal's nearest double reads back to this int
        params.append(float(xy_to_decimal(item.frame, value)) if xy_decimals(item.frame) else value)
    params.append(writer.float32(item.z, where))
    out: dict[str, Any] = {
        "autoContinue": bool(writer.in_range(item.autocontinue, 1, "autocontinue", where)),
        "command": writer.in_range(item.command, 65535, "command", where),
        "doJumpId": index + 1,
        "frame": writer.in_range(item.frame, 255, "frame", where),
        "params": params,
        "type": "SimpleItem",
    }
    if item.command in LOCATION_COMMANDS and item.frame in ALT_MODE_OF_FRAME and math.isfinite(item.z):
        # as SimpleMissionItem::save writes them; the height above terrain is QGC's to compute
        out.update(AltitudeMode=ALT_MODE_OF_FRAME[item.frame], Altitude=params[6],
                   AMSLAltAboveTerrain=None)
    return out


def _jump_id(writer: JsonWriter, target: float, count: int, where: str) -> int:
    """A DO_JUMP's target position as the doJumpId QGC's loader looks for."""
    if not (math.isfinite(target) and target == int(target) and 0 <= target < count):
        writer.fail(where, f"DO_JUMP target (param1) {target:g} is not an item of this mission "
                           f"(0..{count - 1}); a .plan names it by the target's doJumpId")
    return int(target) + 1
