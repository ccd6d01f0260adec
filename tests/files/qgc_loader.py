"""What QGroundControl's loader demands of a .plan, as a checker for the files we write.

Each check mirrors a line of QGC's source (mavlink/qgroundcontrol master):
- PlanMasterController::_loadPlanJson: `mission`, `geoFence`, `rallyPoints` are objects;
- JsonHelper::validateExternalQGCJsonFile / validateInternalQGCJsonFile: `groundStation`
  (string), `fileType` "Plan" (string), `version` 1;
- MissionController::_loadJsonMissionFileV2: `plannedHomePosition` (array of 3, number or
  null: JsonHelper::loadGeoCoordinate), `items` (array), `firmwareType` (number, required),
  `vehicleType` / `cruiseSpeed` / `hoverSpeed` / `globalPlanAltitudeMode` (numbers if
  present); a DO_JUMP's param1 must be some item's `doJumpId` ("Could not find doJumpId");
- MissionItem::load: `type` "SimpleItem", `frame`, `command` (numbers), `params` (7;
  params 1-4 number or null), `autoContinue` (bool), `doJumpId` (number if present);
- SimpleMissionItem::load: `AltitudeMode`, `Altitude` (numbers) and `AMSLAltAboveTerrain`
  (number or null) all three or none;
- GeoFenceController::load: `version` 2 (1 or none: ignored), `circles`, `polygons`
  (arrays); RallyPointController::load: `version` 2 (1: ignored), `points` (array).
JsonHelper::validateKeyTypes: a key typed Double must hold a number (null is refused);
only keys typed Null take a number or null.
"""

from __future__ import annotations

from typing import Any

_TYPES = {"number": (int, float), "string": str, "array": list, "object": dict, "bool": bool}


def _is(value: Any, kind: str) -> bool:
    if kind == "number?":
        return value is None or _is(value, "number")
    if isinstance(value, bool) and kind != "bool":
        return False
    return isinstance(value, _TYPES[kind])


def problems(document: Any) -> list[str]:
    """Every reason QGC's loader would refuse `document` (empty: it loads)."""
    out: list[str] = []

    def need(obj: dict, key: str, kind: str, path: str, required: bool = True) -> Any:
        if key not in obj:
            if required:
                out.append(f"{path}.{key}: missing")
            return None
        if not _is(obj[key], kind):
            out.append(f"{path}.{key}: not a {kind}: {obj[key]!r}")
            return None
        return obj[key]

    if not _is(document, "object"):
        return ["$: not an object"]
    need(document, "groundStation", "string", "$")
    if need(document, "fileType", "string", "$") != "Plan":
        out.append("$.fileType: not 'Plan'")
    if need(document, "version", "number", "$") != 1:
        out.append("$.version: not 1")
    mission = need(document, "mission", "object", "$") or {}
    fence = need(document, "geoFence", "object", "$") or {}
    rally = need(document, "rallyPoints", "object", "$") or {}

    home = need(mission, "plannedHomePosition", "array", "$.mission")
    if home is not None and (len(home) != 3 or not all(_is(v, "number?") for v in home)):
        out.append(f"$.mission.plannedHomePosition: not 3 numbers: {home!r}")
    need(mission, "firmwareType", "number", "$.mission")
    for key in ("vehicleType", "cruiseSpeed", "hoverSpeed", "globalPlanAltitudeMode"):
        need(mission, key, "number", "$.mission", required=False)
    items = need(mission, "items", "array", "$.mission") or []
    jump_ids = {item.get("doJumpId") for item in items if isinstance(item, dict)}
    for index, item in enumerate(items):
        path = f"$.mission.items[{index}]"
        if not _is(item, "object"):
            out.append(f"{path}: not an object")
            continue
        if need(item, "type", "string", path) != "SimpleItem":
            out.append(f"{path}.type: not 'SimpleItem'")
        need(item, "frame", "number", path)
        command = need(item, "command", "number", path)
        need(item, "autoContinue", "bool", path)
        need(item, "doJumpId", "number", path, required=False)
        params = need(item, "params", "array", path) or []
        if len(params) != 7 or not all(_is(v, "number?") for v in params):
            out.append(f"{path}.params: not 7 numbers or nulls: {params!r}")
        altitude = [k for k in ("AltitudeMode", "Altitude", "AMSLAltAboveTerrain") if k in item]
        if altitude:
            need(item, "AltitudeMode", "number", path)
            need(item, "Altitude", "number", path)
            need(item, "AMSLAltAboveTerrain", "number?", path)
        if command == 177 and params and params[0] not in jump_ids:
            out.append(f"{path}: Could not find doJumpId: {params[0]!r}")

    if fence.get("version", 1) != 1:
        if need(fence, "version", "number", "$.geoFence") != 2:
            out.append("$.geoFence.version: not 2")
        need(fence, "circles", "array", "$.geoFence")
        need(fence, "polygons", "array", "$.geoFence")
        need(fence, "breachReturn", "array", "$.geoFence", required=False)
    if rally.get("version") != 1:
        if need(rally, "version", "number", "$.rallyPoints") != 2:
            out.append("$.rallyPoints.version: not 2")
        need(rally, "points", "array", "$.rallyPoints")
    return out
