"""Byte-level surgery on MAVLink frames: where the fields sit, re-checksumming, re-signing.

The mutators work on encoded bytes, not on messages, because the faults they plant (a wrong
length byte, a flag the checksum does not cover, a signature made with the wrong key) only
exist at that level. Each helper takes one whole, well-formed frame as the encoder made it.

Layouts (seed 001, "Packet format"):
  v2: FD len iflags cflags seq sys comp msgid(3)  payload  crc(2) [link ts(6) sig(6)]
  v1: FE len seq sys comp msgid                   payload  crc(2)
The checksum covers everything from `len` to the end of the payload, plus the message's
CRC_EXTRA; the signature covers the whole frame up to and including its link id and
timestamp (SHA-256 of key + those bytes, first 6 bytes).
"""

from __future__ import annotations

import hashlib
import struct
from typing import Any

from mavconform.reference_impl.wire.codec import (IFLAG_SIGNED, MAGIC_V1, MAGIC_V2, SIGNATURE_LEN,
                                       base_payload_length, default_dialect)

from mavconform.reference_impl.wire.checksum import crc16

_DIALECT = default_dialect()
_MSG_BY_ID: dict[int, Any] = _DIALECT.mavlink_map


def header_len(frame: bytes, start: int = 0) -> int:
    return 10 if frame[start] == MAGIC_V2 else 6


def msgid(frame: bytes) -> int:
    if frame[0] == MAGIC_V2:
        return frame[7] | frame[8] << 8 | frame[9] << 16
    return frame[5]


def is_signed(frame: bytes) -> bool:
    return frame[0] == MAGIC_V2 and bool(frame[2] & IFLAG_SIGNED)


def crc_offset(frame: bytes, start: int = 0) -> int:
    """Index of the first checksum byte of the frame at `start` (in a datagram, say)."""
    return start + header_len(frame, start) + frame[start + 1]


def crc_extra(mid: int) -> int:
    cls = _MSG_BY_ID.get(mid)
    return cls.crc_extra if cls is not None else 0


def checksum(body: bytes, extra: int) -> bytes:
    """The X.25 checksum of `body` and CRC_EXTRA as it goes on the wire (little-endian)."""
    return crc16(body, extra).to_bytes(2, "little")


def rechecksum(frame: bytes, extra: int | None = None) -> bytes:
    """The same frame with its checksum made right for its (possibly edited) header and
    payload; a signature block, if any, is kept as it was (and so no longer matches)."""
    at = crc_offset(frame)
    extra = crc_extra(msgid(frame)) if extra is None else extra
    return frame[:at] + checksum(frame[1:at], extra) + frame[at + 2:]


def unsigned(frame: bytes) -> bytes:
    """A v2 frame without its signature block (flag cleared, checksum redone)."""
    if not is_signed(frame):
        return frame
    body = frame[:2] + bytes([frame[2] & ~IFLAG_SIGNED]) + frame[3:crc_offset(frame)]
    return rechecksum(body + b"\0\0")


def sign(frame: bytes, secret: bytes, link_id: int, timestamp: int) -> bytes:
    """A v2 frame signed with `secret` at `timestamp` (10 us units since 2015)."""
    base = unsigned(frame)
    at = crc_offset(base)
    body = base[:2] + bytes([base[2] | IFLAG_SIGNED]) + base[3:at]
    signed = body + checksum(body[1:], crc_extra(msgid(base)))
    block = signed + bytes([link_id & 0xFF]) + struct.pack("<Q", timestamp)[:6]
    return block + hashlib.sha256(secret + block).digest()[:6]


def as_v1(frame: bytes) -> bytes | None:
    """The frame re-encoded as MAVLink 1 (extensions cut, zero-truncated payload padded back
    to the base length); None if the message id does not fit in one byte."""
    mid = msgid(frame)
    cls = _MSG_BY_ID.get(mid)
    if frame[0] == MAGIC_V1:
        return frame
    if mid > 0xFF or cls is None:
        return None
    base = base_payload_length(cls)
    payload = frame[10:10 + frame[1]][:base].ljust(base, b"\0")
    body = bytes([base, frame[4], frame[5], frame[6], mid]) + payload
    return bytes([MAGIC_V1]) + body + checksum(body, cls.crc_extra)


def signature_len(frame: bytes) -> int:
    return SIGNATURE_LEN if is_signed(frame) else 0
