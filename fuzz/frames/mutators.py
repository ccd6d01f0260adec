"""Mutators: one small function per fault, named for it. Data, not code paths.

Each takes a well-formed frame (as the encoder made it, signed when the target signs), a
16-bit `arg` from the fuzz program that picks the variant (which bit, how far, what
garbage), and the `MutationContext`; it returns the bytes to send in the frame's place.
What each one produces, as our own decoder sees it, is checked by
tests/fuzz/test_frames_mutators.py (e.g. `bad_crc` is always a checksum error).
Arbitrary bytes come from `random.Random(arg)`: compact in the program, same every time.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Callable

from mavconform.reference_impl.wire.codec import IFLAG_SIGNED, MAGIC_V1, MAGIC_V2
from mavconform.reference_impl.wire.signing import signing_timestamp

from . import wire

STALE_BY = 6_100_000   # 61 s in signature units (10 us): beyond MAVLink's 1-minute window


@dataclass
class MutationContext:
    """What mutators need beyond the frame: keys and the sender's wall clock."""

    key: bytes            # the target's signing secret (or, if it signs nothing, the campaign's)
    wrong_key: bytes      # a secret the target does not hold
    wall_clock: Callable[[], float]
    _last_timestamp: int = field(default=0, repr=False)

    def fresh_timestamp(self) -> int:
        """Now, and strictly after every timestamp handed out before (one stream order)."""
        ts = max(signing_timestamp(self.wall_clock()), self._last_timestamp + 1)
        self._last_timestamp = ts
        return ts


Mutator = Callable[[bytes, int, MutationContext], bytes]


def _garbage(arg: int, n: int) -> bytes:
    """n random bytes with no frame start in them, so the decoder must resync after them."""
    return random.Random(arg).randbytes(n).translate(_NO_START)


_NO_START = bytes(b ^ 0x10 if b in (MAGIC_V1, MAGIC_V2) else b for b in range(256))   # for translate()


def unmutated(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """The frame as encoded (sent only if harmless: see admission.py)."""
    return frame


def bad_crc(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Checksum off by a non-zero XOR: always a checksum error."""
    at = wire.crc_offset(frame)
    flip = (arg or 1).to_bytes(2, "little")
    return frame[:at] + bytes([frame[at] ^ flip[0], frame[at + 1] ^ flip[1]]) + frame[at + 2:]


def bad_length(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Length byte changed, nothing else: the frame runs short (checksum read from the
    payload) or long (it swallows what follows, or is truncated)."""
    new = (frame[1] + 1 + arg % 255) & 0xFF
    return frame[:1] + bytes([new]) + frame[2:]


def truncate(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """The frame cut short after 1 .. len-1 bytes."""
    return frame[:1 + arg % (len(frame) - 1)]


def bad_magic(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Start byte that is no protocol marker: the rest is garbage a decoder must skip, and
    must not be misled by a marker that happens to sit in the payload."""
    b = arg & 0xFF
    if b in (MAGIC_V1, MAGIC_V2):
        b ^= 0x01 if b == MAGIC_V1 else 0x10
    return bytes([b]) + frame[1:]


def unknown_msgid(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """A message id no dialect defines (0xF0xxxx), with a checksum made with some CRC_EXTRA."""
    frame = wire.unsigned(frame)
    mid = 0xF00000 | (arg & 0x0FFF) << 4 | 0x5
    return wire.rechecksum(frame[:7] + mid.to_bytes(3, "little") + frame[10:], extra=arg >> 8)


def v1_v2_mix(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Header of one version under the marker of the other: a v2 frame marked v1 (arg even)
    or a v1 frame marked v2 (arg odd); lengths and checksum positions then disagree."""
    if arg & 1:
        v1 = wire.as_v1(frame)
        if v1 is not None:
            return bytes([MAGIC_V2]) + v1[1:]
    return bytes([MAGIC_V1]) + frame[1:]


def as_mavlink1(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """The same message, well formed, as MAVLink 1: no extensions (no mission_type), no
    signature. Mixed with v2 frames in one datagram."""
    v1 = wire.as_v1(frame)
    return frame if v1 is None else v1


def incompat_flags(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """An incompat flag no one defines (checksum redone): the frame must be dropped."""
    frame = wire.unsigned(frame)
    flag = 0x02 << (arg % 7)
    return wire.rechecksum(frame[:2] + bytes([frame[2] | flag]) + frame[3:])


def wrong_key_signature(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Signed, with a fresh timestamp, by a key the target does not hold."""
    return wire.sign(frame, ctx.wrong_key, arg & 0xFF, ctx.fresh_timestamp())


def stale_timestamp(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """Signed with the right key, but more than a minute in the past (a replayed frame)."""
    ts = signing_timestamp(ctx.wall_clock()) - STALE_BY - arg * 1000
    return wire.sign(frame, ctx.key, (arg >> 8) & 0xFF, max(ts, 0))


def garbage_between(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """1 .. 32 bytes of garbage (no frame marker in them), then the frame intact."""
    return _garbage(arg, 1 + arg % 32) + frame


def bit_flip(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """One to three bits flipped anywhere in the frame."""
    rng = random.Random(arg)
    out = bytearray(frame)
    for _ in range(1 + arg % 3):
        out[rng.randrange(len(out))] ^= 1 << rng.randrange(8)
    return bytes(out)


def signed_flag_unsigned(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """The signed flag set on a frame with no signature block (checksum redone): the
    decoder must look 13 bytes past the frame's end and not find a signature there."""
    frame = wire.unsigned(frame)
    return wire.rechecksum(frame[:2] + bytes([frame[2] | IFLAG_SIGNED]) + frame[3:])


def random_bytes(frame: bytes, arg: int, ctx: MutationContext) -> bytes:
    """No frame at all: 1 .. 64 arbitrary bytes (frame markers included)."""
    return random.Random(arg).randbytes(1 + arg % 64)


MUTATORS: dict[str, Mutator] = {f.__name__: f for f in (
    unmutated, bad_crc, bad_length, truncate, bad_magic, unknown_msgid, v1_v2_mix, as_mavlink1,
    incompat_flags, wrong_key_signature, stale_timestamp, garbage_between, bit_flip,
    signed_flag_unsigned, random_bytes)}
MUTATOR_NAMES: tuple[str, ...] = tuple(MUTATORS)
# The mutators whose output is a function of (frame, arg) alone: no clock, no context state.
PURE: frozenset[str] = frozenset(MUTATORS) - {"wrong_key_signature", "stale_timestamp"}
