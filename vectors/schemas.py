"""The JSON Schemas of the vector files, written beside them by `generate` (schema/*.json),
so a directory of vectors describes itself. docs/vectors.md is the prose version."""

from __future__ import annotations

from typing import Any

from .messages import ERRORS

MESSAGE_FORMAT = "mavconform-vectors/1"

_ID = {"type": "integer", "minimum": 0, "maximum": 255}
_FIELD_VALUE = {"description": "integer; float as a number or 'NaN' / 'Infinity' / '-Infinity'; char[n] as a "
                               "string; other arrays as lists of those"}

MESSAGE_VECTOR: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "mavconform message vector",
    "description": "One MAVLink frame (one line of messages.jsonl). A valid vector (expected_error null) must "
                   "decode to `fields` and re-encode, with the same header and signature, to `hex`. An invalid "
                   "one must be rejected with `expected_error`.",
    "type": "object",
    "required": ["id", "description", "message", "msgid", "version", "signed", "header", "signature",
                 "fields", "hex", "expected_error"],
    "additionalProperties": False,
    "properties": {
        "id": {"type": "string", "pattern": "^[A-Za-z0-9_-]+/[a-z0-9-]+$",
               "description": "MESSAGE/variant, unique and stable across regenerations"},
        "description": {"type": "string"},
        "message": {"type": ["string", "null"], "description": "message name; null for an unknown id"},
        "msgid": {"type": "integer", "minimum": 0, "maximum": 16777215},
        "version": {"type": "integer", "enum": [1, 2]},
        "signed": {"type": "boolean"},
        "header": {"type": "object", "required": ["sysid", "compid", "seq"], "additionalProperties": False,
                   "properties": {"sysid": _ID, "compid": _ID, "seq": _ID}},
        "signature": {"type": ["object", "null"], "required": ["link_id", "timestamp"], "additionalProperties": False,
                      "properties": {"link_id": _ID,
                                     "timestamp": {"type": "integer", "minimum": 0, "maximum": 2 ** 48 - 1}},
                      "description": "signed vectors: the link id and timestamp of the signature block; the key "
                                     "is the test key of index.json"},
        "fields": {"type": ["object", "null"], "additionalProperties": _FIELD_VALUE,
                   "description": "every field of the message, extensions included; null for invalid vectors"},
        "hex": {"type": "string", "pattern": "^([0-9a-f]{2})+$", "description": "the frame's bytes"},
        "expected_error": {"type": ["string", "null"], "enum": [None, *ERRORS]},
        "derived_from": {"type": "string", "description": "invalid vectors: the valid vector they break"},
    },
}

_EVENT = {
    "type": "object",
    "required": ["t", "from", "to", "lost", "msg", "hex"],
    "additionalProperties": False,
    "properties": {
        "t": {"type": "number", "minimum": 0, "description": "virtual seconds since the start, when sent"},
        "from": {"type": "string", "enum": ["gcs", "gcs2", "vehicle"],
                 "description": "gcs2: a handover exchange's second GCS"},
        "to": {"type": "string", "enum": ["gcs", "gcs2", "vehicle"]},
        "lost": {"type": "boolean", "description": "the link lost it (a scripted fault): never delivered"},
        "msg": {"type": "string", "description": "message name, or DECODE_ERROR"},
        "msgid": {"type": "integer"},
        "sysid": _ID, "compid": _ID, "seq": _ID,
        "version": {"type": "integer", "enum": [1, 2]},
        "fields": {"type": "object", "additionalProperties": _FIELD_VALUE},
        "error": {"type": "string"},
        "hex": {"type": "string", "pattern": "^([0-9a-f]{2})*$"},
    },
}

EXCHANGE: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "mavconform exchange transcript",
    "description": "A complete exchange between the reference GCS and a reference vehicle in virtual time "
                   "(exchanges/PROFILE/SCENARIO.json; the same frames are in SCENARIO.mcap); a handover "
                   "exchange (profile 'handover') has two GCSs, 'gcs' and 'gcs2'.",
    "type": "object",
    "required": ["format", "id", "scenario", "profile", "description", "seed", "peers", "link", "steps", "events"],
    "additionalProperties": False,
    "properties": {
        "format": {"type": "string", "enum": ["mavconform-exchange/1"]},
        "id": {"type": "string", "pattern": "^[a-z0-9-]+/[a-z0-9-]+$"},
        "scenario": {"type": "string"},
        "profile": {"type": "string"},
        "description": {"type": "string"},
        "seed": {"type": "integer"},
        "peers": {"type": "object", "required": ["gcs", "vehicle"], "additionalProperties": {
            "type": "object", "required": ["sysid", "compid", "what"], "additionalProperties": False,
            "properties": {"sysid": _ID, "compid": _ID, "what": {"type": "string"}}}},
        "link": {"type": "object", "required": ["latency", "faults"], "additionalProperties": False,
                 "properties": {"latency": {"type": "number", "description": "one-way seconds, both ways"},
                                "faults": {"type": "array", "items": {"type": "string"}}}},
        "steps": {"type": "array", "items": {
            "type": "object", "required": ["label", "start", "end", "result"], "additionalProperties": False,
            "properties": {"label": {"type": "string"}, "start": {"type": "number"}, "end": {"type": "number"},
                           "result": {"type": "string", "description": "'ok' or the GCS's result summary"}}}},
        "events": {"type": "array", "items": _EVENT,
                   "description": "every frame either end sent, in send order"},
    },
}

SCHEMAS = {"message-vector.schema.json": MESSAGE_VECTOR, "exchange.schema.json": EXCHANGE}
