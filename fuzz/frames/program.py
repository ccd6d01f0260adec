"""The fuzz program: what Hypothesis draws, and how it becomes datagrams of frames.

Throughput decides the shape. Hypothesis spends microseconds per drawn value (and per
byte of a byte string), so an example is a count `k` and `k` byte strings of CHUNK frame
records each, not one draw per field. Shrinking still works: a smaller `k` keeps a prefix
of the chunks (each chunk its own choice, so the rest stay aligned), and bytes shrink
towards zero, which reads as "one frame per datagram, first GCS id, first template (a GCS
HEARTBEAT), unmutated". After Hypothesis, `engine.minimise` drops every step and frame the
failure does not need from the concrete case.

Record layout: [join|source] [template] [mutator] [arg lo] [arg hi]
  join   byte 0 >= 0x60: this frame goes in the same datagram as the one before
         (so a datagram holds one to MAX_PER_DATAGRAM frames, 2.7 on average)
  source byte 0 & 7, an index into templates.GCS_IDS
"""

from __future__ import annotations

from typing import Any, NamedTuple

from hypothesis import strategies as st

from mavconform.reference_impl.wire.codec import FrameEncoder

from . import wire
from .admission import Admission
from .mutators import MUTATOR_NAMES, MUTATORS, PURE, MutationContext
from .templates import GCS_IDS, TEMPLATE_NAMES, TEMPLATES, Target

RECORD = 5
CHUNK = 16             # frame records per drawn byte string
MAX_PER_DATAGRAM = 8
JOIN_FROM = 0x60
MADE_MAX = 50_000      # mutated frames a builder keeps for reuse, at most


class FrameSpec(NamedTuple):
    """One frame of the program (a tuple: parsed by the thousand, and a builder's cache key)."""

    source: int
    template: int
    mutator: int
    arg: int

    def describe(self) -> str:
        s = GCS_IDS[self.source]
        return f"{MUTATOR_NAMES[self.mutator]}({TEMPLATE_NAMES[self.template]}) from {s[0]}/{s[1]}"


def programs(max_frames: int) -> st.SearchStrategy[list[list[FrameSpec]]]:
    """Datagrams of frame specs: 1 to max_frames // CHUNK chunks of CHUNK frames."""
    chunk = st.binary(min_size=CHUNK * RECORD, max_size=CHUNK * RECORD)

    @st.composite
    def draw_program(draw: Any) -> list[list[FrameSpec]]:
        k = draw(st.integers(1, max(1, max_frames // CHUNK)))
        return parse(b"".join(draw(chunk) for _ in range(k)))

    return draw_program()


_spec = tuple.__new__   # FrameSpec without its Python-level __new__


def parse(body: bytes) -> list[list[FrameSpec]]:
    n_src, n_tpl, n_mut = len(GCS_IDS), len(TEMPLATES), len(MUTATORS)
    out: list[list[FrameSpec]] = []
    for i in range(0, len(body) - RECORD + 1, RECORD):
        b0, b1, b2, b3, b4 = body[i:i + RECORD]
        spec = _spec(FrameSpec, (b0 % n_src, b1 % n_tpl, b2 % n_mut, b3 | b4 << 8))
        if b0 >= JOIN_FROM and out and len(out[-1]) < MAX_PER_DATAGRAM:
            out[-1].append(spec)
        else:
            out.append([spec])
    return out


class Builder:
    """Turns frame specs into the bytes of one datagram, for one target and campaign.

    Unsigned template frames are encoded once per (source, template); when the target
    signs, each use is signed afresh (right key, a new timestamp) before it is mutated, so
    `unmutated` is a frame the target should accept and the other mutators start from one.
    """

    def __init__(self, target: Target, ctx: MutationContext, admission: Admission, *,
                 sign_frames: bool) -> None:
        self.target = target
        self.ctx = ctx
        self.admission = admission
        self.sign_frames = sign_frames
        self._encoders = {src: FrameEncoder(*src) for src in set(GCS_IDS)}
        self._cache: dict[tuple[int, int], bytes] = {}
        self._mutators = [MUTATORS[name] for name in MUTATOR_NAMES]
        self._pure = frozenset(i for i, name in enumerate(MUTATOR_NAMES) if name in PURE)
        self._made: dict[FrameSpec, bytes] = {}
        self.frames_built = 0

    def base(self, source: int, template: int) -> bytes:
        key = (source, template)
        frame = self._cache.get(key)
        if frame is None:
            msg = TEMPLATES[template][1](self.target)
            frame = self._cache[key] = self._encoders[GCS_IDS[source]].encode(msg)
        if self.sign_frames:
            frame = wire.sign(frame, self.ctx.key, 0, self.ctx.fresh_timestamp())
        return frame

    def datagram(self, specs: list[FrameSpec]) -> tuple[list[bytes], list[int]]:
        """The frames of one datagram (after the admission rule) and which were neutralised."""
        ctx, mutators = self.ctx, self._mutators
        if self.sign_frames:
            frames = [mutators[s.mutator](self.base(s.source, s.template), s.arg, ctx) for s in specs]
        else:
            # unsigned bases are fixed per (source, template), so a pure mutator's output is
            # fixed per spec; Hypothesis repeats specs often (about 3 in 4 in a campaign)
            made, pure = self._made, self._pure
            frames = []
            for s in specs:
                frame = made.get(s)
                if frame is None:
                    frame = mutators[s.mutator](self.base(s.source, s.template), s.arg, ctx)
                    if s.mutator in pure:
                        if len(made) >= MADE_MAX:
                            made.clear()
                        made[s] = frame
                frames.append(frame)
        self.frames_built += len(frames)
        return self.admission.admit(frames)
