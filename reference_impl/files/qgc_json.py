"""Typed access to a .plan's JSON, both ways: every problem is one line naming the file and
the JSON path ($.mission.items[3].params[6]) or, when writing, the item."""

from __future__ import annotations

import math
from decimal import Decimal
from typing import Any, NoReturn

from mavconform.reference_impl.files.plan import PlanFileError, float32_text, xy_to_decimal
from mavconform.reference_impl.mission.items import GLOBAL_FRAMES, MissionItem

Coordinate = tuple[Decimal, Decimal, Decimal]
Home = tuple[float, float, float]


class JsonReader:
    """Reads the parsed document (numbers as Decimal); `fail` names the file and JSON path."""

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
        self.fail(path, f"expected {article} {kind}, found {describe(value)}")

    def number_or_null(self, value: Any, path: str) -> Decimal:
        """A number, or NaN for null (how QGC writes NaN)."""
        return Decimal("NaN") if value is None else self.check(value, path, "number")

    def member(self, obj: dict, key: str, path: str, kind: str) -> Any:
        if key not in obj:
            self.fail(f"{path}.{key}", "missing required key")
        return self.check(obj[key], f"{path}.{key}", kind)

    def optional(self, obj: dict, key: str, path: str, kind: str) -> Any:
        """The member if present (checked), else None."""
        return self.member(obj, key, path, kind) if key in obj else None

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


def describe(value: Any) -> str:
    for python_type, name in ((bool, "a bool"), (dict, "an object"), (list, "an array"),
                              (str, "a string"), (type(None), "null")):
        if isinstance(value, python_type):
            return name
    return f"the number {value}"


class JsonWriter:
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
