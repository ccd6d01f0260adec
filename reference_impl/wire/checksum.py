"""The MAVLink frame checksum: X.25 (CRC-16/MCRF4XX) over len .. payload, then CRC_EXTRA."""

from __future__ import annotations

from .dialect import mavlink as _dialect

_X25 = _dialect.x25crc
_CRC_CACHE: dict[tuple[bytes, int], int] = {}


def crc16(body: bytes, extra: int) -> int:
    """X.25 over `body` (len .. end of payload) then CRC_EXTRA, by the dialect's x25crc;
    cached, since fuzz frames and the parser model's re-reads repeat the same bodies."""
    key = (body, extra)
    crc = _CRC_CACHE.get(key)
    if crc is None:
        x = _X25(body)
        x.accumulate(bytes((extra,)))
        crc = x.crc
        if len(_CRC_CACHE) > 50_000:
            _CRC_CACHE.clear()
        _CRC_CACHE[key] = crc
    return crc
