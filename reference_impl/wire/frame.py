"""What the wire hands upward: a decoded `Frame`, or a `DecodeError` value.

A decoder never raises on bad bytes; it returns a `DecodeError` naming what was wrong, so
bad input becomes a counted, reportable finding instead of a traceback (DESIGN.md, wire).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Any


class SignatureVerdict(Enum):
    """What the decoder could say about a frame's MAVLink 2 signature."""

    UNSIGNED = "unsigned"    # no signature block
    VALID = "valid"          # signed, and the signature and timestamp check out
    INVALID = "invalid"      # signed, but wrong key, bad signature or stale timestamp
    UNCHECKED = "unchecked"  # signed, but this decoder holds no key to check it


@dataclass(frozen=True, slots=True)
class Frame:
    """One decoded MAVLink frame: header fields, the message, raw bytes, signature verdict."""

    msg: Any                 # a pymavlink MAVLink_message of the codec's dialect
    msgid: int
    src_system: int
    src_component: int
    seq: int
    version: int             # 1 or 2
    incompat_flags: int
    compat_flags: int
    raw: bytes
    signature: SignatureVerdict = SignatureVerdict.UNSIGNED
    link_id: int | None = None

    @property
    def name(self) -> str:
        return self.msg.get_type()

    @property
    def source(self) -> tuple[int, int]:
        return (self.src_system, self.src_component)


@dataclass(frozen=True, slots=True)
class DecodeError:
    """Bytes that did not decode, and why. Returned, counted, never raised."""

    reason: str
    raw: bytes

    def __str__(self) -> str:
        return f"{self.reason} ({len(self.raw)} bytes)"
