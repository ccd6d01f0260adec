"""MAVLink 2 signing parameters, the timestamp rule (seed 001, "Message Signing"), and keys.

The signature timestamp counts 10 us units since 2015-01-01 00:00 UTC and must increase on
every message of a link. The time comes from the injected clock's wall time, so signed
traffic under `SimClock` is deterministic.

One `SigningKey` is the classic setup: every system on the link shares it. A `Keyring`
holds one key per system id, so a receiver checks each frame against the key of the system
it claims to come from: a GCS that signs with its own key but writes another GCS's system
id into the header fails the check (handover/authenticity.py builds one from a roster).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Iterable, Iterator

SIGNING_EPOCH_UNIX = 1420070400.0  # 2015-01-01T00:00:00Z
# The MAVLink signing guide: a new stream's first timestamp may be at most one minute behind
# the receiver's own (pymavlink and the C library apply it to new streams only).
NEW_STREAM_WINDOW = 60 * 100_000   # in 10 us units


def signing_timestamp(unix_seconds: float) -> int:
    """Signature timestamp (10 us units since 2015) for a Unix time."""
    return max(0, int((unix_seconds - SIGNING_EPOCH_UNIX) * 100_000))


@dataclass(frozen=True)
class SigningKey:
    """A 32-byte secret and the link id written into outgoing signatures."""

    secret: bytes
    link_id: int = 0

    def __post_init__(self) -> None:
        if len(self.secret) != 32:
            raise ValueError(f"a MAVLink signing key is 32 bytes, got {len(self.secret)}")
        if not 0 <= self.link_id <= 255:
            raise ValueError(f"signing link id must be 0..255, got {self.link_id}")


def secret_from_hex(text: str) -> bytes:
    """A key written as 64 hex digits (how keys are usually shared in files)."""
    text = text.strip()
    if len(text) != 64:
        raise ValueError(f"a signing key is 64 hex digits, got {len(text)} characters")
    try:
        return bytes.fromhex(text)
    except ValueError:
        raise ValueError("a signing key is 64 hex digits (0-9, a-f)") from None


def secret_from_passphrase(passphrase: str) -> bytes:
    """SHA-256 of an ASCII passphrase, as MAVProxy's `signing setup` makes a key, so the same
    words give the same key in MAVProxy and here."""
    if not passphrase:
        raise ValueError("the passphrase is empty")
    try:
        data = passphrase.encode("ascii")
    except UnicodeEncodeError:
        raise ValueError("the passphrase must be ASCII (MAVProxy hashes its ASCII bytes)") from None
    return hashlib.sha256(data).digest()


class Keyring:
    """Signing keys by system id: what a receiver with several peers verifies against.

    A frame is checked only against the key of the system id in its header, never against
    "any key we know": otherwise whoever holds one key could speak for every system."""

    __slots__ = ("_keys",)

    def __init__(self, keys: Iterable[tuple[int, SigningKey]]) -> None:
        self._keys: dict[int, SigningKey] = {}
        for sysid, key in keys:
            if not 0 <= sysid <= 255:
                raise ValueError(f"system id must be 0..255, got {sysid}")
            if sysid in self._keys:
                raise ValueError(f"system {sysid} has two keys")
            self._keys[sysid] = key

    def key_for(self, sysid: int) -> SigningKey | None:
        return self._keys.get(sysid)

    def __contains__(self, sysid: object) -> bool:
        return sysid in self._keys

    def __iter__(self) -> Iterator[int]:
        return iter(self._keys)

    def __len__(self) -> int:
        return len(self._keys)

    def __repr__(self) -> str:   # never the secrets
        return f"Keyring(systems={sorted(self._keys)})"
