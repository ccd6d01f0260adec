"""Field values in the vector files, and how two decoders' values are compared.

JSON has no NaN, infinity or float32, so (docs/vectors.md, "Field values"):
- integers are JSON integers (uint64 too: exact in any parser that reads integers as such);
- a float or double is the exact value as a JSON number (a float32 written as the double it
  equals, e.g. 0.10000000149011612), "NaN", "Infinity" or "-Infinity"; -0.0 keeps its sign;
- char[n] is a string (ASCII here; the bytes up to the first NUL);
- any other array is a list of its elements in the same forms.
Two values are the same when their wire bytes would be: floats compared as float32/float64
bit patterns (every NaN alike: a decoder may quieten a signalling NaN), -0.0 unlike 0.0.
"""

from __future__ import annotations

import math
import struct
from typing import Any

from .dialect_info import FieldInfo, MessageInfo

_F32 = struct.Struct("<f")
_F64 = struct.Struct("<d")


def to_json(value: Any, field: FieldInfo) -> Any:
    """A decoded (pymavlink) value in the file's form."""
    if field.is_string:
        if isinstance(value, (bytes, bytearray)):
            value = bytes(value).split(b"\0", 1)[0].decode("ascii", "backslashreplace")
        return value
    if field.array_length:
        return [_scalar_json(v, field) for v in value]
    return _scalar_json(value, field)


def _scalar_json(value: Any, field: FieldInfo) -> Any:
    if field.is_float:
        value = float(value)
        if math.isnan(value):
            return "NaN"
        if math.isinf(value):
            return "Infinity" if value > 0 else "-Infinity"
        return value
    return int(value)


def from_json(value: Any, field: FieldInfo) -> Any:
    """The file's form back to what pymavlink's message constructors take."""
    if field.is_string:
        return value.encode("ascii")
    if field.array_length:
        return [_scalar_from(v, field) for v in value]
    return _scalar_from(value, field)


def _scalar_from(value: Any, field: FieldInfo) -> Any:
    if field.is_float:
        return float({"NaN": "nan", "Infinity": "inf", "-Infinity": "-inf"}.get(value, value)) \
            if isinstance(value, str) else float(value)
    return int(value)


def message_fields(msg: Any, info: MessageInfo) -> dict[str, Any]:
    """Every field of a decoded pymavlink message, in the file's form."""
    return {f.name: to_json(getattr(msg, f.name), f) for f in info.fields}


def same(a: Any, b: Any, field: FieldInfo) -> bool:
    """Whether two file-form values put the same bytes on the wire."""
    if field.is_string:
        return isinstance(a, str) and isinstance(b, str) and a == b
    if field.array_length:
        return (isinstance(a, list) and isinstance(b, list) and len(a) == len(b)
                and all(_same_scalar(x, y, field) for x, y in zip(a, b)))
    return _same_scalar(a, b, field)


def _same_scalar(a: Any, b: Any, field: FieldInfo) -> bool:
    if field.is_float:
        try:
            x, y = _scalar_from(a, field), _scalar_from(b, field)
        except (TypeError, ValueError):
            return False
        if math.isnan(x) or math.isnan(y):
            return math.isnan(x) and math.isnan(y)
        pack = _F32.pack if field.type == "float" else _F64.pack
        try:
            return pack(x) == pack(y)
        except OverflowError:
            return False
    return type(a) is int and type(b) is int and a == b


def field_differences(expected: dict[str, Any], got: dict[str, Any] | None,
                      info: MessageInfo) -> list[str]:
    """One line per field that differs or is missing (fields `got` has beyond the message's
    own are not differences: a newer XML's extensions, which must then be zero)."""
    if got is None:
        return ["no fields decoded"]
    out = []
    for f in info.fields:
        if f.name not in got:
            out.append(f"{f.name}: missing (expected {expected.get(f.name)!r})")
        elif not same(expected.get(f.name), got[f.name], f):
            out.append(f"{f.name}: expected {expected.get(f.name)!r}, got {got[f.name]!r}")
    return out
