"""A resyncing MSP stream parser, sans-IO: bytes in, frames out, never an exception.

TCP and serial links deliver MSP as a byte stream with no frame boundaries, and a bench
serial line carries garbage (a boot banner, a CLI prompt, line noise). `feed` takes bytes
as they come and returns every whole frame with a good checksum; anything else is counted
(`stats`) and skipped. After a bad frame the parser looks for the next `$` from the byte
after the one it started at, so a frame hidden behind a bad header is still found (INAV's
own parser, msp_serial.c:84-262, goes back to IDLE at the failing byte instead; it is the
flight controller's side, this one also reads replies and error frames).

A `$` whose frame is still incomplete is given up for a later frame that is already whole
with a good checksum (`_complete_later`): line noise that looks like a header must not hold
back the replies behind it. A frame whose declared size exceeds `max_payload` is refused at
its header (INAV refuses requests over MSP_PORT_INBUF_SIZE so, msp_serial.c:141, 189, 228);
bytes that end the stream inside a frame are `pending` until `close`, which counts them as
truncated.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from .frame import DIRECTIONS, JUMBO, V2_FRAME_ID, MspFrame, Version, crc8_dvb_s2, xor_checksum

MAX_PAYLOAD = 4096          # bytes: well above any mission reply (MSP_WP: 21)
MAX_BUFFER = 8 * 65536      # bytes held while a frame is incomplete, at most


@dataclass
class ParserStats:
    frames: int = 0
    garbage_bytes: int = 0      # skipped while looking for a frame start
    bad_checksum: int = 0
    oversize: int = 0           # declared size above max_payload
    bad_header: int = 0         # `$` followed by something that is no MSP header
    truncated: int = 0          # frames cut off by `close`
    last_error: str = ""
    by_version: dict[str, int] = field(default_factory=dict)

    def problems(self) -> int:
        return self.bad_checksum + self.oversize + self.bad_header + self.truncated


class _Need(Exception):
    """More bytes are needed to decide (internal: never leaves `feed`)."""


class MspParser:
    def __init__(self, *, accept: str = "".join(DIRECTIONS), max_payload: int = MAX_PAYLOAD) -> None:
        self.accept = accept          # directions kept; a frame of another is skipped, counted as bad_header
        self.max_payload = max_payload
        self.stats = ParserStats()
        self._buf = bytearray()
        self._probing = False      # looking ahead (_complete_later): nothing is counted

    @property
    def pending(self) -> int:
        """Bytes held for a frame not yet complete."""
        return len(self._buf)

    def feed(self, data: bytes) -> list[MspFrame]:
        self._buf += data
        out: list[MspFrame] = []
        for _ in range(len(self._buf) + 1):       # each round consumes at least one byte or stops
            start = self._buf.find(b"$")
            if start < 0:
                self._skip(len(self._buf))
                break
            if start:
                self._skip(start)
            try:
                frame, used = self._parse()
            except _Need:
                later = self._complete_later()
                if later is None:
                    break
                self._fail("bad_header", "a frame start whose frame never came (a later frame was whole)")
                self._skip(later)    # the false start and what follows it, up to the whole frame
                continue
            if frame is None:
                del self._buf[:1]        # rescan from the byte after this `$`
                continue
            del self._buf[:used]
            self.stats.frames += 1
            key = frame.version.value
            self.stats.by_version[key] = self.stats.by_version.get(key, 0) + 1
            out.append(frame)
        if len(self._buf) > MAX_BUFFER:           # cannot happen with max_payload <= 65535; bounded anyway
            self._fail("oversize", f"{len(self._buf)} bytes without a frame")
            self._buf.clear()
        return out

    def close(self) -> None:
        """The stream ended: a frame still incomplete is counted as truncated."""
        if self._buf:
            self._fail("truncated", f"the stream ended {len(self._buf)} bytes into a frame")
            self._buf.clear()

    # --- one frame at the start of the buffer ------------------------------------------------
    def _parse(self) -> tuple[MspFrame | None, int]:
        b = self._buf
        self._need(3)
        kind, direction = b[1:2], chr(b[2])
        if kind not in (b"M", b"X") or direction not in DIRECTIONS:
            return self._bad("bad_header", f"'$' followed by {bytes(b[1:3])!r}"), 0
        if direction not in self.accept:
            return self._bad("bad_header", f"a frame in direction {direction!r}, not read here"), 0
        if kind == b"X":
            return self._v2(3, direction, Version.V2, None)
        self._need(5)
        size, command, at = b[3], b[4], 5
        if size == JUMBO:
            self._need(7)
            size, at = struct.unpack_from("<H", b, 5)[0], 7
        if size > self.max_payload + (6 if command == V2_FRAME_ID else 0):
            return self._bad("oversize", f"v1 size {size} over {self.max_payload}"), 0
        self._need(at + size + 1)
        if xor_checksum(b[3:at + size]) != b[at + size]:
            return self._bad("bad_checksum", f"v1 command {command}: XOR checksum"), 0
        if command != V2_FRAME_ID:
            return MspFrame(command, bytes(b[at:at + size]), direction, Version.V1), at + size + 1
        if size < 6:
            return self._bad("bad_header", f"a v2-over-v1 frame of {size} bytes"), 0
        inner, used = self._v2(at, direction, Version.V2_OVER_V1, at + size)
        return inner, (at + size + 1 if inner is not None else 0)

    def _v2(self, at: int, direction: str, version: Version, end: int | None) -> tuple[MspFrame | None, int]:
        """A v2 header, payload and CRC-8 from `at`; `end`: where the enclosing v1 payload ends."""
        b = self._buf
        self._need(at + 5)
        flag, command, size = struct.unpack_from("<BHH", b, at)
        if size > self.max_payload:
            return self._bad("oversize", f"v2 size {size} over {self.max_payload}"), 0
        stop = at + 5 + size
        if end is not None and stop + 1 != end:
            return self._bad("bad_header", f"a v2 size of {size} in a v1 payload of {end - at}"), 0
        self._need(stop + 1)
        if crc8_dvb_s2(b[at:stop]) != b[stop]:
            return self._bad("bad_checksum", f"v2 command {command}: CRC-8"), 0
        return MspFrame(command, bytes(b[at + 5:stop]), direction, version, flag), stop + 1

    def _complete_later(self) -> int | None:
        """While the frame at the buffer's start waits for bytes: the offset of a later `$`
        that starts a whole frame with a good checksum, if any. A noise byte that looks like a
        header with a large size would otherwise swallow the replies behind it until that
        many more bytes came (INAV's parser has that weakness; a client waiting on one reply
        must not)."""
        whole = bytes(self._buf)
        at = whole.find(b"$", 1)
        self._probing = True
        try:
            while at > 0:
                self._buf = bytearray(whole[at:])
                try:
                    frame, _ = self._parse()
                except _Need:
                    frame = None
                if frame is not None:
                    return at
                at = whole.find(b"$", at + 1)
            return None
        finally:
            self._buf = bytearray(whole)
            self._probing = False

    # --- bookkeeping -------------------------------------------------------------------------
    def _need(self, n: int) -> None:
        if len(self._buf) < n:
            raise _Need

    def _bad(self, kind: str, why: str) -> None:
        self._fail(kind, why)
        return None

    def _fail(self, kind: str, why: str) -> None:
        if self._probing:
            return
        setattr(self.stats, kind, getattr(self.stats, kind) + 1)
        self.stats.last_error = why

    def _skip(self, n: int) -> None:
        self.stats.garbage_bytes += n
        del self._buf[:n]
