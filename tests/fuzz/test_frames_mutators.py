"""Each frame mutator produces the fault it is named for, as our own decoder sees it, and
the admission rule never lets a plan-changing message through intact."""

from __future__ import annotations

import pytest

from mavconform.fuzz.frames import wire
from mavconform.fuzz.frames.admission import INERT, Admission
from mavconform.fuzz.frames.mutators import MUTATORS, MutationContext
from mavconform.fuzz.frames.program import CHUNK, RECORD, parse
from mavconform.fuzz.frames.templates import GCS_IDS, TEMPLATES
from mavconform.reference_impl.net.clock import SimClock
from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.frame import DecodeError, Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import SigningKey

KEY, WRONG = bytes(range(32)), bytes(range(1, 33))
TARGET = (1, 1)
ARGS = (0, 1, 2, 7, 255, 256, 4097, 65535)
CLOCK = SimClock(100.0)


def ctx() -> MutationContext:
    return MutationContext(key=KEY, wrong_key=WRONG, wall_clock=CLOCK.wall)


def bases() -> list[tuple[str, bytes]]:
    enc = FrameEncoder(255, 190)
    return [(name, enc.encode(build(TARGET))) for name, build in TEMPLATES]


def decode(data: bytes, key: bytes | None = None) -> list[Frame | DecodeError]:
    return FrameDecoder(signing=SigningKey(key) if key else None, wall_clock=CLOCK.wall).feed(data)


def frames(items) -> list[Frame]:
    return [i for i in items if isinstance(i, Frame)]


def errors(items) -> list[str]:
    return [i.reason for i in items if isinstance(i, DecodeError)]


def cases():
    return [(name, base, arg) for name, base in bases() for arg in ARGS]


@pytest.mark.parametrize("name,base,arg", cases())
def test_every_mutator_makes_its_fault(name: str, base: bytes, arg: int) -> None:
    c = ctx()
    m = {k: f(base, arg, c) for k, f in MUTATORS.items()}
    # the untouched frame, and the frame behind garbage, decode as the original
    (got,) = decode(m["unmutated"])
    assert isinstance(got, Frame) and got.raw == base
    items = decode(m["garbage_between"])
    assert errors(items) == ["bytes outside any frame"] and [f.raw for f in frames(items)] == [base]
    # checksum, flags and id faults are each reported as exactly that
    assert len(errors(decode(m["bad_crc"]))) == 1 and "CRC" in errors(decode(m["bad_crc"]))[0]
    assert not frames(decode(m["bad_crc"]))
    assert errors(decode(m["incompat_flags"]))[0].startswith("unknown incompat_flags")
    assert errors(decode(m["unknown_msgid"]))[0].startswith("unknown message id")
    assert errors(decode(m["truncate"]))[-1].startswith("truncated frame")
    # faults that break the framing never yield a valid frame
    for fault in ("bad_crc", "bad_length", "truncate", "bad_magic", "unknown_msgid", "v1_v2_mix",
                  "incompat_flags", "bit_flip", "signed_flag_unsigned"):
        assert not frames(decode(m[fault])), f"{fault}({name}, {arg}) decoded as a frame"
    assert errors(decode(m["bad_magic"]))[0] == "bytes outside any frame"
    # MAVLink 1 re-encoding: the same message, version 1
    (v1,) = decode(m["as_mavlink1"])
    assert isinstance(v1, Frame) and v1.version == 1 and v1.name == name.split()[0]
    # signatures: wrong key and stale time are invalid to a key holder, unchecked to others
    for fault in ("wrong_key_signature", "stale_timestamp"):
        (keyed,) = decode(m[fault], KEY)
        assert isinstance(keyed, Frame) and keyed.signature is SignatureVerdict.INVALID, fault
        (keyless,) = decode(m[fault])
        assert isinstance(keyless, Frame) and keyless.signature is SignatureVerdict.UNCHECKED
    assert 1 <= len(m["random_bytes"]) <= 64 and m["random_bytes"] == MUTATORS["random_bytes"](base, arg, c)


def test_a_fresh_right_key_signature_is_valid_so_the_signed_baseline_is_real() -> None:
    base = bases()[0][1]
    c = ctx()
    (got,) = decode(wire.sign(base, KEY, 3, c.fresh_timestamp()), KEY)
    assert got.signature is SignatureVerdict.VALID and got.link_id == 3
    assert wire.unsigned(wire.sign(base, KEY, 3, 5)) == base


def test_admission_breaks_the_checksum_of_accepted_plan_changing_frames_only() -> None:
    by_name = dict(bases())
    clear, heartbeat = by_name["MISSION_CLEAR_ALL all"], by_name["HEARTBEAT"]
    adm = Admission(None, False, CLOCK.wall)
    out, fixed = adm.admit([heartbeat, clear, heartbeat])
    assert fixed == [1] and out[0] == heartbeat == out[2] and out[1] != clear
    assert [type(i).__name__ for i in decode(b"".join(out))] == ["Frame", "DecodeError", "Frame"]
    # a vehicle that requires signatures would not accept the unsigned frame: it goes out intact
    strict = Admission(KEY, True, CLOCK.wall)
    assert strict.admit([clear]) == ([clear], [])
    signed = wire.sign(clear, KEY, 0, ctx().fresh_timestamp())
    assert strict.admit([signed])[1] == [0]


@pytest.mark.parametrize("seed", range(40))
def test_nothing_admitted_decodes_as_an_accepted_non_inert_message(seed: int) -> None:
    import random
    from mavconform.fuzz.frames.program import Builder
    for key in (None, KEY):
        c = ctx()
        adm = Admission(key, key is not None, CLOCK.wall)
        builder = Builder(TARGET, c, adm, sign_frames=key is not None)
        check = Admission(key, key is not None, CLOCK.wall)
        for specs in parse(random.Random(seed).randbytes(CHUNK * RECORD * 4)):
            sent, _ = builder.datagram(specs)
            for item in frames(check.decoder.feed(b"".join(sent))):
                assert item.name in INERT or not check.accepts(item), (item.name, specs)


def test_program_records_parse_into_datagrams_of_one_to_eight_frames() -> None:
    from mavconform.fuzz.frames.program import FrameSpec
    assert parse(bytes(RECORD * 3)) == [[FrameSpec(0, 0, 0, 0)]] * 3   # zero bytes: simplest
    joined = parse(bytes([0xFF, 0, 0, 0, 0]) * 20)
    assert [len(d) for d in joined] == [8, 8, 4]
    assert len(GCS_IDS) == 8 and (250, 190) not in GCS_IDS


class _Passthrough:
    """An admission rule that lets everything out: the builder's own frames, unchanged."""

    last_filled: list[int] = []

    def admit(self, frames: list[bytes]) -> tuple[list[bytes], list[int]]:
        return frames, []


def test_a_builder_reuses_only_what_mutating_again_would_give() -> None:
    """The builder keeps pure mutators' frames per spec (specs repeat); each datagram must
    hold exactly what mutating the template afresh gives, clock-bound mutators included."""
    import random
    from mavconform.fuzz.frames.mutators import MUTATOR_NAMES, PURE
    from mavconform.fuzz.frames.program import Builder
    clock = SimClock(100.0)
    c = MutationContext(key=KEY, wrong_key=WRONG, wall_clock=clock.wall)
    fresh = MutationContext(key=KEY, wrong_key=WRONG, wall_clock=clock.wall)
    builder = Builder(TARGET, c, _Passthrough(), sign_frames=False)
    body = random.Random(3).randbytes(CHUNK * RECORD * 40)
    program = parse(body + body)          # every spec twice at least
    for specs in program:
        got, _ = builder.datagram(specs)
        want = [MUTATORS[MUTATOR_NAMES[s.mutator]](builder.base(s.source, s.template), s.arg, fresh) for s in specs]
        assert got == want, specs
        clock.advance(0.37)
    assert builder._made and all(MUTATOR_NAMES[s.mutator] in PURE for s in builder._made)
