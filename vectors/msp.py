"""Golden MSP vectors (msp.jsonl): the mission commands in every framing, and broken frames.

One vector per line, like messages.jsonl: the frame's fields, its bytes, and for a broken one
the error a parser must report (`expected_error`, the names of `MspParser.stats`). Built from
the codec (reference_impl/msp) and fixed payloads, so a regeneration gives the same bytes;
`verify_ours` reads each back, and tests/interop/test_yamspy_msp.py has yamspy read and
write them too.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.msp.commands import COMMANDS, FLAG_LAST, Waypoint, WaypointInfo
from mavconform.reference_impl.msp.frame import ERROR, FROM_FC, TO_FC, MspFrame, Version, encode
from mavconform.reference_impl.msp.parser import MspParser

FILE = "msp.jsonl"
WAYPOINT = Waypoint(1, 1, 473977419, 85455938, 5000, 0, 0, 0, FLAG_LAST)   # the SITL read it back so
EXAMPLES: dict[str, tuple[bytes, bytes]] = {      # command -> (request payload, reply payload)
    "MSP_API_VERSION": (b"", bytes((0, 2, 5))),
    "MSP_WP_MISSION_LOAD": (b"\x00", b""),
    "MSP_WP_MISSION_SAVE": (b"\x00", b""),
    "MSP_WP_GETINFO": (b"", WaypointInfo(0, 120, True, 1).pack()),
    "MSP_WP": (b"\x01", WAYPOINT.pack()),
    "MSP_NAV_STATUS": (b"", bytes.fromhex("00000001000000")),
    "MSP_SET_WP": (WAYPOINT.pack(), b""),
}
VERSIONS = (Version.V1, Version.V2, Version.V2_OVER_V1)


def _vector(vid: str, description: str, frame: MspFrame, data: bytes, error: str | None = None) -> dict[str, Any]:
    return {"id": vid, "description": description, "version": frame.version.value, "direction": frame.direction,
            "command": frame.command, "flag": frame.flag, "payload": frame.payload.hex(), "bytes": data.hex(),
            "expected_error": error}


def generate() -> list[dict[str, Any]]:
    out = []
    for name, (request, reply) in EXAMPLES.items():
        code = COMMANDS[name].code
        for version in VERSIONS:
            for direction, payload, what in ((TO_FC, request, "request"), (FROM_FC, reply, "reply")):
                frame = MspFrame(code, payload, direction, version)
                out.append(_vector(f"msp-{name.lower()}-{what}-{version.value}", f"{name} {what}, {version.value}",
                                   frame, encode(frame)))
    error = MspFrame(COMMANDS["MSP_SET_WP"].code, b"", ERROR, Version.V1)
    out.append(_vector("msp-msp_set_wp-error-v1", "MSP_SET_WP answered `!` (a payload of the wrong size)",
                       error, encode(error)))
    jumbo = MspFrame(COMMANDS["MSP_WP"].code, bytes(range(256)) + bytes(44), FROM_FC, Version.V1)
    out.append(_vector("msp-jumbo-v1", "a 300-byte v1 reply: size 255, command, u16 size (framing only)",
                       jumbo, encode(jumbo)))
    out += _broken()
    return out


def _broken() -> list[dict[str, Any]]:
    request = MspFrame(COMMANDS["MSP_WP"].code, b"\x01")
    v1 = encode(request)
    v2_frame = MspFrame(COMMANDS["MSP_WP"].code, b"\x01", TO_FC, Version.V2)
    v2 = encode(v2_frame)
    huge = MspFrame(COMMANDS["MSP_SET_WP"].code, b"", TO_FC, Version.V2)
    return [
        _vector("msp-bad-xor-v1", "v1 with its XOR checksum off by one bit", request,
                v1[:-1] + bytes((v1[-1] ^ 1,)), "bad_checksum"),
        _vector("msp-bad-crc-v2", "v2 with its CRC-8 off by one bit", v2_frame, v2[:-1] + bytes((v2[-1] ^ 1,)),
                "bad_checksum"),
        _vector("msp-truncated-v1", "a v1 frame cut before its checksum (the stream ends)", request, v1[:-1],
                "truncated"),
        _vector("msp-bad-direction", "`$M` followed by `?`: no MSP direction", request,
                b"$M?" + v1[3:], "bad_header"),
        _vector("msp-oversize-v2", "a v2 header declaring 65535 payload bytes", huge,
                b"$X<" + bytes((0, 209, 0, 0xFF, 0xFF)), "oversize"),
    ]


def verify_ours(vector: dict[str, Any]) -> str | None:
    """None if our parser reads the vector as it says; else one line saying how it does not."""
    data = bytes.fromhex(vector["bytes"])
    parser = MspParser()
    frames = parser.feed(data)
    parser.close()
    error = vector["expected_error"]
    if error is not None:
        count = getattr(parser.stats, error, 0)
        return None if not frames and count else f"expected {error}; got {len(frames)} frame(s), {parser.stats}"
    want = MspFrame(vector["command"], bytes.fromhex(vector["payload"]), vector["direction"],
                    Version(vector["version"]), vector["flag"])
    if frames != [want]:
        return f"read {frames!r}, expected {want!r}"
    if encode(frames[0]) != data:
        return "re-encoded to other bytes"
    return None
