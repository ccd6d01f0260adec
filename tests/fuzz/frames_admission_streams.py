"""Frames as the admission tests build them: real frames from the templates, mutated, signed
and cut into datagrams, and what a C parser model accepts of them (test_frames_admission*.py)."""

from __future__ import annotations

from hypothesis import strategies as st

from mavconform.fuzz.frames import wire
from mavconform.fuzz.frames.admission import INERT, TARGET_TABLE
from mavconform.fuzz.frames.mutators import MUTATORS, MutationContext
from mavconform.fuzz.frames.templates import GCS_IDS, TEMPLATE_NAMES, TEMPLATES
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.net.clock import SimClock
from mavconform.reference_impl.wire.codec import FrameEncoder
from mavconform.reference_impl.wire.cparser import BAD_CRC, FRAME_CHAR_BUFFER, OK, CParser, ParsedFrame

KEY, WRONG = bytes(range(32)), bytes(range(1, 33))
TARGET = (1, 1)
CLOCK = SimClock(1.7e9)          # a wall clock after 2015, so signing timestamps are real
ORACLE = (250, 190)
MUTATOR_LIST = list(MUTATORS.values())
MUTATOR_INDEX = {name: i for i, name in enumerate(MUTATORS)}


# --- building streams ------------------------------------------------------------------------

def ctx() -> MutationContext:
    return MutationContext(key=KEY, wrong_key=WRONG, wall_clock=CLOCK.wall)


ENCODERS = {src: FrameEncoder(*src) for src in set(GCS_IDS)}
BASES = {(s, t): ENCODERS[GCS_IDS[s]].encode(build(TARGET))
         for s in range(len(GCS_IDS)) for t, (_, build) in enumerate(TEMPLATES)}


def template(name: str, source: int = 0) -> bytes:
    return BASES[(source, TEMPLATE_NAMES.index(name))]


def mutate(mutator: str, frame: bytes, arg: int = 7) -> bytes:
    return MUTATORS[mutator](frame, arg, ctx())


CLEAR = template("MISSION_CLEAR_ALL all")
HEARTBEAT = template("HEARTBEAT")


def oracle_frame(signing: bool = False) -> bytes:
    frame = FrameEncoder(*ORACLE).encode(m.request_list_message(MissionType.MISSION, TARGET))
    return wire.sign(frame, KEY, 0, ctx().fresh_timestamp() + 10**6) if signing else frame


def inert(msgid: int) -> bool:
    return TARGET_TABLE.name(msgid) in INERT


def model_events(variant: str, datagrams: list[bytes]) -> tuple[list[tuple[int, ...]], str]:
    """What the harness prints, predicted by the model: mavlink_parse_char reports OK frames
    only; mavlink_frame_char_buffer every frame, and a signed frame with a bad checksum twice
    (at its second checksum byte, then after the 13 bytes it swallows)."""
    model = CParser(variant)
    frames = [f for d in datagrams for f in model.feed(d)]
    events = []
    row = lambda f, at: (at, f.msgid, f.result, f.sysid, f.compid)   # noqa: E731
    for f in frames:
        if variant == FRAME_CHAR_BUFFER and f.signed and f.result == BAD_CRC:
            events.append(row(f, f.crc + 2))
        if variant == FRAME_CHAR_BUFFER or f.ok:
            events.append(row(f, f.end))
    pending = model.pending()
    if variant == FRAME_CHAR_BUFFER and pending is not None and not pending.ok:
        events.append(row(pending, pending.crc + 2))
    return events, model.c_state()


def accepted(variant: str, datagrams: list[bytes], *, table=TARGET_TABLE,
             key: bytes | None = None) -> list[ParsedFrame]:
    """The OK frames one fresh C parser (model) finds in the datagrams, in order."""
    model = CParser(variant, table=table, key=key, wall_clock=CLOCK.wall)
    return [f for d in datagrams for f in model.feed(d) if f.result == OK]


def plan_changing(frames: list[ParsedFrame]) -> list[ParsedFrame]:
    return [f for f in frames if not inert(f.msgid)]


def split(stream: bytes, cuts: list[int]) -> list[bytes]:
    points = sorted({c % (len(stream) + 1) for c in cuts})
    out, prev = [], 0
    for c in points + [len(stream)]:
        out.append(stream[prev:c])
        prev = c
    return out


piece = st.tuples(st.integers(0, len(GCS_IDS) - 1), st.integers(0, len(TEMPLATES) - 1),
                  st.integers(0, len(MUTATORS) - 1), st.integers(0, 0xFFFF), st.booleans(),
                  st.sampled_from([None, None, 0xFD, 0xFE]))
corruption = st.tuples(st.integers(0, 1 << 20), st.sampled_from([0xFD, 0xFE, 0x00, 0x01, 0x02, 0x80, 0xFF]))


@st.composite
def streams(draw) -> list[bytes]:
    """Datagrams cut from a stream of real frames, mutated (some signed first, some ending
    on a start byte: a bad frame that ends so restarts mavlink_parse_char), with a few
    bytes overwritten by start bytes and flags."""
    c = ctx()
    frames = []
    for source, tpl, mutator, arg, signed, last in draw(st.lists(piece, min_size=1, max_size=20)):
        base = BASES[(source, tpl)]
        if signed:
            base = wire.sign(base, KEY, arg & 3, c.fresh_timestamp())
        frame = MUTATOR_LIST[mutator](base, arg, c)
        frames.append(frame if last is None else frame[:-1] + bytes((last,)))
    stream = bytearray(b"".join(frames))
    for at, value in draw(st.lists(corruption, max_size=4)):
        stream[at % len(stream)] = value
    return split(bytes(stream), draw(st.lists(st.integers(0, 1 << 20), max_size=6)))
