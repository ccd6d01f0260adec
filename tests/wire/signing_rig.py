"""Keys, a hand-moved wall clock and frame helpers the signing tests share
(test_signing.py, test_signing_keyring.py). Time is injected, never read from the machine."""

from __future__ import annotations

import hashlib
from typing import Any

from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink
from mavconform.reference_impl.wire.frame import Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import SigningKey

T0 = 1_700_000_000.0  # 2023-11-14, a plain Unix time
SECRET = bytes(range(1, 33))
KEY = SigningKey(SECRET, link_id=7)
OTHER_KEY = SigningKey(bytes(32 * [0xA5]), link_id=7)

VALID = SignatureVerdict.VALID
INVALID = SignatureVerdict.INVALID
UNSIGNED = SignatureVerdict.UNSIGNED
UNCHECKED = SignatureVerdict.UNCHECKED


class Clock:
    """A wall clock the test moves by hand."""

    def __init__(self, t: float = T0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


def item(seq: int = 0) -> Any:
    return mavlink.MAVLink_mission_item_int_message(1, 1, seq, 6, 16, 0, 1, 0.0, 2.0, 0.0, 0.0,
                                                    473_977_420, 85_455_940, 12.5, 0)


def sig_timestamp(raw: bytes) -> int:
    return int.from_bytes(raw[-12:-6], "little")


def expected_signature(secret: bytes, raw: bytes) -> bytes:
    """Independent of pymavlink: SHA-256 over key + everything up to the signature, first 6 bytes."""
    return hashlib.sha256(secret + raw[:-6]).digest()[:6]


def signer(t: float = T0, key: SigningKey = KEY, system: int = 1, component: int = 1) -> FrameEncoder:
    return FrameEncoder(system, component, signing=key, wall_clock=lambda: t)


def decode_one(dec: FrameDecoder, data: bytes) -> Frame:
    [frame] = dec.feed(data)
    assert isinstance(frame, Frame), frame
    return frame


def far_future_forgery(genuine: bytes) -> bytes:
    """The genuine frame with its timestamp pushed a year ahead; the signature no longer fits."""
    ts = sig_timestamp(genuine) + 365 * 24 * 3600 * 100_000
    return genuine[:-12] + ts.to_bytes(6, "little") + genuine[-6:]
