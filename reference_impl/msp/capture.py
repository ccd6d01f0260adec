"""MSP frames for a run's MCAP capture (reference_impl/net/capture.py's `frames` hook).

A stream link hands the capture its bytes as they were read, so a frame may be split over two
records: each direction keeps its own `MspParser`, and a record yields the frames it
completes (none while a frame is still arriving). Bytes the parser skipped or refused are
written as DECODE_ERROR with its reason, as the MAVLink capture writes what it cannot decode.
"""

from __future__ import annotations

from typing import Any, Callable

from ..net.sim import CaptureRecord
from .commands import BY_CODE, Waypoint, WaypointInfo
from .frame import MspFrame, encode
from .parser import MspParser

MAX_STREAMS = 64


def frame_fields(frame: MspFrame) -> dict[str, Any]:
    """A frame's fields: direction, framing, and the payload decoded where we know it."""
    fields: dict[str, Any] = {"dir": frame.direction, "version": frame.version.value}
    known = BY_CODE.get(frame.command)
    payload = frame.payload
    if known is not None and known.name in ("MSP_SET_WP", "MSP_WP") and len(payload) == 21:
        fields.update(vars(Waypoint.unpack(payload)))
    elif known is not None and known.name == "MSP_WP_GETINFO" and frame.direction == ">" and len(payload) == 4:
        fields.update(vars(WaypointInfo.unpack(payload)))
    elif payload:
        fields["payload"] = payload.hex()
    return fields


def frame_name(code: int) -> str:
    known = BY_CODE.get(code)
    return known.name if known is not None else f"MSP {code}"


def msp_frames() -> Callable[[CaptureRecord], list[dict[str, Any]]]:
    """A `frames` hook for one capture: parsers per (source, destination, kind)."""
    parsers: dict[tuple[Any, Any, str], MspParser] = {}

    def frames(record: CaptureRecord) -> list[dict[str, Any]]:
        key = (record.src, record.dst, record.kind)
        parser = parsers.get(key)
        if parser is None:
            if len(parsers) >= MAX_STREAMS:
                parsers.pop(next(iter(parsers)))
            parser = parsers[key] = MspParser()
        problems, skipped = parser.stats.problems(), parser.stats.garbage_bytes
        out = [{"msg": frame_name(f.command), "msgid": f.command, "fields": frame_fields(f),
                "raw": encode(f).hex()} for f in parser.feed(record.data)]
        if parser.stats.problems() > problems or parser.stats.garbage_bytes > skipped:
            out.append({"msg": "DECODE_ERROR", "fields": {}, "raw": record.data.hex(),
                        "error": parser.stats.last_error or "bytes outside any MSP frame"})
        return out
    return frames
