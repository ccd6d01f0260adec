"""QGroundControl's .plan JSON: mission, geofence and rally points in one file.

QGroundControl is the reference for what the file means, and its loader for what a file
must hold (PlanMasterController::_loadPlanJson, JsonHelper::validateExternalQGCJsonFile,
MissionController::_loadJsonMissionFileV2, GeoFenceController::load,
RallyPointController::load): every key it requires is written (`REQUIRED_KEYS`). Mission
items are QGC's SimpleItems (qgc_items.py). Fence and rally items are built the way QGC's
GeoFenceManager and RallyPointManager build them for an upload: polygon vertices, then
circles, then the breach-return point; autocontinue off. Reading yields exactly those items;
writing accepts any order that groups into the same shapes. So `load(save(plan)) == plan`
holds for every plan in that form that has a home (one without gets `fallback_home`).

A version-1 geoFence or rallyPoints block (an old QGC's) is skipped, as QGC skips it, with
a note on the plan.
"""

from __future__ import annotations

import json
import math
from decimal import Decimal
from typing import Any, NoReturn

from mavconform.reference_impl.files.plan import (
    MissionSettings, Plan, PlanFileError, float32_from_decimal, plan_from_items,
    xy_from_decimal, xy_to_decimal,
)
from mavconform.reference_impl.files.qgc_items import (
    ALT_MODE_MIXED, ALT_MODE_NONE, ALT_MODE_RELATIVE, items_json, read_items,
)
from mavconform.reference_impl.files.qgc_json import Coordinate, Home, JsonReader, JsonWriter
from mavconform.reference_impl.mission.commands import LOCATION_COMMANDS
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import GLOBAL_FRAMES, MissionItem
from mavconform.reference_impl.wire.dialect import mavlink as _d

FILE_VERSION = 1
MISSION_VERSION = 2
GEOFENCE_VERSION = 2
RALLY_VERSION = 2
SKIPPED_VERSION = 1  # of geoFence / rallyPoints: QGC ignores such a block ("old version 1 data")
SHAPE_VERSION = 1  # of each polygon and circle
FRAME_GLOBAL = _d.MAV_FRAME_GLOBAL  # polygon vertices and circle centres (as QGC uploads them)
FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT  # rally and breach-return points (as QGC uploads them)
VERTEX_COMMAND = {True: Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                  False: Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION}
CIRCLE_COMMAND = {True: Cmd.NAV_FENCE_CIRCLE_INCLUSION, False: Cmd.NAV_FENCE_CIRCLE_EXCLUSION}
GROUND_STATION = "mavconform"
# Every key QGC's loader requires, by JSON path (a test holds written files to it). Source:
# QGC PlanMasterController::_loadPlanJson (mission, geoFence, rallyPoints objects),
# JsonHelper::validateExternalQGCJsonFile / validateInternalQGCJsonFile (groundStation,
# fileType, version), MissionController::_loadJsonMissionFileV2 (plannedHomePosition,
# items, firmwareType), MissionItem::load (type, frame, command, params, autoContinue),
# GeoFenceController::load (version, circles, polygons), RallyPointController::load
# (version, points).
REQUIRED_KEYS: dict[str, tuple[str, ...]] = {
    "$": ("fileType", "geoFence", "groundStation", "mission", "rallyPoints", "version"),
    "$.mission": ("firmwareType", "items", "plannedHomePosition"),
    "$.mission.items[]": ("autoContinue", "command", "frame", "params", "type"),
    "$.geoFence": ("circles", "polygons", "version"),
    "$.rallyPoints": ("points", "version"),
}
# QGeoCoordinate::atDistanceAndAzimuth's earth radius (Qt qgeocoordinate.cpp), metres
_QT_EARTH_MEAN_RADIUS = 6371.0072e3
FALLBACK_HOME_OFFSET = 30.0  # m north of the first location, as QGC places a plan's home


# --- reading -------------------------------------------------------------------------------

def parse_qgc_plan(text: str, source: str) -> Plan:
    """The plan in .plan JSON; `source` names the file in errors ("FILE: $.path: problem")."""
    try:
        # Decimal keeps every written digit: degrees become degE7 without a float detour.
        document = json.loads(text, parse_float=Decimal, parse_constant=Decimal)
    except json.JSONDecodeError as error:
        raise PlanFileError(f"{source}: line {error.lineno} column {error.colno}: "
                            f"invalid JSON: {error.msg}") from None
    reader = JsonReader(source)
    root = reader.check(document, "$", "object")
    if (file_type := reader.member(root, "fileType", "$", "string")) != "Plan":
        reader.fail("$.fileType", f"expected 'Plan', found {file_type!r}")
    reader.version(root, "$", FILE_VERSION)
    reader.optional(root, "groundStation", "$", "string")
    mission, home, settings = _read_mission(reader, reader.member(root, "mission", "$", "object"))
    fence: list[MissionItem] = []
    rally: list[MissionItem] = []
    notes: list[str] = []
    if "geoFence" in root:  # optional here (QGC requires it; every file it writes has it)
        obj = reader.member(root, "geoFence", "$", "object")
        if obj.get("version", SKIPPED_VERSION) == SKIPPED_VERSION:   # QGC: version 1 "or prior"
            notes.append(_skipped(source, "$.geoFence", "fence"))
        else:
            fence = _read_fence(reader, obj)
    if "rallyPoints" in root:
        obj = reader.member(root, "rallyPoints", "$", "object")
        if obj.get("version") == SKIPPED_VERSION:
            notes.append(_skipped(source, "$.rallyPoints", "rally points"))
        else:
            rally = _read_rally(reader, obj)
    return plan_from_items(mission, fence, rally, home, settings, notes)


def _skipped(source: str, path: str, what: str) -> str:
    return (f"{source}: {path}: version 1 (an old QGroundControl's format) is skipped, as "
            f"QGroundControl skips it: the plan has no {what}, and uploading it clears the vehicle's {what}")


def _read_mission(reader: JsonReader, obj: dict) -> tuple[list[MissionItem], Home | None, MissionSettings]:
    path = "$.mission"
    reader.version(obj, path, MISSION_VERSION)
    home = None
    if "plannedHomePosition" in obj:
        lat, lon, alt = reader.coordinate(obj["plannedHomePosition"],
                                          f"{path}.plannedHomePosition", with_altitude=True)
        home = (float(lat), float(lon), float(alt))
    defaults = MissionSettings()
    settings = MissionSettings(
        firmware_type=_optional_integer(reader, obj, "firmwareType", path, 255, defaults.firmware_type),
        vehicle_type=_optional_integer(reader, obj, "vehicleType", path, 255, defaults.vehicle_type),
        cruise_speed=_optional_speed(reader, obj, "cruiseSpeed", path, defaults.cruise_speed),
        hover_speed=_optional_speed(reader, obj, "hoverSpeed", path, defaults.hover_speed),
    )
    _optional_integer(reader, obj, "globalPlanAltitudeMode", path, ALT_MODE_NONE, 0)  # checked only
    items = reader.member(obj, "items", path, "array")
    return read_items(reader, items, f"{path}.items"), home, settings


def _optional_integer(reader: JsonReader, obj: dict, key: str, path: str, high: int, default: int) -> int:
    return reader.integer_in(obj, key, path, high) if key in obj else default


def _optional_speed(reader: JsonReader, obj: dict, key: str, path: str, default: float) -> float:
    if key not in obj:
        return default
    value = reader.member(obj, key, path, "number")
    if not (value.is_finite() and value >= 0):
        reader.fail(f"{path}.{key}", f"a speed must be a finite number >= 0, found {value}")
    return float(value)


def _position_item(command: int, frame: int, where: Coordinate, param1: float = 0.0) -> MissionItem:
    """A fence or rally item as QGC builds it for upload (autocontinue off, seq set later)."""
    lat, lon, alt = where
    x, y = xy_from_decimal(frame, lat), xy_from_decimal(frame, lon)
    assert x is not None and y is not None  # checked latitude/longitude always fit degE7
    return MissionItem(seq=0, frame=frame, command=command, param1=param1, x=x, y=y,
                       z=float32_from_decimal(alt), autocontinue=0)


def _read_fence(reader: JsonReader, obj: dict) -> list[MissionItem]:
    path = "$.geoFence"
    reader.version(obj, path, GEOFENCE_VERSION)
    items = []
    for index, value in enumerate(reader.member(obj, "polygons", path, "array")):
        shape_path = f"{path}.polygons[{index}]"
        shape = reader.check(value, shape_path, "object")
        reader.version(shape, shape_path, SHAPE_VERSION)
        command = VERTEX_COMMAND[reader.member(shape, "inclusion", shape_path, "bool")]
        vertices = reader.member(shape, "polygon", shape_path, "array")
        if len(vertices) < 3:
            reader.fail(f"{shape_path}.polygon",
                        f"a polygon needs at least 3 vertices, found {len(vertices)}")
        for i, vertex in enumerate(vertices):
            where = reader.coordinate(vertex, f"{shape_path}.polygon[{i}]", with_altitude=False)
            items.append(_position_item(command, FRAME_GLOBAL, where, param1=float(len(vertices))))
    for index, value in enumerate(reader.member(obj, "circles", path, "array")):
        shape_path = f"{path}.circles[{index}]"
        shape = reader.check(value, shape_path, "object")
        reader.version(shape, shape_path, SHAPE_VERSION)
        command = CIRCLE_COMMAND[reader.member(shape, "inclusion", shape_path, "bool")]
        circle_path = f"{shape_path}.circle"
        circle = reader.member(shape, "circle", shape_path, "object")
        center = reader.coordinate(reader.member(circle, "center", circle_path, "array"),
                                   f"{circle_path}.center", with_altitude=False)
        radius = float32_from_decimal(reader.member(circle, "radius", circle_path, "number"))
        if not (math.isfinite(radius) and radius > 0):
            reader.fail(f"{circle_path}.radius",
                        f"radius must be a positive finite number, found {radius}")
        items.append(_position_item(command, FRAME_GLOBAL, center, param1=radius))
    if "breachReturn" in obj:
        where = reader.coordinate(obj["breachReturn"], f"{path}.breachReturn", with_altitude=True)
        items.append(_position_item(Cmd.NAV_FENCE_RETURN_POINT, FRAME_GLOBAL_RELATIVE_ALT, where))
    return items


def _read_rally(reader: JsonReader, obj: dict) -> list[MissionItem]:
    path = "$.rallyPoints"
    reader.version(obj, path, RALLY_VERSION)
    return [_position_item(Cmd.NAV_RALLY_POINT, FRAME_GLOBAL_RELATIVE_ALT,
                           reader.coordinate(point, f"{path}.points[{i}]", with_altitude=True))
            for i, point in enumerate(reader.member(obj, "points", path, "array"))]


# --- writing -------------------------------------------------------------------------------

def format_qgc_plan(plan: Plan, source: str) -> str:
    """.plan JSON for the whole plan, in QGC's layout (keys sorted, 4-space indent)."""
    writer = JsonWriter(source)
    rally_points = [_rally_point_json(writer, item, f"rally item {index}")
                    for index, item in enumerate(plan.rally)]
    document = {
        "fileType": "Plan",
        "geoFence": _fence_json(writer, plan.fence),
        "groundStation": GROUND_STATION,
        "mission": _mission_json(writer, plan),
        "rallyPoints": {"points": rally_points, "version": RALLY_VERSION},
        "version": FILE_VERSION,
    }
    return json.dumps(document, indent=4, sort_keys=True, allow_nan=False) + "\n"


def _mission_json(writer: JsonWriter, plan: Plan) -> dict:
    lat, lon, alt = plan.home if plan.home is not None else fallback_home(plan.mission)
    if not math.isfinite(alt):
        writer.fail("home", f"altitude {alt} is not finite")
    settings = plan.settings
    for name in ("cruise_speed", "hover_speed"):
        value = getattr(settings, name)
        if not (math.isfinite(value) and value >= 0):
            writer.fail("settings", f"{name} {value} is not a finite number >= 0")
    return {
        "cruiseSpeed": settings.cruise_speed,
        "firmwareType": writer.in_range(settings.firmware_type, 255, "firmware type", "settings"),
        # as QGC has it after loading a plan from a vehicle: Mixed when there are items
        # (each carries its own AltitudeMode), else its default, Relative
        "globalPlanAltitudeMode": ALT_MODE_MIXED if plan.mission else ALT_MODE_RELATIVE,
        "hoverSpeed": settings.hover_speed,
        "items": items_json(writer, plan.mission),
        "plannedHomePosition": [*writer.checked_lat_lon(lat, lon, "home"), alt],
        "vehicleType": writer.in_range(settings.vehicle_type, 255, "vehicle type", "settings"),
        "version": MISSION_VERSION,
    }


def fallback_home(mission: list[MissionItem]) -> Home:
    """The planned home of a plan that has none, as QGC makes one up
    (MissionController::_setPlannedHomePositionFromFirstCoordinate): 30 m north of the first
    item with a location, at altitude 0; (0, 0, 0) when no item has one (QGC would write an
    invalid coordinate there)."""
    for item in mission:
        if item.command in LOCATION_COMMANDS and item.frame in GLOBAL_FRAMES:
            lat = float(xy_to_decimal(item.frame, item.x))
            lon = float(xy_to_decimal(item.frame, item.y))
            if -90 <= lat <= 90 and -180 <= lon <= 180:
                north = lat + math.degrees(FALLBACK_HOME_OFFSET / _QT_EARTH_MEAN_RADIUS)
                return round(min(north, 90.0), 7), lon, 0.0
    return 0.0, 0.0, 0.0


def _fence_json(writer: JsonWriter, items: list[MissionItem]) -> dict:
    """Group fence items back into shapes: runs of vertices whose param1 is the run's length."""
    polygons: list[dict] = []
    circles: list[dict] = []
    breach_return: list | None = None
    vertices: list[list[float]] = []  # of the polygon being collected
    start = 0  # index of that polygon's first vertex item, whose param1 declares the count

    def incomplete_polygon() -> NoReturn:
        writer.fail(f"fence item {start}", f"polygon declares {items[start].param1:g} vertices "
                                           f"but only {len(vertices)} follow")

    for index, item in enumerate(items):
        where = f"fence item {index}"
        if vertices and item.command != items[start].command:
            incomplete_polygon()
        if item.command in VERTEX_COMMAND.values():
            if not vertices:
                start, count = index, item.param1
                if not (math.isfinite(count) and count >= 3 and count == int(count)):
                    writer.fail(where, f"polygon vertex count (param1) {count:g} "
                                       "is not a whole number >= 3")
            elif item.param1 != items[start].param1:
                writer.fail(where, f"vertex count (param1) {item.param1:g} differs from "
                                   f"{items[start].param1:g} declared by fence item {start}")
            vertices.append(writer.lat_lon(item, where))
            if len(vertices) == items[start].param1:
                inclusion = item.command == Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION
                polygons.append({"inclusion": inclusion, "polygon": vertices,
                                 "version": SHAPE_VERSION})
                vertices = []
        elif item.command in CIRCLE_COMMAND.values():
            if not (math.isfinite(item.param1) and item.param1 > 0):
                writer.fail(where, f"circle radius (param1) {item.param1:g} "
                                   "is not a positive finite number")
            circles.append({
                "circle": {"center": writer.lat_lon(item, where),
                           "radius": writer.float32(item.param1, where)},
                "inclusion": item.command == Cmd.NAV_FENCE_CIRCLE_INCLUSION,
                "version": SHAPE_VERSION,
            })
        elif item.command == Cmd.NAV_FENCE_RETURN_POINT:
            if breach_return is not None:
                writer.fail(where, "a second return point; a .plan file holds only one")
            altitude = writer.finite_float32(item.z, where, "return point altitude")
            breach_return = [*writer.lat_lon(item, where), altitude]
        else:
            writer.fail(where, f"command {item.command} is not a fence command "
                               "a .plan file can hold (5000-5004)")
    if vertices:
        incomplete_polygon()
    fence: dict[str, Any] = {"circles": circles, "polygons": polygons, "version": GEOFENCE_VERSION}
    if breach_return is not None:
        fence["breachReturn"] = breach_return
    return fence


def _rally_point_json(writer: JsonWriter, item: MissionItem, where: str) -> list:
    if item.command != Cmd.NAV_RALLY_POINT:
        writer.fail(where, f"command {item.command} is not MAV_CMD_NAV_RALLY_POINT (5100)")
    altitude = writer.finite_float32(item.z, where, "rally point altitude")
    return [*writer.lat_lon(item, where), altitude]
