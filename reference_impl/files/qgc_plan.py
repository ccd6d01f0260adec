"""QGroundControl's .plan JSON: mission, geofence and rally points in one file.

QGroundControl is the reference for what the file means. SimpleItem params are the raw
command params (params[4]/[5] are lat/lon only in global frames, so they are scaled by the
item's frame). Fence and rally items are built the way QGC's GeoFenceManager and
RallyPointManager build them for an upload: polygon vertices, then circles, then the
breach-return point; autocontinue off. Reading yields exactly those items; writing accepts
any order that groups into the same shapes. So `load(save(plan)) == plan` holds for every
plan in that form.
"""

from __future__ import annotations

import json
import math
from decimal import Decimal
from typing import Any, NoReturn

from mavconform.reference_impl.files.plan import (
    Plan, PlanFileError, float32_from_decimal, float32_text, plan_from_items, xy_decimals,
    xy_from_decimal, xy_to_decimal,
)
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import GLOBAL_FRAMES, MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

FILE_VERSION = 1
MISSION_VERSION = 2
GEOFENCE_VERSION = 2
RALLY_VERSION = 2
SHAPE_VERSION = 1  # of each polygon and circle
FRAME_GLOBAL = _d.MAV_FRAME_GLOBAL  # polygon vertices and circle centres (as QGC uploads them)
FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT  # rally and breach-return points (as QGC uploads them)
PARAM_COUNT = 7
VERTEX_COMMAND = {True: Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
                  False: Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION}
CIRCLE_COMMAND = {True: Cmd.NAV_FENCE_CIRCLE_INCLUSION, False: Cmd.NAV_FENCE_CIRCLE_EXCLUSION}

# Written because QGC requires these keys; the Plan model does not carry them (QGC defaults).
WRITTEN_MISSION_SETTINGS = {
    "cruiseSpeed": 15,
    "firmwareType": 0,  # MAV_AUTOPILOT_GENERIC
    "hoverSpeed": 5,
    "vehicleType": 0,  # MAV_TYPE_GENERIC
}

Coordinate = tuple[Decimal, Decimal, Decimal]
Home = tuple[float, float, float]


# --- reading -------------------------------------------------------------------------------

class _Reader:
    """Typed access to the parsed document; every problem names its JSON path."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, path: str, problem: str) -> NoReturn:
        raise PlanFileError(f"{self.source}: {path}: {problem}")

    def check(self, value: Any, path: str, kind: str) -> Any:
        """`value` if it is a JSON `kind`: object, array, bool, string, number, integer.

        Numbers come back as Decimal (every written digit kept), integers as int.
        """
        if isinstance(value, (int, Decimal)) and not isinstance(value, bool):
            number = Decimal(value)
            if kind == "number":
                return number
            if (kind == "integer" and number.is_finite() and number.adjusted() < 20
                    and number == number.to_integral_value()):
                return int(number)  # (1e400 is refused above rather than built as an int)
        python_type = {"object": dict, "array": list, "bool": bool, "string": str}.get(kind)
        if python_type is not None and isinstance(value, python_type):
            return value
        article = "an" if kind[0] in "aeiou" else "a"
        self.fail(path, f"expected {article} {kind}, found {_describe(value)}")

    def member(self, obj: dict, key: str, path: str, kind: str) -> Any:
        if key not in obj:
            self.fail(f"{path}.{key}", "missing required key")
        return self.check(obj[key], f"{path}.{key}", kind)

    def integer_in(self, obj: dict, key: str, path: str, high: int) -> int:
        value = self.member(obj, key, path, "integer")
        if not 0 <= value <= high:
            self.fail(f"{path}.{key}", f"{value} is outside 0..{high}")
        return value

    def version(self, obj: dict, path: str, expected: int) -> None:
        if (found := self.member(obj, "version", path, "integer")) != expected:
            self.fail(f"{path}.version", f"unsupported version {found} (expected {expected})")

    def coordinate(self, value: Any, path: str, with_altitude: bool) -> Coordinate:
        """[lat, lon] or [lat, lon, alt] (degrees, metres); alt is 0 where not carried."""
        values = self.check(value, path, "array")
        if len(values) != (3 if with_altitude else 2):
            shape = "[lat, lon, alt]" if with_altitude else "[lat, lon]"
            self.fail(path, f"expected {shape}, found {len(values)} values")
        numbers = [self.check(v, f"{path}[{i}]", "number") for i, v in enumerate(values)]
        for index, (name, limit) in enumerate((("latitude", 90), ("longitude", 180))):
            if not (numbers[index].is_finite() and -limit <= numbers[index] <= limit):
                self.fail(f"{path}[{index}]",
                          f"{name} {numbers[index]} is outside [-{limit}, {limit}]")
        if with_altitude and not numbers[2].is_finite():
            self.fail(f"{path}[2]", f"altitude {numbers[2]} is not finite")
        return numbers[0], numbers[1], numbers[2] if with_altitude else Decimal(0)


def _describe(value: Any) -> str:
    for python_type, name in ((bool, "a bool"), (dict, "an object"), (list, "an array"),
                              (str, "a string"), (type(None), "null")):
        if isinstance(value, python_type):
            return name
    return f"the number {value}"


def parse_qgc_plan(text: str, source: str) -> Plan:
    """The plan in .plan JSON; `source` names the file in errors ("FILE: $.path: problem")."""
    try:
        # Decimal keeps every written digit: degrees become degE7 without a float detour.
        document = json.loads(text, parse_float=Decimal, parse_constant=Decimal)
    except json.JSONDecodeError as error:
        raise PlanFileError(f"{source}: line {error.lineno} column {error.colno}: "
                            f"invalid JSON: {error.msg}") from None
    reader = _Reader(source)
    root = reader.check(document, "$", "object")
    if (file_type := reader.member(root, "fileType", "$", "string")) != "Plan":
        reader.fail("$.fileType", f"expected 'Plan', found {file_type!r}")
    reader.version(root, "$", FILE_VERSION)
    mission, home = _read_mission(reader, reader.member(root, "mission", "$", "object"))
    fence: list[MissionItem] = []
    rally: list[MissionItem] = []
    if "geoFence" in root:  # optional, as in QGC
        fence = _read_fence(reader, reader.member(root, "geoFence", "$", "object"))
    if "rallyPoints" in root:
        rally = _read_rally(reader, reader.member(root, "rallyPoints", "$", "object"))
    return plan_from_items(mission, fence, rally, home)


def _read_mission(reader: _Reader, obj: dict) -> tuple[list[MissionItem], Home | None]:
    path = "$.mission"
    reader.version(obj, path, MISSION_VERSION)
    home = None
    if "plannedHomePosition" in obj:
        lat, lon, alt = reader.coordinate(obj["plannedHomePosition"],
                                          f"{path}.plannedHomePosition", with_altitude=True)
        home = (float(lat), float(lon), float(alt))
    items = reader.member(obj, "items", path, "array")
    return [_read_simple_item(reader, item, f"{path}.items[{index}]")
            for index, item in enumerate(items)], home


def _read_simple_item(reader: _Reader, value: Any, path: str) -> MissionItem:
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
    if "doJumpId" in obj:  # QGC's 1-based item number; items here are numbered by position
        reader.member(obj, "doJumpId", path, "integer")
    raw_params = reader.member(obj, "params", path, "array")
    if len(raw_params) != PARAM_COUNT:
        reader.fail(f"{path}.params", f"expected {PARAM_COUNT} params, found {len(raw_params)}")
    params = [Decimal("NaN") if raw is None else reader.check(raw, f"{path}.params[{i}]", "number")
              for i, raw in enumerate(raw_params)]  # null is how QGC writes NaN
    xy = [xy_from_decimal(frame, params[4]), xy_from_decimal(frame, params[5])]
    for index, scaled in zip((4, 5), xy):
        if scaled is None:
            reader.fail(f"{path}.params[{index}]", f"{params[index]} does not fit "
                        f"MISSION_ITEM_INT's int32 {'xy'[index - 4]} in frame {frame}")
    p1, p2, p3, p4, z = (float32_from_decimal(params[i]) for i in (0, 1, 2, 3, 6))
    return MissionItem(seq=0, frame=frame, command=command, param1=p1, param2=p2, param3=p3,
                       param4=p4, x=xy[0], y=xy[1], z=z, autocontinue=int(autocontinue),
                       mission_type=MissionType.MISSION)


def _position_item(command: int, frame: int, where: Coordinate, param1: float = 0.0) -> MissionItem:
    """A fence or rally item as QGC builds it for upload (autocontinue off, seq set later)."""
    lat, lon, alt = where
    x, y = xy_from_decimal(frame, lat), xy_from_decimal(frame, lon)
    assert x is not None and y is not None  # checked latitude/longitude always fit degE7
    return MissionItem(seq=0, frame=frame, command=command, param1=param1, x=x, y=y,
                       z=float32_from_decimal(alt), autocontinue=0)


def _read_fence(reader: _Reader, obj: dict) -> list[MissionItem]:
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


def _read_rally(reader: _Reader, obj: dict) -> list[MissionItem]:
    path = "$.rallyPoints"
    reader.version(obj, path, RALLY_VERSION)
    return [_position_item(Cmd.NAV_RALLY_POINT, FRAME_GLOBAL_RELATIVE_ALT,
                           reader.coordinate(point, f"{path}.points[{i}]", with_altitude=True))
            for i, point in enumerate(reader.member(obj, "points", path, "array"))]


# --- writing -------------------------------------------------------------------------------

class _Writer:
    """Builds the JSON document; refuses what the reader would refuse, naming the item."""

    def __init__(self, source: str) -> None:
        self.source = source

    def fail(self, where: str, problem: str) -> NoReturn:
        raise PlanFileError(f"{self.source}: {where}: {problem}")

    def float32(self, value: float, where: str) -> int | float | None:
        """A float32 as a JSON number with the fewest digits; NaN is null, as QGC writes it."""
        if math.isnan(value):
            return None
        if math.isinf(value):
            self.fail(where, f"{value} cannot be written: JSON has no infinity")
        text = float32_text(value)  # integral values come back as plain digits: write an int
        return int(text) if text.lstrip("-").isdigit() else float(text)

    def finite_float32(self, value: float, where: str, what: str) -> int | float:
        number = self.float32(value, where)
        if number is None:
            self.fail(where, f"{what} is NaN")
        return number

    def lat_lon(self, item: MissionItem, where: str) -> list[float]:
        if item.frame not in GLOBAL_FRAMES:
            self.fail(where, f"frame {item.frame} is not a global frame; a .plan file stores "
                             "fence and rally positions as latitude/longitude")
        lat = float(xy_to_decimal(item.frame, item.x))
        lon = float(xy_to_decimal(item.frame, item.y))
        return self.checked_lat_lon(lat, lon, where)

    def checked_lat_lon(self, lat: float, lon: float, where: str) -> list[float]:
        if not -90 <= lat <= 90:
            self.fail(where, f"latitude {lat} is outside [-90, 90]")
        if not -180 <= lon <= 180:
            self.fail(where, f"longitude {lon} is outside [-180, 180]")
        return [lat, lon]

    def in_range(self, value: int, high: int, name: str, where: str) -> int:
        if not 0 <= value <= high:
            self.fail(where, f"{name} {value} is outside 0..{high}")
        return value


def format_qgc_plan(plan: Plan, source: str) -> str:
    """.plan JSON for the whole plan, in QGC's layout (keys sorted, 4-space indent)."""
    writer = _Writer(source)
    rally_points = [_rally_point_json(writer, item, f"rally item {index}")
                    for index, item in enumerate(plan.rally)]
    document = {
        "fileType": "Plan",
        "geoFence": _fence_json(writer, plan.fence),
        "groundStation": "mavconform",
        "mission": _mission_json(writer, plan),
        "rallyPoints": {"points": rally_points, "version": RALLY_VERSION},
        "version": FILE_VERSION,
    }
    return json.dumps(document, indent=4, sort_keys=True, allow_nan=False) + "\n"


def _mission_json(writer: _Writer, plan: Plan) -> dict:
    mission: dict[str, Any] = {
        **WRITTEN_MISSION_SETTINGS,
        "items": [_simple_item_json(writer, item, index) for index, item in enumerate(plan.mission)],
        "version": MISSION_VERSION,
    }
    if plan.home is not None:  # QGC requires it, but a plan without home omits it, not invents it
        lat, lon, alt = plan.home
        if not math.isfinite(alt):
            writer.fail("home", f"altitude {alt} is not finite")
        mission["plannedHomePosition"] = [*writer.checked_lat_lon(lat, lon, "home"), alt]
    return mission


def _simple_item_json(writer: _Writer, item: MissionItem, index: int) -> dict:
    where = f"mission item {index}"
    params = [writer.float32(p, where) for p in (item.param1, item.param2, item.param3, item.param4)]
    for value in (item.x, item.y):  # the exact decimal's nearest double reads back to this int
        params.append(float(xy_to_decimal(item.frame, value)) if xy_decimals(item.frame) else value)
    params.append(writer.float32(item.z, where))
    return {
        "autoContinue": bool(writer.in_range(item.autocontinue, 1, "autocontinue", where)),
        "command": writer.in_range(item.command, 65535, "command", where),
        "doJumpId": index + 1,
        "frame": writer.in_range(item.frame, 255, "frame", where),
        "params": params,
        "type": "SimpleItem",
    }


def _fence_json(writer: _Writer, items: list[MissionItem]) -> dict:
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


def _rally_point_json(writer: _Writer, item: MissionItem, where: str) -> list:
    if item.command != Cmd.NAV_RALLY_POINT:
        writer.fail(where, f"command {item.command} is not MAV_CMD_NAV_RALLY_POINT (5100)")
    altitude = writer.finite_float32(item.z, where, "rally point altitude")
    return [*writer.lat_lon(item, where), altitude]
