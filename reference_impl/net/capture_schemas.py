"""The JSON schemas a capture registers: its own frame schema, and Foxglove's `foxglove.Log`
for markers (Foxglove recognises a schema by its exact name, so the Log panel lists them)."""

from __future__ import annotations

from typing import Any

SCHEMA_NAME = "mavconform.CapturedFrame"
_NULL_INT = {"type": ["integer", "null"]}
_NULL_STR = {"type": ["string", "null"]}
SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": SCHEMA_NAME,
    "description": "One MAVLink frame (or undecodable bytes) seen on a link",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "driver clock (monotonic or virtual), seconds"},
        "kind": {"type": "string", "enum": ["tx", "rx", "drop"],
                 "description": "tx: sent; rx: arrived, its sending not seen; drop: lost"},
        "src": {"type": "string"},
        "dst": {"type": "string"},
        "msg": {"type": "string", "description": "message name, or DECODE_ERROR"},
        "msgid": _NULL_INT,
        "sysid": _NULL_INT,
        "compid": _NULL_INT,
        "seq": _NULL_INT,
        "version": _NULL_INT,
        "fields": {"type": "object"},
        "signature": _NULL_STR,
        "error": _NULL_STR,
        "frame_index": {"type": "integer", "description": "position of the frame in its datagram"},
        "datagram_len": {"type": "integer"},
        "raw": {"type": "string", "description": "the frame's bytes, hex"},
    },
    "required": ["time", "kind", "src", "dst", "msg", "fields", "raw"],
}

MARKER_SCHEMA_NAME = "foxglove.Log"
LOG_LEVELS = {"debug": 1, "info": 2, "warning": 3, "error": 4, "fatal": 5}
MARKER_SCHEMA: dict[str, Any] = {
    "title": MARKER_SCHEMA_NAME,
    "description": "A log message (here: a mavconform marker, e.g. where a clause starts)",
    "type": "object",
    "properties": {
        "timestamp": {"type": "object", "title": "time", "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}},
        "level": {"type": "integer", "minimum": 0, "maximum": 5,
                  "description": "0 unknown, 1 debug, 2 info, 3 warning, 4 error, 5 fatal"},
        "message": {"type": "string"},
        "name": {"type": "string", "description": "process or node name"},
        "file": {"type": "string"},
        "line": {"type": "integer", "minimum": 0},
    },
    "required": ["timestamp", "level", "message", "name", "file", "line"],
}
