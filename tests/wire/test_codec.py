"""The frame codec: MAVLink 1/2 framing over our dialect, and decoding that never raises.

The byte-level check rebuilds frames from the spec (header struct, field order from the XML,
zero truncation, CRC-16/MCRF4XX with CRC_EXTRA) with a small implementation of its own, so
the encoder is checked against MAVLink rather than only against pymavlink.
"""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET
from typing import Any

import pytest

from mavconform.reference_impl.wire.codec import (
    MAGIC_V1,
    MAGIC_V2,
    FrameDecoder,
    FrameEncoder,
)
from mavconform.reference_impl.wire.dialect import XML_PATH, mavlink
from mavconform.reference_impl.wire.frame import Frame, SignatureVerdict

from .codec_samples import FIXED_WALL, KEY, fields_of, sample_messages, v1_capable


# --- round trips -------------------------------------------------------------------------------

@pytest.mark.parametrize("version", [2, 1])
def test_round_trip_header_fields_and_raw_bytes(version: int) -> None:
    enc = FrameEncoder(42, 190, version=version)
    dec = FrameDecoder()
    msgs = sample_messages() if version == 2 else v1_capable(sample_messages())
    for i, msg in enumerate(msgs):
        data = enc.encode(msg)
        assert data[0] == (MAGIC_V2 if version == 2 else MAGIC_V1)
        [frame] = dec.feed(data)
        assert isinstance(frame, Frame), frame
        assert frame.msgid == msg.id
        assert frame.name == msg.get_type()
        assert (frame.src_system, frame.src_component) == frame.source == (42, 190)
        assert frame.seq == i
        assert frame.version == version
        assert frame.incompat_flags == 0
        assert frame.compat_flags == 0
        assert frame.raw == data
        assert frame.signature is SignatureVerdict.UNSIGNED
        assert frame.link_id is None
        if version == 2:
            assert fields_of(frame.msg) == fields_of(msg)
        else:  # MAVLink 1 carries the base fields; whether extensions ride along is not pinned here
            base = {f[0] for f in xml_layout(msg.get_type())[1]}
            assert {k: v for k, v in fields_of(frame.msg).items() if k in base} == \
                {k: v for k, v in fields_of(msg).items() if k in base}
    assert enc.frames_sent == len(msgs)
    assert (dec.frames, dec.errors, dec.bad_signatures) == (len(msgs), 0, 0)


def test_per_call_version_override() -> None:
    enc = FrameEncoder(1, 1, version=2)
    msg = mavlink.MAVLink_mission_request_list_message(1, 1, mission_type=0)
    assert enc.encode(msg, version=1)[0] == MAGIC_V1
    assert enc.encode(msg)[0] == MAGIC_V2
    [f1, f2] = FrameDecoder().feed(FrameEncoder(1, 1, version=1).encode(msg) + enc.encode(msg))
    assert (f1.version, f2.version) == (1, 2)


def test_constructor_rejects_unknown_version() -> None:
    with pytest.raises(ValueError):
        FrameEncoder(1, 1, version=3)


def test_sequence_increments_and_wraps_at_256() -> None:
    enc = FrameEncoder(1, 1)
    dec = FrameDecoder()
    msg = mavlink.MAVLink_mission_item_reached_message(5)
    seqs = []
    for _ in range(600):
        [frame] = dec.feed(enc.encode(msg))
        seqs.append(frame.seq)
    assert seqs == [i % 256 for i in range(600)]
    # each sender has its own counter
    assert FrameDecoder().feed(FrameEncoder(1, 2).encode(msg))[0].seq == 0


def test_v1_refuses_msgid_above_255_and_signing() -> None:
    enc = FrameEncoder(1, 1, version=1)
    big = mavlink.MAVLink_control_status_message(0, 255, [0] * 10)
    assert big.id == 512
    with pytest.raises(ValueError, match="MAVLink 1"):
        enc.encode(big)
    with pytest.raises(ValueError):
        FrameEncoder(1, 1).encode(mavlink.MAVLink_setup_signing_message(1, 1, [0] * 32, 0), version=1)
    # a refused message does not consume a sequence number
    assert FrameDecoder().feed(enc.encode(mavlink.MAVLink_mission_item_reached_message(1)))[0].seq == 0
    assert enc.frames_sent == 1

    signed_v1 = FrameEncoder(1, 1, version=1, signing=KEY, wall_clock=lambda: FIXED_WALL)
    with pytest.raises(ValueError, match="signed"):
        signed_v1.encode(mavlink.MAVLink_mission_item_reached_message(1))
    signed_v2 = FrameEncoder(1, 1, signing=KEY, wall_clock=lambda: FIXED_WALL)
    with pytest.raises(ValueError, match="signed"):
        signed_v2.encode(mavlink.MAVLink_mission_item_reached_message(1), version=1)


def test_v1_mission_count_without_extensions_defaults_them_to_zero() -> None:
    # A MAVLink 1 sender knows only the base fields: 4-byte payload (count, target sys, comp).
    payload = struct.pack("<HBB", 12, 1, 190)
    header = bytes([MAGIC_V1, len(payload), 9, 255, 190, 44])
    crc = mcrf4xx(header[1:] + payload + bytes([crc_extra_from_xml("MISSION_COUNT")]))
    frame_bytes = header + payload + struct.pack("<H", crc)
    dec = FrameDecoder()
    [frame] = dec.feed(frame_bytes)
    assert isinstance(frame, Frame), frame
    assert (frame.version, frame.msgid, frame.seq, frame.source) == (1, 44, 9, (255, 190))
    m = frame.msg
    assert (m.count, m.target_system, m.target_component) == (12, 1, 190)
    assert (m.mission_type, m.opaque_id) == (0, 0)
    assert frame.raw == frame_bytes


# --- the bytes, rebuilt independently from the spec --------------------------------------------

_TYPES = {  # MAVLink type -> (size, struct code)
    "char": (1, "s"), "int8_t": (1, "b"), "uint8_t": (1, "B"), "int16_t": (2, "h"),
    "uint16_t": (2, "H"), "int32_t": (4, "i"), "uint32_t": (4, "I"), "float": (4, "f"),
    "int64_t": (8, "q"), "uint64_t": (8, "Q"), "double": (8, "d"),
}


def mcrf4xx(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/MCRF4XX: reflected poly 0x1021 (0x8408), init 0xFFFF, no final xor; bitwise."""
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x8408 if crc & 1 else crc >> 1
    return crc


def xml_layout(name: str) -> tuple[int, list[tuple[str, str, int]], list[tuple[str, str, int]]]:
    """(id, base fields in wire order, extension fields in XML order); field = (name, type, array)."""
    root = ET.parse(XML_PATH).getroot()
    [node] = [m for m in root.iter("message") if m.get("name") == name]
    base: list[tuple[str, str, int]] = []
    ext: list[tuple[str, str, int]] = []
    target = base
    for child in node:
        if child.tag == "extensions":
            target = ext
        elif child.tag == "field":
            ftype = child.get("type", "")
            array = 0
            if "[" in ftype:
                ftype, _, rest = ftype.partition("[")
                array = int(rest.rstrip("]"))
            if ftype == "uint8_t_mavlink_version":
                ftype = "uint8_t"
            target.append((child.get("name", ""), ftype, array))
    # Base fields are sent largest type first; the sort is stable. Extensions are not sorted.
    base.sort(key=lambda f: -_TYPES[f[1]][0])
    return int(node.get("id", "-1")), base, ext


def crc_extra_from_xml(name: str) -> int:
    _, base, _ = xml_layout(name)
    text = name.encode() + b" "
    crc = mcrf4xx(text)
    for fname, ftype, array in base:
        crc = mcrf4xx(f"{ftype} {fname} ".encode(), crc)
        if array:
            crc = mcrf4xx(bytes([array]), crc)
    return (crc & 0xFF) ^ (crc >> 8)


def payload_from_xml(name: str, values: dict[str, Any]) -> bytes:
    _, base, ext = xml_layout(name)
    out = b""
    for fname, ftype, array in base + ext:
        size, code = _TYPES[ftype]
        value = values[fname]
        if ftype == "char":
            out += struct.pack(f"<{array}s", value)
        elif array:
            out += struct.pack(f"<{array}{code}", *value)
        else:
            out += struct.pack(f"<{code}", value)
    return out


def v2_frame_by_hand(name: str, values: dict[str, Any], seq: int, sysid: int, compid: int) -> bytes:
    msgid, _, _ = xml_layout(name)
    payload = payload_from_xml(name, values)
    while len(payload) > 1 and payload[-1] == 0:  # MAVLink 2 zero truncation; byte 0 always stays
        payload = payload[:-1]
    header = struct.pack("<BBBBBBB", MAGIC_V2, len(payload), 0, 0, seq, sysid, compid)
    header += msgid.to_bytes(3, "little")
    crc = mcrf4xx(header[1:] + payload + bytes([crc_extra_from_xml(name)]))
    return header + payload + struct.pack("<H", crc)


def test_crc_implementation_check_value() -> None:
    assert mcrf4xx(b"123456789") == 0x6F91  # the catalogued check value of CRC-16/MCRF4XX


# CRC_EXTRA values as published by upstream MAVLink (common.xml / minimal.xml).
UPSTREAM_CRC_EXTRA = {
    "HEARTBEAT": 50, "MISSION_ITEM": 254, "MISSION_REQUEST": 230, "MISSION_CURRENT": 28,
    "MISSION_REQUEST_LIST": 132, "MISSION_COUNT": 221, "MISSION_CLEAR_ALL": 232,
    "MISSION_ITEM_REACHED": 11, "MISSION_ACK": 153, "MISSION_REQUEST_INT": 196,
    "MISSION_ITEM_INT": 38, "COMMAND_INT": 158, "COMMAND_LONG": 152, "COMMAND_ACK": 143,
    "STATUSTEXT": 83, "SETUP_SIGNING": 71,
}


@pytest.mark.parametrize("name", sorted(UPSTREAM_CRC_EXTRA))
def test_crc_extra_from_xml_matches_upstream_and_dialect(name: str) -> None:
    assert crc_extra_from_xml(name) == UPSTREAM_CRC_EXTRA[name]
    msgid = xml_layout(name)[0]
    assert mavlink.mavlink_map[msgid].crc_extra == UPSTREAM_CRC_EXTRA[name]


HAND_BUILT = [
    ("MISSION_ITEM_INT", dict(target_system=1, target_component=190, seq=513, frame=6, command=16,
                              current=0, autocontinue=0, param1=0.5, param2=2.0, param3=0.0,
                              param4=-1.25, x=473_977_420, y=-85_455_940, z=15.5, mission_type=0)),
    ("MISSION_ITEM_INT", dict(target_system=1, target_component=1, seq=0, frame=3, command=22,
                              current=1, autocontinue=1, param1=0.0, param2=0.0, param3=0.0,
                              param4=0.0, x=1, y=2, z=30.0, mission_type=2)),
    ("MISSION_COUNT", dict(target_system=1, target_component=1, count=300, mission_type=1,
                           opaque_id=0x1234)),
    ("MISSION_ACK", dict(target_system=255, target_component=190, type=0, mission_type=0,
                         opaque_id=0)),
    ("MISSION_ITEM_REACHED", dict(seq=0)),  # all-zero payload: truncated to its first byte
    ("STATUSTEXT", dict(severity=6, text=b"mission accepted", id=0, chunk_seq=0)),
    ("HEARTBEAT", dict(type=2, autopilot=12, base_mode=81, custom_mode=65536 * 4,
                       system_status=4, mavlink_version=3)),
]


@pytest.mark.parametrize("name, values", HAND_BUILT, ids=[f"{n}-{i}" for i, (n, _) in enumerate(HAND_BUILT)])
def test_encoder_output_equals_frame_built_from_spec(name: str, values: dict[str, Any]) -> None:
    msgid = xml_layout(name)[0]
    msg = mavlink.mavlink_map[msgid](**values)
    enc = FrameEncoder(17, 42)
    for seq in range(3):  # a few sequence numbers, so seq lands in the right header byte
        assert enc.encode(msg) == v2_frame_by_hand(name, values, seq, 17, 42)


def test_truncation_facts_of_hand_built_frames() -> None:
    # STATUSTEXT: 51 payload bytes declared, only the text survives truncation.
    frame = v2_frame_by_hand("STATUSTEXT", dict(severity=6, text=b"hi", id=0, chunk_seq=0), 0, 1, 1)
    assert frame[1] == 3
    # a message whose payload is all zero keeps exactly one byte
    assert v2_frame_by_hand("MISSION_ITEM_REACHED", dict(seq=0), 0, 1, 1)[1] == 1
