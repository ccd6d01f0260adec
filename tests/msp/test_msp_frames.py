"""The MSP codec and stream parser (reference_impl/msp): every frame it writes it reads back,
however the stream is cut, with garbage between frames, and bad bytes never raise.

Known bytes: seed 004 ch. 1.3 ("for a request message the checksum is equal to the type")
and CRC-8/DVB-S2's published check value (0xBC for "123456789").
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mavconform.reference_impl.msp.commands import COMMANDS, FLAG_LAST, Waypoint, WaypointInfo
from mavconform.reference_impl.msp.frame import FROM_FC, MspFrame, Version, crc8_dvb_s2, encode
from mavconform.reference_impl.msp.parser import MspParser


@st.composite
def frames(draw) -> MspFrame:
    version = draw(st.sampled_from(list(Version)))
    top = 254 if version is Version.V1 else 0xFFFF
    return MspFrame(draw(st.integers(0, top)), draw(st.binary(max_size=600)),
                    draw(st.sampled_from(["<", ">", "!"])), version,
                    draw(st.integers(0, 255)) if version is not Version.V1 else 0)


def _feed_in_pieces(parser: MspParser, data: bytes, cuts: list[int]) -> list[MspFrame]:
    out, at = [], 0
    for cut in sorted(c % (len(data) + 1) for c in cuts) + [len(data)]:
        out += parser.feed(data[at:cut])
        at = max(at, cut)
    return out


@settings(max_examples=300)
@given(st.lists(frames(), min_size=1, max_size=6), st.lists(st.binary(max_size=40).filter(lambda b: b"$" not in b),
                                                         min_size=7, max_size=7), st.lists(st.integers(0, 10_000)))
def test_frames_come_back_whole_through_garbage_and_any_cut(sent, garbage, cuts):
    data = b"".join(g + encode(f) for g, f in zip(garbage, sent)) + garbage[-1]
    parser = MspParser()
    assert _feed_in_pieces(parser, data, cuts) == sent
    assert parser.stats.frames == len(sent) and parser.stats.problems() == 0
    assert parser.stats.garbage_bytes == sum(len(g) for g in garbage[:len(sent)]) + len(garbage[-1])


@settings(max_examples=300)
@given(st.binary(max_size=2000), st.lists(st.integers(0, 10_000)))
def test_any_bytes_never_raise_and_every_byte_is_accounted(noise, cuts):
    parser = MspParser()
    got = _feed_in_pieces(parser, noise, cuts)
    parser.close()
    assert parser.pending == 0
    assert all(isinstance(f, MspFrame) for f in got)


@given(frames(), st.integers(0, 10_000), st.integers(1, 255))
def test_a_damaged_byte_loses_that_frame_only(frame, where, xor):
    wire = bytearray(encode(frame))
    at = 3 + where % (len(wire) - 3)           # past `$`, the version and the direction
    wire[at] ^= xor
    after = MspFrame(20)                         # MSP_WP_GETINFO, a request
    parser = MspParser()
    got = parser.feed(bytes(wire) + encode(after))
    parser.close()
    assert got[-1:] == [after] or parser.stats.truncated   # a grown size may still wait for bytes
    assert frame not in got[:-1] or bytes(wire) == encode(frame)


def test_known_bytes():
    assert encode(MspFrame(COMMANDS["MSP_WP_GETINFO"].code)) == b"$M<\x00\x14\x14"   # checksum = type
    assert crc8_dvb_s2(b"123456789") == 0xBC
    assert encode(MspFrame(20, version=Version.V2)) == bytes.fromhex("24583c00140000006f")
    big = encode(MspFrame(118, bytes(300), ">", Version.V1))
    assert big[3] == 255 and big[4] == 118 and big[5:7] == (300).to_bytes(2, "little")   # jumbo


def test_truncated_oversize_and_bad_checksum_are_counted():
    parser = MspParser(max_payload=100)
    good = encode(MspFrame(118, b"\x01"))
    assert parser.feed(good[:-2]) == [] and parser.pending == len(good) - 2
    parser.close()
    assert parser.stats.truncated == 1 and parser.pending == 0
    assert parser.feed(encode(MspFrame(209, bytes(200), version=Version.V2)) + good) == [MspFrame(118, b"\x01")]
    assert parser.stats.oversize == 1
    bad = bytearray(good)
    bad[-1] ^= 1
    assert parser.feed(bytes(bad)) == [] and parser.stats.bad_checksum == 1
    assert "XOR" in parser.stats.last_error


def test_directions_not_read_are_skipped():
    parser = MspParser(accept="<")
    assert parser.feed(encode(MspFrame(20, direction=">")) + encode(MspFrame(20))) == [MspFrame(20)]
    assert parser.stats.bad_header == 1


def test_waypoint_records_are_21_bytes_and_round_trip():
    w = Waypoint(1, 1, 473977419, -85455938, -500, -1, 32767, -32768, FLAG_LAST)
    assert len(w.pack()) == 21 == COMMANDS["MSP_SET_WP"].request_size == COMMANDS["MSP_WP"].reply_size
    assert Waypoint.unpack(w.pack()) == w
    info = WaypointInfo(0, 120, True, 3)
    assert WaypointInfo.unpack(info.pack()) == info
    with pytest.raises(ValueError, match="21 bytes"):
        Waypoint.unpack(bytes(20))


@pytest.mark.parametrize("bad", [dict(command=256), dict(command=255), dict(direction="?"),
                                 dict(flag=300, version=Version.V2), dict(command=70000, version=Version.V2)])
def test_a_frame_that_cannot_be_sent_is_refused_when_built(bad):
    with pytest.raises(ValueError):
        MspFrame(**{"command": 1, **bad})


def test_a_false_frame_start_does_not_hold_back_the_frames_behind_it():
    """Noise that reads as `$M>` with a size of 5 would wait for 6 more bytes and swallow the
    reply behind it (INAV's own parser would); a later whole frame wins instead."""
    reply = encode(MspFrame(209, b"", FROM_FC))              # MSP_SET_WP's empty `>`: 6 bytes
    parser = MspParser()
    assert parser.feed(b"\x00$M>\x05" + reply) == [MspFrame(209, b"", FROM_FC)]
    assert parser.stats.bad_header == 1 and parser.pending == 0
    split = MspParser()                                       # a frame merely split is still waited for
    whole = encode(MspFrame(118, bytes(range(21)), FROM_FC))
    assert split.feed(whole[:10]) == [] and split.feed(whole[10:]) == [MspFrame(118, bytes(range(21)), FROM_FC)]
    assert split.stats.problems() == 0
