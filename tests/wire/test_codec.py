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
from hypothesis import given
from hypothesis import strategies as st
from pymavlink.dialects.v20 import common as bundled

from mavconform.reference_impl.wire.codec import (
    MAGIC_V1,
    MAGIC_V2,
    FrameDecoder,
    FrameEncoder,
    frames_only,
)
from mavconform.reference_impl.wire.dialect import XML_PATH, mavlink
from mavconform.reference_impl.wire.frame import DecodeError, Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import SigningKey

FIXED_WALL = 1_700_000_000.0
KEY = SigningKey(bytes(range(32)), link_id=7)


# --- sample messages ---------------------------------------------------------------------------

def mission_item_int(seq: int = 3, mission_type: int = 0) -> Any:
    return mavlink.MAVLink_mission_item_int_message(
        target_system=1, target_component=1, seq=seq, frame=6, command=16, current=0,
        autocontinue=1, param1=0.5, param2=2.0, param3=0.0, param4=-1.25,
        x=473_977_420, y=85_455_940, z=15.5, mission_type=mission_type)


def sample_messages() -> list[Any]:
    return [
        mission_item_int(),
        mission_item_int(seq=1000, mission_type=2),
        mavlink.MAVLink_mission_count_message(1, 1, 12, mission_type=1, opaque_id=0xDEADBEEF),
        mavlink.MAVLink_mission_request_int_message(255, 190, 7, mission_type=2),
        mavlink.MAVLink_mission_ack_message(255, 190, 0, mission_type=0, opaque_id=42),
        mavlink.MAVLink_mission_current_message(4, total=9, mission_state=3, mission_mode=1,
                                                mission_id=11, fence_id=0, rally_points_id=13),
        mavlink.MAVLink_mission_clear_all_message(1, 1, mission_type=255),
        mavlink.MAVLink_mission_item_reached_message(0),
        mavlink.MAVLink_command_long_message(1, 1, 400, 0, 1.0, 0, 0, 0, 0, 0, 0),
        mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3),
    ]


def v1_capable(msgs: list[Any]) -> list[Any]:
    return [m for m in msgs if m.id <= 255]


def fields_of(msg: Any) -> dict[str, Any]:
    return {name: getattr(msg, name) for name in msg.get_fieldnames()}


def encoded(msg: Any, **kw: Any) -> bytes:
    return FrameEncoder(1, 1, **kw).encode(msg)


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


# --- datagram splitting and errors -------------------------------------------------------------

def three_frames() -> list[bytes]:
    enc = FrameEncoder(1, 1)
    return [enc.encode(m) for m in sample_messages()[:3]]


def test_several_frames_in_one_datagram_decode_in_order() -> None:
    enc = FrameEncoder(3, 4)
    msgs = sample_messages()
    datagram = b"".join(enc.encode(m) for m in msgs)
    dec = FrameDecoder()
    out = dec.feed(datagram)
    assert all(isinstance(f, Frame) for f in out)
    assert [f.msgid for f in out] == [m.id for m in msgs]
    assert [f.seq for f in out] == list(range(len(msgs)))
    assert b"".join(f.raw for f in out) == datagram
    assert (dec.frames, dec.errors) == (len(msgs), 0)


def test_mixed_v1_and_v2_frames_in_one_datagram() -> None:
    msg = mavlink.MAVLink_mission_request_int_message(1, 1, 5, mission_type=0)
    v1 = FrameEncoder(1, 1, version=1).encode(msg)
    v2 = FrameEncoder(2, 1).encode(msg)
    out = FrameDecoder().feed(v1 + v2 + v1)
    assert [(f.version, f.src_system) for f in out] == [(1, 1), (2, 2), (1, 1)]


def test_empty_datagram() -> None:
    dec = FrameDecoder()
    assert dec.feed(b"") == []
    assert (dec.frames, dec.errors) == (0, 0)


GARBAGE = b"\x00\x11garbage\x7f"  # contains neither magic byte


def test_garbage_before_between_and_after_frames() -> None:
    a, b, c = three_frames()
    dec = FrameDecoder()
    out = dec.feed(GARBAGE + a + b"\x01\x02" + b + c + b"\xff\x00")
    kinds = [type(x).__name__ for x in out]
    assert kinds == ["DecodeError", "Frame", "DecodeError", "Frame", "Frame", "DecodeError"]
    errors = [x for x in out if isinstance(x, DecodeError)]
    assert all("outside any frame" in e.reason for e in errors)
    assert [e.raw for e in errors] == [GARBAGE, b"\x01\x02", b"\xff\x00"]
    assert [f.raw for f in frames_only(out)] == [a, b, c]
    assert (dec.frames, dec.errors) == (3, 3)
    assert str(errors[0]).endswith(f"({len(GARBAGE)} bytes)")


def test_only_garbage_is_one_error() -> None:
    dec = FrameDecoder()
    [err] = dec.feed(GARBAGE * 5)
    assert isinstance(err, DecodeError) and "outside any frame" in err.reason
    assert err.raw == GARBAGE * 5
    assert (dec.frames, dec.errors) == (0, 1)


@pytest.mark.parametrize("cut", [1, 2, 3, 10, -1])
def test_truncated_frame(cut: int) -> None:
    a, b, _ = three_frames()
    dec = FrameDecoder()
    out = dec.feed(a + b[:cut])
    assert isinstance(out[0], Frame) and out[0].raw == a
    assert len(out) == 2
    assert isinstance(out[1], DecodeError) and "truncated" in out[1].reason
    assert out[1].raw == b[:cut]
    assert (dec.frames, dec.errors) == (1, 1)


def test_bad_crc_is_an_error_and_following_frames_still_decode() -> None:
    a, b, c = three_frames()
    bad = bytearray(b)
    bad[12] ^= 0x40  # a payload byte
    dec = FrameDecoder()
    out = dec.feed(a + bytes(bad) + c)
    assert isinstance(out[0], Frame) and isinstance(out[2], Frame)
    assert isinstance(out[1], DecodeError) and "CRC" in out[1].reason
    assert out[1].raw == bytes(bad)
    assert (dec.frames, dec.errors) == (2, 1)


def test_bad_crc_bytes() -> None:
    a = three_frames()[0]
    bad = a[:-1] + bytes([a[-1] ^ 1])
    [err] = FrameDecoder().feed(bad)
    assert isinstance(err, DecodeError) and "CRC" in err.reason


def test_bad_length_byte() -> None:
    a = three_frames()[0]
    dec = FrameDecoder()
    # longer than the datagram: the frame is truncated
    longer = a[:1] + bytes([a[1] + 5]) + a[2:]
    [err] = dec.feed(longer)
    assert isinstance(err, DecodeError) and "truncated" in err.reason
    # shorter: the claimed frame fails its CRC; no frame comes out, nothing raises
    shorter = a[:1] + bytes([a[1] - 2]) + a[2:]
    out = dec.feed(shorter)
    assert out and not frames_only(out)
    assert isinstance(out[0], DecodeError) and "CRC" in out[0].reason
    assert dec.frames == 0 and dec.errors == 1 + len(out)
    # the decoder is not left in a bad state: the next datagram decodes
    assert isinstance(dec.feed(a)[0], Frame)


def test_unknown_message_id_is_an_error() -> None:
    assert 30 not in mavlink.mavlink_map  # our dialect does not carry ATTITUDE
    other = bundled.MAVLink(None, 9, 1)
    attitude = bytes(bundled.MAVLink_attitude_message(1000, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0).pack(other))
    ok = three_frames()[0]
    dec = FrameDecoder()
    out = dec.feed(ok + attitude + ok)
    assert isinstance(out[0], Frame) and isinstance(out[2], Frame)
    err = out[1]
    assert isinstance(err, DecodeError)
    assert err.reason == "unknown message id 30"
    assert err.raw == attitude
    assert (dec.frames, dec.errors) == (2, 1)


def test_unknown_message_id_v1_names_the_id() -> None:
    other = bundled.MAVLink(None, 9, 1)
    attitude = bytes(bundled.MAVLink_attitude_message(1, 0, 0, 0, 0, 0, 0).pack(other, force_mavlink1=True))
    [err] = FrameDecoder().feed(attitude)
    assert isinstance(err, DecodeError) and err.reason == "unknown message id 30"


@pytest.mark.parametrize("flags", [0x02, 0x04, 0x80, 0x03])
def test_unknown_incompat_flag_is_an_error(flags: int) -> None:
    a = three_frames()[0]
    if flags & 0x01:  # keep the framing consistent: a "signed" frame carries 13 more bytes
        a = a + bytes(13)
    bad = a[:2] + bytes([flags]) + a[3:]
    ok = three_frames()[1]
    dec = FrameDecoder()
    out = dec.feed(bad + ok)
    assert isinstance(out[0], DecodeError)
    assert out[0].reason == f"unknown incompat_flags 0x{flags:02x}"
    assert out[0].raw == bad
    assert isinstance(out[1], Frame) and out[1].raw == ok
    assert (dec.frames, dec.errors) == (1, 1)


def test_unknown_compat_flag_is_ignored_per_spec_but_covered_by_crc() -> None:
    # compat_flags may be ignored, but they are part of the CRC: flipping one alone breaks it.
    a = three_frames()[0]
    [err] = FrameDecoder().feed(a[:3] + b"\x01" + a[4:])
    assert isinstance(err, DecodeError) and "CRC" in err.reason


# --- properties: feed never raises -------------------------------------------------------------

def _check_output(dec: FrameDecoder, out: list[Frame | DecodeError], frames0: int, errors0: int) -> None:
    assert all(isinstance(x, (Frame, DecodeError)) for x in out)
    assert dec.frames - frames0 == sum(isinstance(x, Frame) for x in out)
    assert dec.errors - errors0 == sum(isinstance(x, DecodeError) for x in out)


@given(st.binary(max_size=600))
def test_random_bytes_never_raise(data: bytes) -> None:
    for dec in (FrameDecoder(), FrameDecoder(signing=KEY, wall_clock=lambda: FIXED_WALL)):
        out = dec.feed(data)
        _check_output(dec, out, 0, 0)
        # everything in the datagram is accounted for, in order
        assert b"".join(x.raw for x in out) == data


@given(st.lists(st.sampled_from([b"\xfd", b"\xfe", b"\x00", b"\x01", b"\xff", b"\x0d"]), max_size=80))
def test_magic_heavy_bytes_never_raise(parts: list[bytes]) -> None:
    data = b"".join(parts)
    dec = FrameDecoder()
    _check_output(dec, dec.feed(data), 0, 0)


_VALID_FRAMES = [
    encoded(mission_item_int()),
    encoded(mission_item_int(), version=1),
    encoded(mavlink.MAVLink_mission_count_message(1, 1, 3, 0, 0)),
    encoded(mission_item_int(), signing=KEY, wall_clock=lambda: FIXED_WALL),
]


@given(st.sampled_from(_VALID_FRAMES), st.data())
def test_single_byte_mutations_never_raise(frame: bytes, data: st.DataObject) -> None:
    index = data.draw(st.integers(0, len(frame) - 1))
    value = data.draw(st.integers(0, 255).filter(lambda v: v != frame[index]))
    mutated = frame[:index] + bytes([value]) + frame[index + 1:]
    for dec in (FrameDecoder(), FrameDecoder(signing=KEY, wall_clock=lambda: FIXED_WALL)):
        out = dec.feed(mutated + frame)
        _check_output(dec, out, 0, 0)
        assert b"".join(x.raw for x in out) == mutated + frame


@pytest.mark.parametrize("frame", _VALID_FRAMES[:3], ids=["v2", "v1", "v2-short"])
def test_every_single_byte_mutation_after_the_length_byte_is_detected(frame: bytes) -> None:
    """Exhaustive: CRC-16 catches any one corrupted byte in header, payload or CRC."""
    dec = FrameDecoder()
    for index in range(2, len(frame)):
        for value in range(256):
            if value == frame[index]:
                continue
            out = dec.feed(frame[:index] + bytes([value]) + frame[index + 1:])
            assert not frames_only(out), (index, value)
    assert dec.frames == 0


def test_mavlink1_frames_carry_only_base_fields():
    """Extensions are a MAVLink 2 feature: a v1 MISSION_COUNT has the 4 base payload bytes,
    and a decoder of the older dialect (pymavlink's bundled common.xml) reads it."""
    from pymavlink.dialects.v20 import common as bundled

    from mavconform.reference_impl.wire.codec import base_payload_length

    raw = FrameEncoder(1, 1, version=1).encode(mavlink.MAVLink_mission_count_message(1, 1, 5, 2, 77))
    assert raw[0] == 0xFE and raw[1] == 4 == base_payload_length(mavlink.MAVLink_mission_count_message)
    (frame,) = FrameDecoder().feed(raw)
    assert (frame.msg.count, frame.msg.mission_type, frame.msg.opaque_id) == (5, 0, 0)
    (old,) = FrameDecoder(dialect=bundled).feed(raw)
    assert old.msg.count == 5
    d = mavlink
    for cls, base in ((d.MAVLink_mission_item_int_message, 37), (d.MAVLink_mission_current_message, 2),
                      (d.MAVLink_mission_ack_message, 3), (d.MAVLink_heartbeat_message, 9)):
        assert base_payload_length(cls) == base


def test_a_statustext_whose_chunk_id_is_over_255_still_goes_out_as_mavlink_1() -> None:
    """STATUSTEXT has a field called `id` that shadows the message id on the instance: the
    MAVLink 1 check must read the message's id (253), not the chunk id."""
    from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder
    from mavconform.reference_impl.wire.dialect import mavlink as d
    data = FrameEncoder(1, 1).encode(d.MAVLink_statustext_message(6, b"hello", 300, 0), version=1)
    (frame,) = [f for f in FrameDecoder().feed(data) if getattr(f, "msg", None) is not None]
    assert data[0] == 0xFE and frame.msg.get_type() == "STATUSTEXT" and frame.msg.text == "hello"
