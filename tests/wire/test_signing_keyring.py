"""MAVLink 2 signing with a key per system (a `Keyring`), and the endpoint that signs and
checks per link with one, counting what it drops."""

from __future__ import annotations

import hashlib
from typing import Any

import pytest

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink
from mavconform.reference_impl.wire.frame import SignatureFault
from mavconform.reference_impl.wire.signing import Keyring, SigningKey, secret_from_hex, secret_from_passphrase

from .signing_rig import INVALID, KEY, SECRET, T0, UNSIGNED, VALID, Clock, decode_one, far_future_forgery, item, signer


# --- a key per system (keyring) ----------------------------------------------------------------

KEY_A = SigningKey(bytes(range(32)), link_id=1)
KEY_B = SigningKey(bytes(range(100, 132)), link_id=2)
KEY_X = SigningKey(bytes(32 * [0x42]))
A, B = 201, 202


def ring() -> Keyring:
    return Keyring([(A, KEY_A), (B, KEY_B)])


def test_keyring_checks_each_frame_against_the_key_of_the_system_it_claims() -> None:
    dec = FrameDecoder(signing=ring(), wall_clock=Clock(T0))
    assert dec.signing_enabled and dec.keyring is not None
    assert decode_one(dec, signer(key=KEY_A, system=A).encode(item())).authenticity == "ok"
    assert decode_one(dec, signer(key=KEY_B, system=B).encode(item())).authenticity == "ok"
    # B signs with its own (valid, known) key but claims to be A
    spoof = decode_one(dec, signer(T0 + 1, key=KEY_B, system=A).encode(item()))
    assert (spoof.signature, spoof.fault) == (INVALID, SignatureFault.BAD_SIGNATURE)
    # a system the keyring does not know, whatever key it signs with
    for key in (KEY_X, KEY_A):
        stranger = decode_one(dec, signer(key=key, system=66).encode(item()))
        assert (stranger.signature, stranger.fault, stranger.authenticity) == (
            INVALID, SignatureFault.UNKNOWN_KEY, "unknown key")
    assert decode_one(dec, FrameEncoder(A, 1).encode(item())).signature is UNSIGNED
    assert (dec.frames, dec.bad_signatures) == (6, 3)
    # the spoof did not touch A's stream: A carries on
    assert decode_one(dec, signer(T0 + 0.5, key=KEY_A, system=A).encode(item())).authenticity == "ok"


def test_keyring_replay_protection_is_per_system_component_and_link() -> None:
    dec = FrameDecoder(signing=ring(), wall_clock=Clock(T0 + 10))
    a1 = signer(T0 + 10, key=KEY_A, system=A).encode(item())
    assert decode_one(dec, a1).authenticity == "ok"
    assert decode_one(dec, a1).authenticity == "replayed"
    older = signer(T0 + 5, key=KEY_A, system=A).encode(item())
    assert decode_one(dec, older).authenticity == "replayed"
    # other streams of A (another component, another link id) keep their own timestamps
    assert decode_one(dec, signer(T0 + 5, key=KEY_A, system=A, component=2).encode(item())).authenticity == "ok"
    other_link = SigningKey(KEY_A.secret, link_id=9)
    assert decode_one(dec, signer(T0 + 5, key=other_link, system=A).encode(item())).authenticity == "ok"
    # and B's streams are B's
    assert decode_one(dec, signer(T0 + 5, key=KEY_B, system=B).encode(item())).authenticity == "ok"
    # the one-minute rule for a new stream
    assert decode_one(dec, signer(T0 - 60, key=KEY_B, system=B, component=3).encode(item())).authenticity == "replayed"
    assert decode_one(dec, signer(T0 - 40, key=KEY_B, system=B, component=4).encode(item())).authenticity == "ok"


def test_one_systems_clock_running_ahead_cannot_make_anothers_frames_stale() -> None:
    """Each key keeps its own local timestamp for the one-minute rule. With one shared key,
    a genuine frame an hour ahead makes every new stream look stale (the control case)."""
    ahead, on_time = T0 + 3600, T0
    shared = FrameDecoder(signing=KEY, wall_clock=Clock(T0))
    assert decode_one(shared, signer(ahead, system=A).encode(item())).signature is VALID
    assert decode_one(shared, signer(on_time, system=B).encode(item())).fault is SignatureFault.REPLAYED
    dec = FrameDecoder(signing=ring(), wall_clock=Clock(T0))
    assert decode_one(dec, signer(ahead, key=KEY_A, system=A).encode(item())).authenticity == "ok"
    assert decode_one(dec, signer(on_time, key=KEY_B, system=B).encode(item())).authenticity == "ok"


def test_keyring_forgery_never_moves_the_claimed_systems_stream() -> None:
    dec = FrameDecoder(signing=ring(), wall_clock=Clock(T0))
    forged = far_future_forgery(signer(T0, key=KEY_A, system=A).encode(item()))
    assert decode_one(dec, forged).fault is SignatureFault.BAD_SIGNATURE
    assert decode_one(dec, signer(T0 + 365 * 86400, key=KEY_B, system=A).encode(item())).fault \
        is SignatureFault.BAD_SIGNATURE
    assert decode_one(dec, signer(T0 + 1, key=KEY_A, system=A).encode(item())).authenticity == "ok"


def test_keyring_validation_and_secret_helpers() -> None:
    assert len(ring()) == 2 and A in ring() and 66 not in ring() and sorted(ring()) == [A, B]
    assert ring().key_for(B) == KEY_B and ring().key_for(66) is None
    assert "secret" not in repr(ring()) and KEY_A.secret.hex() not in repr(ring())
    with pytest.raises(ValueError, match="two keys"):
        Keyring([(A, KEY_A), (A, KEY_B)])
    with pytest.raises(ValueError, match="0..255"):
        Keyring([(256, KEY_A)])
    assert secret_from_hex(SECRET.hex()) == SECRET == secret_from_hex(SECRET.hex().upper())
    for bad, why in ((SECRET.hex()[:-1], "64 hex digits, got 63"), ("zz" * 32, "0-9, a-f")):
        with pytest.raises(ValueError, match=why):
            secret_from_hex(bad)
    # MAVProxy's `signing setup`: SHA-256 of the passphrase's ASCII bytes
    assert secret_from_passphrase("correct horse") == hashlib.sha256(b"correct horse").digest()
    for bad in ("", "pässword"):
        with pytest.raises(ValueError):
            secret_from_passphrase(bad)


# --- the endpoint with a keyring: per-link signing, counted drops ------------------------------

def heartbeat() -> Any:
    return mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3)


def test_endpoint_signs_each_link_with_the_key_of_the_system_verified_there() -> None:
    clock = Clock(T0)
    vehicle = MavlinkEndpoint(1, 1, keyring=ring(), require_signature=True, wall_clock=clock)
    enc_a = FrameEncoder(A, 190, signing=KEY_A, wall_clock=clock)
    enc_b = FrameEncoder(B, 190, signing=KEY_B, wall_clock=clock)
    assert len(vehicle.receive(enc_a.encode(heartbeat()), "a")) == 1
    assert len(vehicle.receive(enc_b.encode(heartbeat()), "b")) == 1
    assert (vehicle.link_key("a"), vehicle.link_key("b")) == (KEY_A, KEY_B)
    vehicle.send(heartbeat())                      # a broadcast
    vehicle.send(item(), (A, 190))                 # to one peer
    out = vehicle.take_outgoing()
    assert [where for _, where in out] == ["a", "b", "a"]
    gcs_a = FrameDecoder(signing=KEY_A, wall_clock=clock)
    gcs_b = FrameDecoder(signing=KEY_B, wall_clock=clock)
    for data, where in out:
        mine, other = (gcs_a, gcs_b) if where == "a" else (gcs_b, gcs_a)
        assert data[-13] == (KEY_A if where == "a" else KEY_B).link_id
        assert mine.feed(data)[0].signature is VALID
        assert other.feed(data)[0].fault is SignatureFault.BAD_SIGNATURE   # B cannot read A's link as ours
    # each link has its own sequence numbers
    assert [mavlink_seq(d) for d, w in out if w == "a"] == [0, 1]


def mavlink_seq(frame: bytes) -> int:
    return frame[4]


def test_endpoint_counts_every_dropped_frame_by_reason() -> None:
    clock = Clock(T0)
    vehicle = MavlinkEndpoint(1, 1, keyring=ring(), require_signature=True, wall_clock=clock)
    good = FrameEncoder(A, 190, signing=KEY_A, wall_clock=clock).encode(heartbeat())
    sent = [
        (good, "ok"),
        (good, "replayed"),
        (FrameEncoder(B, 190).encode(heartbeat()), "unsigned"),
        (FrameEncoder(A, 190, signing=KEY_B, wall_clock=clock).encode(heartbeat()), "bad signature"),
        (FrameEncoder(66, 190, signing=KEY_X, wall_clock=clock).encode(heartbeat()), "unknown key"),
    ]
    kept = [bool(vehicle.receive(data, "x")) for data, _ in sent]
    assert kept == [True, False, False, False, False]
    assert vehicle.rejections == {"replayed": 1, "unsigned": 1, "bad signature": 1, "unknown key": 1}
    assert vehicle.rejected_signatures == 4
    assert [(r.system, r.message, r.reason) for r in vehicle.rejected] == [
        (A, "HEARTBEAT", "replayed"), (B, "HEARTBEAT", "unsigned"), (A, "HEARTBEAT", "bad signature"),
        (66, "HEARTBEAT", "unknown key")]
    assert str(vehicle.rejected[-1]) == "HEARTBEAT claiming 66/190 from x: unknown key"
    # not required: unsigned frames pass, anything that fails a check still does not
    lenient = MavlinkEndpoint(1, 1, keyring=ring(), wall_clock=clock)
    assert lenient.receive(FrameEncoder(B, 190).encode(heartbeat()), "y")
    assert not lenient.receive(FrameEncoder(66, 190, signing=KEY_X, wall_clock=clock).encode(heartbeat()), "y")
    assert lenient.rejections == {"unknown key": 1} and lenient.link_key("y") is None
