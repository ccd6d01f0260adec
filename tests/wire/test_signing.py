"""MAVLink 2 signing through the codec: signature bytes, timestamps, verdicts, replay rules.

Signature facts (seed 001): incompat flag 0x01; a 13-byte block of link id, 48-bit timestamp
in 10 us units since 2015-01-01, and the first 6 bytes of
SHA-256(secret_key + header + payload + CRC + link id + timestamp). Time is injected, never
read from the machine.
"""

from __future__ import annotations

from datetime import datetime, timezone

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.wire.codec import IFLAG_SIGNED, SIGNATURE_LEN, FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.frame import DecodeError, SignatureFault
from mavconform.reference_impl.wire.signing import SIGNING_EPOCH_UNIX, SigningKey, signing_timestamp

from .signing_rig import (INVALID, KEY, OTHER_KEY, SECRET, T0, UNCHECKED, UNSIGNED, VALID, Clock, decode_one,
                          expected_signature, far_future_forgery, item, sig_timestamp, signer)


# --- signing parameters ------------------------------------------------------------------------

def test_signing_epoch_is_2015_utc() -> None:
    assert SIGNING_EPOCH_UNIX == datetime(2015, 1, 1, tzinfo=timezone.utc).timestamp()


@pytest.mark.parametrize("unix, expected", [
    (SIGNING_EPOCH_UNIX, 0),
    (SIGNING_EPOCH_UNIX + 1, 100_000),
    (SIGNING_EPOCH_UNIX + 0.5, 50_000),
    (SIGNING_EPOCH_UNIX - 10, 0),  # before the epoch: clamped, never negative
    (T0, 27_992_960_000_000),
])
def test_signing_timestamp_units(unix: float, expected: int) -> None:
    assert signing_timestamp(unix) == expected


def test_signing_key_validation() -> None:
    assert SigningKey(bytes(32)).link_id == 0
    assert SigningKey(bytes(32), link_id=255).link_id == 255
    for bad_len in (0, 16, 31, 33, 64):
        with pytest.raises(ValueError, match="32 bytes"):
            SigningKey(bytes(bad_len))
    for bad_link in (-1, 256, 1000):
        with pytest.raises(ValueError, match="link id"):
            SigningKey(bytes(32), link_id=bad_link)


# --- signed round trip -------------------------------------------------------------------------

def test_signed_round_trip() -> None:
    signed = signer().encode(item())
    unsigned = FrameEncoder(1, 1).encode(item())
    assert len(signed) == len(unsigned) + SIGNATURE_LEN == len(unsigned) + 13
    assert signed[2] == IFLAG_SIGNED == 0x01
    assert signed[-13] == KEY.link_id
    assert signed[-6:] == expected_signature(SECRET, signed)
    # apart from the flag byte and the CRC it covers, the unsigned frame is the signed one's prefix
    assert signed[3:len(unsigned) - 2] == unsigned[3:-2]

    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    assert dec.signing_enabled
    frame = decode_one(dec, signed)
    assert frame.signature is VALID
    assert frame.link_id == 7
    assert frame.incompat_flags == 0x01
    assert frame.raw == signed
    assert frame.msg.x == 473_977_420 and frame.msg.z == 12.5
    assert (dec.frames, dec.errors, dec.bad_signatures) == (1, 0, 0)


def test_signature_covers_link_id_and_timestamp() -> None:
    """The whole 13-byte block is checked: changing any byte of it makes the frame INVALID."""
    signed = signer().encode(item())
    for offset in range(1, SIGNATURE_LEN + 1):
        tampered = bytearray(signed)
        tampered[-offset] ^= 0x01
        dec = FrameDecoder(signing=KEY, wall_clock=Clock())
        frame = decode_one(dec, bytes(tampered))
        assert frame.signature is INVALID, offset
        assert dec.bad_signatures == 1


def test_encoder_can_turn_signing_off_and_on() -> None:
    enc = signer()
    assert enc.encode(item())[2] == 0x01
    enc.set_signing(None)
    assert enc.encode(item())[2] == 0x00
    enc.set_signing(SigningKey(SECRET, link_id=9))
    assert enc.encode(item())[-13] == 9


# --- timestamps --------------------------------------------------------------------------------

def test_timestamp_is_the_wall_clock_in_10us_units_since_2015() -> None:
    raw = signer(T0).encode(item())
    assert sig_timestamp(raw) == signing_timestamp(T0)
    assert sig_timestamp(raw) == round((T0 - datetime(2015, 1, 1, tzinfo=timezone.utc).timestamp()) * 100_000)


def test_timestamp_strictly_increases_within_one_tick() -> None:
    clock = Clock()
    enc = FrameEncoder(1, 1, signing=KEY, wall_clock=clock)
    dec = FrameDecoder(signing=KEY, wall_clock=clock)
    frames = [enc.encode(item(i)) for i in range(20)]  # all at the same instant
    stamps = [sig_timestamp(f) for f in frames]
    assert stamps[0] == signing_timestamp(T0)
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    assert all(decode_one(dec, f).signature is VALID for f in frames)
    # once the wall clock has moved past the counter, the wall clock wins again
    clock.t = T0 + 1
    assert sig_timestamp(enc.encode(item())) == signing_timestamp(T0 + 1)
    # a wall clock that steps backwards never makes the timestamp go backwards
    last = signing_timestamp(T0 + 1)
    clock.t = T0 - 100
    later = enc.encode(item())
    assert sig_timestamp(later) > last
    assert decode_one(dec, later).signature is VALID


@given(st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=1, max_size=40))
def test_any_clock_walk_gives_increasing_valid_stream(steps: list[float]) -> None:
    clock = Clock()
    enc = FrameEncoder(1, 1, signing=KEY, wall_clock=clock)
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0 + 10))
    last = -1
    for step in steps:
        clock.t += step
        raw = enc.encode(item())
        assert sig_timestamp(raw) > last
        last = sig_timestamp(raw)
        assert decode_one(dec, raw).signature is VALID
    assert dec.bad_signatures == 0


# --- verdicts ----------------------------------------------------------------------------------

def test_wrong_key_is_invalid_but_the_message_is_decoded() -> None:
    raw = signer(key=OTHER_KEY).encode(item(5))
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    frame = decode_one(dec, raw)
    assert frame.signature is INVALID
    assert frame.msg.seq == 5 and frame.name == "MISSION_ITEM_INT"
    assert frame.link_id == 7
    assert (dec.frames, dec.errors, dec.bad_signatures) == (1, 0, 1)


@pytest.mark.parametrize("version", [1, 2])
def test_unsigned_frame_to_keyed_decoder_is_unsigned(version: int) -> None:
    raw = FrameEncoder(1, 1, version=version).encode(item())
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    frame = decode_one(dec, raw)
    assert frame.signature is UNSIGNED and frame.link_id is None
    assert dec.bad_signatures == 0


def test_signed_frame_to_keyless_decoder_is_unchecked() -> None:
    dec = FrameDecoder()
    assert not dec.signing_enabled
    for key in (KEY, OTHER_KEY):
        frame = decode_one(dec, signer(key=key).encode(item()))
        assert frame.signature is UNCHECKED
        assert frame.link_id == 7 and frame.incompat_flags == 0x01
    assert dec.bad_signatures == 0


def test_decoder_can_drop_its_key() -> None:
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    raw = signer().encode(item())
    assert decode_one(dec, raw).signature is VALID
    dec.set_signing(None)
    assert not dec.signing_enabled
    assert decode_one(dec, raw).signature is UNCHECKED


def test_tampered_signature_byte_is_invalid() -> None:
    raw = bytearray(signer().encode(item()))
    raw[-1] ^= 0xFF
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    assert decode_one(dec, bytes(raw)).signature is INVALID
    assert dec.bad_signatures == 1


def test_tampered_payload_of_signed_frame_is_a_crc_error_not_a_verdict() -> None:
    raw = bytearray(signer().encode(item()))
    raw[12] ^= 0x10
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    [err] = dec.feed(bytes(raw))
    assert isinstance(err, DecodeError) and "CRC" in err.reason
    assert (dec.frames, dec.errors, dec.bad_signatures) == (0, 1, 0)


# --- replay and stale streams ------------------------------------------------------------------

def test_replay_of_the_same_frame_is_invalid() -> None:
    enc = signer()
    first = enc.encode(item(0))
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    assert decode_one(dec, first).signature is VALID
    assert decode_one(dec, first).signature is INVALID  # equal timestamp
    assert decode_one(dec, enc.encode(item(1))).signature is VALID  # the sender is unharmed
    assert dec.bad_signatures == 1


def test_replay_of_an_older_frame_is_invalid() -> None:
    clock = Clock()
    enc = FrameEncoder(1, 1, signing=KEY, wall_clock=clock)
    old = enc.encode(item(0))
    clock.t += 5
    new = enc.encode(item(1))
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0 + 5))
    assert decode_one(dec, new).signature is VALID
    assert decode_one(dec, old).signature is INVALID
    assert dec.bad_signatures == 1


def test_stale_new_stream_is_invalid() -> None:
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    stale = signer(T0 - 61, system=2).encode(item())
    assert decode_one(dec, stale).signature is INVALID
    # within the minute a new stream is accepted
    recent = signer(T0 - 59, system=3).encode(item())
    assert decode_one(dec, recent).signature is VALID
    assert dec.bad_signatures == 1
    # the stale stream was not recorded: once the decoder is not ahead, the same sender is fine
    late_dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0 - 61))
    assert decode_one(late_dec, stale).signature is VALID


def test_genuine_frame_ahead_of_decoder_clock_is_valid() -> None:
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    assert decode_one(dec, signer(T0 + 3600).encode(item())).signature is VALID


# --- forged frames must not lock out the genuine sender ----------------------------------------



def test_forged_future_frame_on_a_new_stream_does_not_lock_out_the_sender() -> None:
    forged = far_future_forgery(signer(T0).encode(item()))
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    assert decode_one(dec, forged).signature is INVALID
    genuine = signer(T0 + 1).encode(item())
    assert decode_one(dec, genuine).signature is VALID
    assert dec.bad_signatures == 1


def test_forged_future_frame_on_an_existing_stream_does_not_lock_out_the_sender() -> None:
    clock = Clock()
    enc = FrameEncoder(1, 1, signing=KEY, wall_clock=clock)
    dec = FrameDecoder(signing=KEY, wall_clock=clock)
    assert decode_one(dec, enc.encode(item(0))).signature is VALID
    assert decode_one(dec, far_future_forgery(enc.encode(item(1)))).signature is INVALID
    clock.t += 1
    assert decode_one(dec, enc.encode(item(2))).signature is VALID
    # the stream remembers the last *genuine* timestamp: the sender's counter keeps it moving
    clock.t -= 0.5
    assert decode_one(dec, enc.encode(item(3))).signature is VALID


def test_forged_future_frame_with_wrong_key_does_not_lock_out_the_sender() -> None:
    forged = signer(T0 + 365 * 24 * 3600, key=OTHER_KEY).encode(item())
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    assert decode_one(dec, forged).signature is INVALID
    assert decode_one(dec, signer(T0).encode(item())).signature is VALID


def test_forged_future_frame_does_not_advance_the_decoder_clock() -> None:
    """Otherwise every honest new stream would then look more than a minute stale."""
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    for system in range(2, 6):
        assert decode_one(dec, far_future_forgery(signer(T0, system=system).encode(item()))).signature is INVALID
    assert decode_one(dec, signer(T0 - 30, system=9).encode(item())).signature is VALID
    assert dec.bad_signatures == 4


# --- per-link streams --------------------------------------------------------------------------

def test_links_of_one_sender_keep_separate_timestamp_streams() -> None:
    link0 = SigningKey(SECRET, link_id=0)
    link1 = SigningKey(SECRET, link_id=1)
    ahead = signer(T0 + 10, key=link0).encode(item())
    behind = signer(T0, key=link1).encode(item())
    assert (ahead[-13], behind[-13]) == (0, 1)
    assert sig_timestamp(behind) < sig_timestamp(ahead)

    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0 + 10))
    assert decode_one(dec, ahead).signature is VALID
    assert decode_one(dec, behind).signature is VALID  # its own stream, older timestamp is fine
    assert decode_one(dec, behind).signature is INVALID  # but a replay on that link is not
    assert decode_one(dec, signer(T0 + 20, key=link1).encode(item())).signature is VALID

    # control: the same two frames on one link id are an out-of-order stream
    same = FrameDecoder(signing=KEY, wall_clock=Clock(T0 + 10))
    assert decode_one(same, signer(T0 + 10, key=link0).encode(item())).signature is VALID
    assert decode_one(same, signer(T0, key=link0).encode(item())).signature is INVALID


def test_senders_on_one_link_keep_separate_streams() -> None:
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0 + 10))
    assert decode_one(dec, signer(T0 + 10, system=1).encode(item())).signature is VALID
    assert decode_one(dec, signer(T0, system=2).encode(item())).signature is VALID
    assert decode_one(dec, signer(T0, system=1, component=2).encode(item())).signature is VALID


def test_bad_signature_counter_counts_every_kind() -> None:
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    good = signer(T0).encode(item())
    tampered = good[:-1] + bytes([good[-1] ^ 1])
    items = [
        (good, VALID),
        (good, INVALID),                                          # replay
        (signer(T0, key=OTHER_KEY, system=2).encode(item()), INVALID),   # wrong key
        (tampered, INVALID),                                      # tampered signature
        (signer(T0 - 120, system=3).encode(item()), INVALID),    # stale new stream
        (FrameEncoder(4, 1).encode(item()), UNSIGNED),
    ]
    got = [decode_one(dec, raw).signature for raw, _ in items]
    assert got == [v for _, v in items]
    assert (dec.frames, dec.errors, dec.bad_signatures) == (6, 0, 4)


def test_signed_frames_in_one_datagram() -> None:
    enc = signer()
    datagram = b"".join(enc.encode(item(i)) for i in range(5))
    dec = FrameDecoder(signing=KEY, wall_clock=Clock())
    out = dec.feed(datagram)
    assert [f.signature for f in out] == [VALID] * 5
    assert [f.seq for f in out] == list(range(5))


def test_invalid_verdicts_say_why() -> None:
    """One key: every refusal is INVALID as before, and its fault tells a replay (a genuine
    signature, too old) from a forgery."""
    dec = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    good = signer(T0).encode(item())
    assert decode_one(dec, good).fault is None
    got = decode_one(dec, good)
    assert (got.signature, got.fault, got.authenticity) == (INVALID, SignatureFault.REPLAYED, "replayed")
    tampered = good[:-1] + bytes([good[-1] ^ 1])
    assert decode_one(dec, tampered).fault is SignatureFault.BAD_SIGNATURE      # stale and forged
    assert decode_one(dec, signer(T0, key=OTHER_KEY, system=2).encode(item())).fault is SignatureFault.BAD_SIGNATURE
    stale = signer(T0 - 61, system=3).encode(item())
    assert decode_one(dec, stale).fault is SignatureFault.REPLAYED             # new stream, a minute late
    assert decode_one(dec, FrameEncoder(4, 1).encode(item())).authenticity == "unsigned"
    assert decode_one(FrameDecoder(), good).authenticity == "unchecked"
