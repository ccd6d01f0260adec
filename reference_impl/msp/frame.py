"""MSP frames: v1 (`$M`, XOR checksum), v2 native (`$X`, CRC-8/DVB-S2) and v2 inside v1.

Seed 004 ch. 1.3 describes v1: `$M`, a direction byte (`<` to the flight controller, `>`
from it), the payload size, the command (the "type"), the payload, and "the XOR of size,
type and payload bytes". The rest is INAV 9.1's `src/main/msp/msp_serial.c`, the MSP that
flies today: `!` marks an error reply (an unknown command, a payload of the wrong size), v2
carries a flag byte and 16-bit little-endian command and size checksummed by CRC-8/DVB-S2
(polynomial 0xD5, `common/crc.c`), v2 may also travel as the payload of v1 command 255
(`MSP_V2_FRAME_ID`, both checksums then hold), and a reply of 255 bytes or more is a
"jumbo" frame: size byte 255, then the real size as u16 (msp_serial.c:270-352).

`encode` builds the bytes; `MspParser` (parser.py) reads them back from a stream.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import Enum

V2_FRAME_ID = 255           # v1 command that carries a v2 frame (msp_protocol.h)
JUMBO = 255                 # v1 size byte announcing a u16 size (msp_serial.c:270)
TO_FC, FROM_FC, ERROR = "<", ">", "!"
DIRECTIONS = (TO_FC, FROM_FC, ERROR)


class Version(Enum):
    V1 = "v1"
    V2 = "v2"                 # native: $X
    V2_OVER_V1 = "v2-over-v1"


@dataclass(frozen=True)
class MspFrame:
    command: int
    payload: bytes = b""
    direction: str = TO_FC
    version: Version = Version.V1
    flag: int = 0             # v2 only

    def __post_init__(self) -> None:
        if self.direction not in DIRECTIONS:
            raise ValueError(f"MSP direction {self.direction!r}: expected one of {''.join(DIRECTIONS)}")
        top = 0xFF if self.version is Version.V1 else 0xFFFF
        if not 0 <= self.command <= top or (self.version is Version.V1 and self.command == V2_FRAME_ID):
            raise ValueError(f"MSP {self.version.value} command {self.command} out of range")
        if not 0 <= self.flag <= 0xFF:
            raise ValueError(f"MSP v2 flag {self.flag} out of range")
        if len(self.payload) > 0xFFFF:
            raise ValueError(f"MSP payload of {len(self.payload)} bytes: at most 65535")


def crc8_dvb_s2(data: bytes, crc: int = 0) -> int:
    """CRC-8/DVB-S2 (poly 0xD5, init 0, no reflection), as INAV's `crc8_dvb_s2_update`."""
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0xD5) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def xor_checksum(data: bytes) -> int:
    out = 0
    for byte in data:
        out ^= byte
    return out


def _v1(direction: bytes, command: int, payload: bytes) -> bytes:
    """`$M`, direction, size, command, [u16 size if jumbo], payload, XOR of all from size on
    (msp_serial.c:312-330: the jumbo size follows the command byte)."""
    n = len(payload)
    head = bytes((n, command)) if n < JUMBO else bytes((JUMBO, command)) + struct.pack("<H", n)
    body = head + payload
    return b"$M" + direction + body + bytes((xor_checksum(body),))


def encode(frame: MspFrame) -> bytes:
    """The frame's bytes on the wire."""
    d = frame.direction.encode()
    if frame.version is Version.V1:
        return _v1(d, frame.command, frame.payload)
    v2 = struct.pack("<BHH", frame.flag, frame.command, len(frame.payload)) + frame.payload
    v2 += bytes((crc8_dvb_s2(v2),))
    if frame.version is Version.V2:
        return b"$X" + d + v2
    return _v1(d, V2_FRAME_ID, v2)
