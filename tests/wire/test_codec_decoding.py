"""The frame decoder on datagrams: several frames in one, garbage, truncation, bad CRCs, unknown
ids and flags; and properties: feed never raises, every single-byte corruption is caught."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pymavlink.dialects.v20 import common as bundled

from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder, frames_only
from mavconform.reference_impl.wire.dialect import mavlink
from mavconform.reference_impl.wire.frame import DecodeError, Frame

from .codec_samples import FIXED_WALL, KEY, encoded, mission_item_int, sample_messages


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


# --- an unsigned frame no key checks skips the signing steps ----------------------------------

def _outcome(dec: FrameDecoder, item: Frame | DecodeError) -> tuple:
    if isinstance(item, DecodeError):
        return ("error", item.reason, item.raw, dec.frames, dec.errors)
    return ("frame", item.msg.get_type(), item.msg.to_dict(), item.raw, item.src_system, item.src_component,
            item.signature, item.link_id, item.fault, dec.frames, dec.errors)


@given(st.sampled_from([f for f in _VALID_FRAMES if f[0] == 0xFE or f[2] == 0]), st.data())
def test_an_unsigned_frame_decodes_alike_with_no_key_and_through_the_signing_steps(frame: bytes,
                                                                                  data: st.DataObject) -> None:
    """With no key (or only a keyring), an unsigned frame goes straight to pymavlink, without
    the signing context and verdict; a decoder with a key takes it through them. For any bytes
    after the header's first three (a bad msgid, checksum, payload...), MAVLink 1 or 2, the
    outcome and the counters are the same."""
    index = data.draw(st.integers(3, len(frame) - 1))
    value = data.draw(st.integers(0, 255))
    mutated = frame[:index] + bytes([value]) + frame[index + 1:]
    plain, keyed = FrameDecoder(), FrameDecoder(signing=KEY, wall_clock=lambda: FIXED_WALL)
    (got,) = plain.feed(mutated)
    (want,) = keyed.feed(mutated)
    assert _outcome(plain, got) == _outcome(keyed, want)
