"""MAVLink 2 signing parameters and the timestamp rule (seed 001, "Message Signing").

The signature timestamp counts 10 us units since 2015-01-01 00:00 UTC and must increase on
every message of a link. The time comes from the injected clock's wall time, so signed
traffic under `SimClock` is deterministic.
"""

from __future__ import annotations

from dataclasses import dataclass

SIGNING_EPOCH_UNIX = 1420070400.0  # 2015-01-01T00:00:00Z


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
