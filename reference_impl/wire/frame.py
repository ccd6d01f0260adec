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


class SignatureFault(Enum):
    """Why a signed frame is INVALID, so the layer above can count and log each kind apart
    (a replay says someone records the link; a bad signature, that someone forges)."""

    BAD_SIGNATURE = "bad signature"  # the claimed sender's key does not give it: another key, or tampered
    REPLAYED = "replayed"            # a genuine signature, but not newer than its stream's last frame
                                     # (or a new stream more than a minute behind our clock)
    UNKNOWN_KEY = "unknown key"      # signed, claiming a system the decoder's keyring has no key for


@dataclass(slots=True)
class Frame:
    """One decoded MAVLink frame: header fields, the message, raw bytes, signature verdict.

    Built for every frame on the hot path, so it stores only what the decoder has at hand
    and reads the header fields from the message's pymavlink header when asked. Treat it
    as read-only.
    """

    msg: Any                 # a pymavlink MAVLink_message of the codec's dialect
    raw: bytes
    src_system: int
    src_component: int
    signature: SignatureVerdict = SignatureVerdict.UNSIGNED
    link_id: int | None = None
    fault: SignatureFault | None = None   # set exactly when `signature` is INVALID

    @property
    def authenticity(self) -> str:
        """One label per frame for counters and logs: "ok", "unsigned", "unchecked", or the
        fault ("bad signature", "replayed", "unknown key")."""
        if self.fault is not None:
            return self.fault.value
        return "ok" if self.signature is SignatureVerdict.VALID else self.signature.value

    @property
    def name(self) -> str:
        return self.msg._type

    @property
    def msgid(self) -> int:
        return self.msg._header.msgId

    @property
    def source(self) -> tuple[int, int]:
        return (self.src_system, self.src_component)

    @property
    def seq(self) -> int:
        return self.msg._header.seq

    @property
    def version(self) -> int:
        return 1 if self.raw[0] == 0xFE else 2

    @property
    def incompat_flags(self) -> int:
        return self.msg._header.incompat_flags

    @property
    def compat_flags(self) -> int:
        return self.msg._header.compat_flags


@dataclass(frozen=True, slots=True)
class DecodeError:
    """Bytes that did not decode, and why. Returned, counted, never raised."""

    reason: str
    raw: bytes

    def __str__(self) -> str:
        return f"{self.reason} ({len(self.raw)} bytes)"
