"""The admission rule's light decode equals the full one.

`Admission` asks `FrameDecoder.accepted` (framing, msgid, checksum, signature: no message
built) which frames of a datagram the target's per-datagram decoder takes; the vehicle then
decodes the datagram with `FrameDecoder.feed`. If the two ever disagreed, a plan-changing
frame could go out intact (or a harmless one be neutralised for nothing). So both run in
lockstep here, on many mutated datagrams, with every kind of signing configuration: the same
frames (offset, length, msgid, verdict) and the same signing state after every datagram.
"""

from __future__ import annotations

import random
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mavconform.fuzz.frames import wire
from mavconform.fuzz.frames.admission import INERT, Admission
from mavconform.fuzz.frames.mutators import MUTATOR_NAMES, MUTATORS, MutationContext
from mavconform.fuzz.frames.program import RECORD, parse
from mavconform.reference_impl.net.clock import SimClock
from mavconform.reference_impl.wire.codec import FrameDecoder
from mavconform.reference_impl.wire.frame import Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import Keyring, SigningKey

from .frames_admission_streams import BASES, KEY, WRONG, streams

SIGNINGS = {
    "none": lambda: None,
    "right key": lambda: SigningKey(KEY),
    "wrong key": lambda: SigningKey(WRONG),
    "keyring": lambda: Keyring([(255, SigningKey(KEY)), (246, SigningKey(WRONG))]),
}


def by_feed(decoder: FrameDecoder, data: bytes) -> list[tuple[int, int, int, SignatureVerdict]]:
    """What `accepted` must say, read off the full decode."""
    out, pos = [], 0
    for item in decoder.feed(data):
        if isinstance(item, Frame):
            out.append((pos, len(item.raw), item.msgid, item.signature))
        pos += len(item.raw)
    assert pos == len(data)       # feed's items cover the datagram, in order
    return out


def signing_state(decoder: FrameDecoder) -> Any:
    mavs = [decoder._mav, *(decoder._by_system[s] for s in sorted(decoder._by_system))]
    return [(m.signing.timestamp, dict(m.signing.stream_timestamps)) for m in mavs]


def lockstep(signing: str, datagrams: list[bytes], clock: SimClock) -> int:
    """Feed both decoders every datagram; the number of frames accepted."""
    full = FrameDecoder(signing=SIGNINGS[signing](), wall_clock=clock.wall)
    light = FrameDecoder(signing=SIGNINGS[signing](), wall_clock=clock.wall)
    n = 0
    for d in datagrams:
        want = by_feed(full, d)
        assert light.accepted(d) == want, (signing, d.hex())
        assert signing_state(light) == signing_state(full), (signing, d.hex())
        n += len(want)
        clock.advance(0.001)
    return n


def mutated_datagrams(seed: int, frames: int, signed: bool) -> list[bytes]:
    """Datagrams as the fuzz program makes them (templates, mutators, up to 8 frames each),
    before the admission rule; signed with the right key first if `signed`."""
    clock = SimClock(1.7e9)
    ctx = MutationContext(KEY, WRONG, clock.wall)
    mutators = [MUTATORS[name] for name in MUTATOR_NAMES]
    out = []
    for specs in parse(random.Random(seed).randbytes(frames * RECORD)):
        parts = []
        for s in specs:
            base = BASES[(s.source, s.template)]
            if signed:
                base = wire.sign(base, KEY, 0, ctx.fresh_timestamp())
            parts.append(mutators[s.mutator](base, s.arg, ctx))
        out.append(b"".join(parts))
        clock.advance(0.001)
    return out


@pytest.mark.parametrize("signed", [False, True])
@pytest.mark.parametrize("signing", list(SIGNINGS))
def test_accepted_equals_feed_on_fuzz_datagrams(signing: str, signed: bool) -> None:
    datagrams = mutated_datagrams(seed=11 + signed, frames=4000, signed=signed)
    accepted = lockstep(signing, datagrams, SimClock(1.7e9))
    assert accepted > 200        # the sweep holds accepted frames, not only errors


@settings(max_examples=200, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(streams(), st.sampled_from(list(SIGNINGS)))
def test_accepted_equals_feed_on_cut_and_corrupted_streams(datagrams: list[bytes], signing: str) -> None:
    lockstep(signing, datagrams, SimClock(1.7e9))


def offending_by_feed(adm: Admission, decoder: FrameDecoder, data: bytes) -> list[int]:
    """The admission rule's verdict as it was made with the full decode."""
    out, pos = [], 0
    for item in decoder.feed(data):
        if isinstance(item, Frame) and item.name not in adm.inert and adm.accepts(item):
            out.append(pos + wire.crc_offset(item.raw))
        pos += len(item.raw)
    return out


@pytest.mark.parametrize("keyed", [False, True])
def test_the_rule_flags_the_same_frames_as_with_the_full_decode(keyed: bool) -> None:
    clock = SimClock(1.7e9)
    adm = Admission(KEY if keyed else None, keyed, clock.wall, inert=INERT - {"MISSION_ITEM"})
    full = FrameDecoder(signing=SigningKey(KEY) if keyed else None, wall_clock=clock.wall)
    flagged = 0
    for d in mutated_datagrams(seed=5, frames=3000, signed=keyed):
        want = offending_by_feed(adm, full, d)
        assert adm._decoder_offending(d, adm.decoder) == want, d.hex()
        flagged += len(want)
        clock.advance(0.001)
    assert flagged > 20


class _Unkept(Admission):
    """The rule computing every datagram afresh (no outcome kept)."""

    def admit(self, frames: list[bytes]) -> tuple[list[bytes], list[int]]:
        return self._admit(frames)


def _state(adm: Admission) -> list[tuple]:
    return [(vs, m.offset, m._buf, m._start if m._buf else None, m._v1 if m._buf else None) for vs, m in adm._plan]


def test_a_kept_outcome_equals_a_fresh_one() -> None:
    """Keyless, admit() replays what it worked out for the same frames from the same model
    state before: the same frames out, the same flips and fillers, the same model state moved to
    the stream offset of now; the oracle's datagrams and resync fillers in between."""
    clock = SimClock(1.7e9)
    ctx = MutationContext(KEY, WRONG, clock.wall)
    rng = random.Random(4)
    mutators = [MUTATORS[name] for name in MUTATOR_NAMES]
    pool = [[mutators[s.mutator](BASES[(s.source, s.template)], s.arg, ctx) for s in specs]
            for specs in parse(random.Random(9).randbytes(600 * RECORD))]
    kept, fresh = Admission(None, False, clock.wall), _Unkept(None, False, clock.wall)
    computed = [0]
    compute = kept._admit
    kept._admit = lambda frames: (computed.__setitem__(0, computed[0] + 1), compute(frames))[1]
    for step in range(3000):
        frames = rng.choice(pool)
        got, want = kept.admit(list(frames)), fresh.admit(list(frames))
        assert got == want and kept.last_filled == fresh.last_filled, step
        assert (kept.neutralised, kept.filled) == (fresh.neutralised, fresh.filled)
        assert _state(kept) == _state(fresh), step
        for adm in (kept, fresh):
            adm.observe(b"".join(got[0]))
        if step % 7 == 0:               # the oracle speaks: resync, then its frame
            assert kept.resync() == fresh.resync()
            for adm in (kept, fresh):
                adm.observe(BASES[(0, 0)])
    assert 3000 - computed[0] > 500 and kept.neutralised > 100      # replayed; flips among them
