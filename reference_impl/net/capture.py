"""McapCapture: every frame of a run, as an MCAP file that opens in Foxglove.

Used as a capture hook on `SimNetwork`, `UdpDriver` or `ChaosProxy`. Each `CaptureRecord`
is split into its frames with a keyless `FrameDecoder` (so capture never needs, or leaks, a
signing key; signed frames get the verdict "unchecked") and each frame becomes one JSON
message. Bytes that do not decode are written too, as "DECODE_ERROR" with the reason: a
capture that hid the garbage would hide the finding. JSON has no NaN or infinity and no
bytes, so those become strings ("NaN", hex).

Layout (topics are stable; Foxglove lists them by name):
- "<sender> -> <receiver>", one channel per direction per peer ("gcs -> vehicle",
  "127.0.0.1:14550 -> [::1]:5760"), metadata {"sender", "receiver"}: each datagram once.
  `tx` when the capture saw it sent; `rx` when it saw only the arrival (a sender outside
  the driver, or a duplicate or corrupted copy the link made). The `rx` of a datagram
  already written as `tx` is not written again (see `InFlight`).
- "<sender> -> <receiver> (lost)", metadata also {"lost": "true"}: each datagram a fault
  or a missing route ate, kind `drop`, at the time it was lost. A lost datagram the capture
  saw sent is also on its direction's channel, as its `tx`: that one is what was sent,
  this one says it never arrived.
- "markers" (`foxglove.Log`, so the Log panel shows them): `mark()` labels, e.g. where
  each clause starts.

Time: log_time is wall-clock Unix nanoseconds, from the record's `wall` stamp (the driver
clock's `wall()`: real time over UDP, a fixed epoch plus virtual seconds under SimNetwork, so
a seeded run writes the same bytes twice), or, for records without one, from the injected
`wall_clock` when the record is written. publish_time is the driver clock's own time
(monotonic or virtual seconds), as the JSON body's "time".
"""

from __future__ import annotations

import json
import math
import os
import time
from typing import IO, Any, Callable

from mcap.well_known import MessageEncoding, SchemaEncoding
from mcap.writer import CompressionType, Writer

from ..errors import UsageError
from ..wire.codec import FrameDecoder
from ..wire.frame import DecodeError
from .capture_schemas import LOG_LEVELS, MARKER_SCHEMA, MARKER_SCHEMA_NAME, SCHEMA, SCHEMA_NAME
from .clock import Clock
from .inflight import InFlight
from .node import Address
from .sim import CaptureRecord

MARKERS_TOPIC = "markers"
LOST_SUFFIX = " (lost)"


def address_label(address: Address) -> str:
    """'gcs' for a sim name, '127.0.0.1:14550' or '[::1]:14550' for a UDP address."""
    if isinstance(address, tuple) and len(address) >= 2:
        host = str(address[0])
        return f"[{host}]:{address[1]}" if ":" in host else f"{host}:{address[1]}"
    return str(address)


def direction_topic(src: Address, dst: Address) -> str:
    """The topic of the frames `src` sends to `dst`: 'gcs -> vehicle'."""
    return f"{address_label(src)} -> {address_label(dst)}"


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


def _ns(seconds: float) -> int:
    """Whole nanoseconds, >= 0. Seconds and fraction apart: `seconds * 1e9` would round a
    Unix time (~1.8e18 ns, past a float's 53 bits) to a multiple of 256 ns."""
    whole = math.floor(seconds)
    return max(0, whole * 1_000_000_000 + round((seconds - whole) * 1e9))


class McapCapture:
    """A capture hook writing an MCAP file; call close() (or use `with`) to finish it.

    `wall_clock` (Unix seconds) times records that carry no wall stamp and markers given
    no clock; tests inject a fixed one."""

    def __init__(self, path: str | os.PathLike[str], *, dialect: Any = None,
                 wall_clock: Callable[[], float] = time.time, compress: bool = True,
                 frames: Callable[[CaptureRecord], list[dict[str, Any]]] | None = None) -> None:
        self.path = os.fspath(path)
        # another protocol's frames (MSP: reference_impl/msp/capture.py): the record's bodies
        # (msg, msgid, fields, error, raw; the rest null) instead of MAVLink's
        self._frames = frames
        self._wall_clock = wall_clock
        self._decoder = FrameDecoder(dialect=dialect)
        self._in_flight = InFlight()
        try:
            self._stream: IO[bytes] = open(self.path, "wb")
        except OSError as exc:
            raise UsageError(f"cannot write capture file {self.path!r}: {exc.strerror}") from None
        # compress=False: bytes that depend on no compressor's version (committed golden files)
        try:
            self._writer = Writer(self._stream, compression=CompressionType.ZSTD if compress else CompressionType.NONE)
        except Exception:  # zstandard missing: an uncompressed file is still a valid MCAP
            self._writer = Writer(self._stream, compression=CompressionType.NONE)
        self._writer.start(profile="", library="mavconform")
        self._schema_id = self._writer.register_schema(
            SCHEMA_NAME, SchemaEncoding.JSONSchema, json.dumps(SCHEMA).encode())
        self._marker_schema_id: int | None = None
        self._channels: dict[str, int] = {}
        self._sequence: dict[int, int] = {}
        self.messages = 0  # frames and markers written
        self._closed = False

    def __call__(self, record: CaptureRecord) -> None:
        self._check_open()
        src, dst = record.src, record.dst
        if record.kind == "tx":
            self._in_flight.sent(src, dst, record.data)
        elif self._in_flight.settle(src, dst, record.data) and record.kind == "rx":
            return  # the arrival of a datagram already written as sent
        lost = record.kind == "drop"
        channel = self._frame_channel(src, dst, lost)
        wall = record.wall if record.wall is not None else self._wall_clock()
        self._write_frames(channel, record, _ns(wall))

    def mark(self, label: str, *, clock: Clock | None = None, level: str = "info") -> None:
        """Write `label` on the "markers" channel, timed by `clock` (pass the driver's: its
        `wall()` is the log time, so a virtual-time run stays deterministic, and its `now()`
        the publish time); without one, by the capture's wall clock."""
        self._check_open()
        if level not in LOG_LEVELS:
            raise ValueError(f"marker level must be one of {sorted(LOG_LEVELS)}, got {level!r}")
        log_time = _ns(clock.wall() if clock is not None else self._wall_clock())
        publish_time = _ns(clock.now()) if clock is not None else log_time
        if self._marker_schema_id is None:
            self._marker_schema_id = self._writer.register_schema(
                MARKER_SCHEMA_NAME, SchemaEncoding.JSONSchema, json.dumps(MARKER_SCHEMA).encode())
        channel = self._channel(MARKERS_TOPIC, self._marker_schema_id, {})
        sec, nsec = divmod(log_time, 1_000_000_000)
        body = {"timestamp": {"sec": sec, "nsec": nsec}, "level": LOG_LEVELS[level],
                "message": label, "name": "mavconform", "file": "", "line": 0}
        self._add(channel, log_time, publish_time, body)

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

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError(f"McapCapture {self.path!r} is closed")

    def _write_frames(self, channel: int, record: CaptureRecord, log_time: int) -> None:
        src, dst = address_label(record.src), address_label(record.dst)
        if self._frames is not None:
            for index, described in enumerate(self._frames(record)):
                body = {"time": record.time, "kind": record.kind, "src": src, "dst": dst, "frame_index": index,
                        "datagram_len": len(record.data), "msgid": None, "sysid": None, "compid": None,
                        "seq": None, "version": None, "signature": None, "error": None, **described}
                self._add(channel, log_time, _ns(record.time), body)
            return
        items: list[Any] = list(self._decoder.feed(record.data))
        if not items:
            items = [DecodeError("empty datagram", b"")]
        for index, item in enumerate(items):
            body = {"time": record.time, "kind": record.kind, "src": src, "dst": dst,
                    "frame_index": index, "datagram_len": len(record.data)}
            body.update(_describe(item))
            self._add(channel, log_time, _ns(record.time), body)

    def _frame_channel(self, src: Address, dst: Address, lost: bool) -> int:
        topic = direction_topic(src, dst) + (LOST_SUFFIX if lost else "")
        channel = self._channels.get(topic)
        if channel is not None:
            return channel
        metadata = {"sender": address_label(src), "receiver": address_label(dst)}
        if lost:
            metadata["lost"] = "true"
        return self._channel(topic, self._schema_id, metadata)

    def _channel(self, topic: str, schema_id: int, metadata: dict[str, str]) -> int:
        channel = self._channels.get(topic)
        if channel is None:
            channel = self._channels[topic] = self._writer.register_channel(
                topic, MessageEncoding.JSON, schema_id, metadata)
            self._sequence[channel] = 0
        return channel

    def _add(self, channel: int, log_time: int, publish_time: int, body: dict[str, Any]) -> None:
        seq = self._sequence[channel] = self._sequence[channel] + 1
        self._writer.add_message(
            channel, log_time=log_time, publish_time=publish_time, sequence=seq,
            data=json.dumps(body, allow_nan=False, separators=(",", ":")).encode())
        self.messages += 1


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
