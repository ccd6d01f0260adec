"""McapCapture: every frame of a run, as an MCAP file that opens in Foxglove.

Used as a capture hook on `SimNetwork` or `UdpDriver`. Each `CaptureRecord` is split into
its frames with a keyless `FrameDecoder` (so capture never needs, or leaks, a signing key;
signed frames get the verdict "unchecked") and each frame becomes one JSON message on the
channel of its direction ("gcs->vehicle"). Bytes that do not decode are written too, as
"DECODE_ERROR" with the reason: a capture that hid the garbage would hide the finding.
JSON has no NaN or infinity and no bytes, so those become strings ("NaN", hex).
"""

from __future__ import annotations

import json
import math
import os
from typing import IO, Any

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from ..errors import UsageError
from ..wire.codec import FrameDecoder
from ..wire.frame import DecodeError
from .node import Address
from .sim import CaptureRecord

SCHEMA_NAME = "mavconform.CapturedFrame"
_NULL_INT = {"type": ["integer", "null"]}
_NULL_STR = {"type": ["string", "null"]}
SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": SCHEMA_NAME,
    "description": "One MAVLink frame (or undecodable bytes) seen on a link",
    "type": "object",
    "properties": {
        "time": {"type": "number", "description": "driver clock, seconds"},
        "kind": {"type": "string", "enum": ["tx", "rx", "drop"]},
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


def address_label(address: Address) -> str:
    """'gcs' for a sim name, '127.0.0.1:14550' for a UDP address."""
    if isinstance(address, tuple) and len(address) == 2:
        return f"{address[0]}:{address[1]}"
    return str(address)


def json_safe(value: Any) -> Any:
    """A JSON-encodable copy: non-finite floats as strings, bytes as hex."""
    if isinstance(value, float):
        if math.isfinite(value):
            return value
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).hex()
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


class McapCapture:
    """A capture hook writing an MCAP file; call close() (or use `with`) to finish it."""

    def __init__(self, path: str | os.PathLike[str], *, dialect: Any = None) -> None:
        self.path = os.fspath(path)
        self._decoder = FrameDecoder(dialect=dialect)
        try:
            self._stream: IO[bytes] = open(self.path, "wb")
        except OSError as exc:
            raise UsageError(f"cannot write capture file {self.path!r}: {exc.strerror}") from None
        try:
            self._writer = Writer(self._stream, compression=CompressionType.ZSTD)
        except Exception:  # zstandard missing: an uncompressed file is still a valid MCAP
            self._writer = Writer(self._stream, compression=CompressionType.NONE)
        self._writer.start(profile="", library="mavconform")
        self._schema_id = self._writer.register_schema(
            SCHEMA_NAME, SchemaEncoding.JSONSchema, json.dumps(SCHEMA).encode())
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self.messages = 0
        self._closed = False

    def __call__(self, record: CaptureRecord) -> None:
        if self._closed:
            raise ValueError(f"McapCapture {self.path!r} is closed")
        src, dst = address_label(record.src), address_label(record.dst)
        channel = self._channel(f"{src}->{dst}")
        log_time = max(0, round(record.time * 1e9))
        items: list[Any] = list(self._decoder.feed(record.data))
        if not items:
            items = [DecodeError("empty datagram", b"")]
        for index, item in enumerate(items):
            body = {"time": record.time, "kind": record.kind, "src": src, "dst": dst,
                    "frame_index": index, "datagram_len": len(record.data)}
            body.update(_describe(item))
            seq = self._sequence[channel] = self._sequence[channel] + 1
            self._writer.add_message(
                channel, log_time=log_time, publish_time=log_time, sequence=seq,
                data=json.dumps(body, allow_nan=False, separators=(",", ":")).encode())
            self.messages += 1

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._writer.finish()
        finally:
            self._stream.close()

    def __enter__(self) -> "McapCapture":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _channel(self, topic: str) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            channel = self._channels[topic] = self._writer.register_channel(
                topic, MessageEncoding.JSON, self._schema_id)
            self._sequence[channel] = 0
        return channel


def _describe(item: Any) -> dict[str, Any]:
    if isinstance(item, DecodeError):
        return {"msg": "DECODE_ERROR", "msgid": None, "sysid": None, "compid": None,
                "seq": None, "version": None, "fields": {}, "signature": None,
                "error": item.reason, "raw": item.raw.hex()}
    msg = item.msg
    fields = {name: json_safe(getattr(msg, name)) for name in msg.fieldnames}
    return {"msg": item.name, "msgid": item.msgid, "sysid": item.src_system,
            "compid": item.src_component, "seq": item.seq, "version": item.version,
            "fields": fields, "signature": item.signature.value, "error": None,
            "raw": item.raw.hex()}
