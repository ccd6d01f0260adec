"""Which mutated frames may be sent as they are: the rule that keeps the plan oracle honest.

The oracle says the stored plans must not change and a normal download must still work.
A mutant can, by accident or by design (`unmutated`, `as_mavlink1`, `garbage_between`, a
checksum that happens to match), be a well-formed frame the target accepts; a well-formed
MISSION_CLEAR_ALL *should* clear the plan, and a well-formed MISSION_REQUEST_LIST from a
fuzz id *should* make the download of the oracle's GCS wait (DENIED). So a frame the target
would accept is sent only if its message is INERT: it can neither change a stored plan nor
open a transfer (HEARTBEAT, MISSION_ACK, item requests, items - a stray item or request in
idle gets at most an error ACK - and vehicle-to-GCS telemetry; a profile whose uploads
neither end nor apply whole takes items out of it: `inert_messages`). Any other accepted frame
goes out with a checksum byte flipped (XOR 0xFF, at the same position every time, so
replays are exact); the step records that it was.

"Would accept" is judged by two kinds of parser, each configured as the target is:

  - our own decoder (reference_impl/wire/codec.py), one datagram at a time: the builtin
    and mutant vehicles read datagrams so;
  - the MAVLink C parser (reference_impl/wire/cparser.py), in both forms real autopilots run it
    (mavlink_parse_char: PX4, mavlink_parse_char restarting on a 0xFD that ends a bad
    frame; mavlink_frame_char_buffer: ArduPilot), as a BYTE STREAM whose state persists
    from one datagram to the next on the link. So a frame is also caught when it is
    completed by the next datagram's bytes (truncated at a datagram's end, or flagged
    signed with no signature: without signing a C target takes the next 13 bytes as its
    signature), when it hides in the payload of a frame with an unknown incompat flag (the
    C parser rescans after the flag byte), or when it starts on the 0xFD that ended a
    bad frame. A frame whose checksum is good and that waits, at the datagram's end, for
    its signature bytes counts as accepted now (for a target without signing whatever
    follows completes it), so its checksum is broken in this datagram and no later bytes -
    fuzz, filler or the oracle's - can complete it as valid. The C models know every
    message pymavlink knows (our dialect first), so a frame of a message a real target
    knows and we do not is caught too.

Per datagram (`admit`): every parser runs on a copy of its state; each offending frame gets
a checksum byte flipped that lies in THIS datagram (a frame whose checksum lay in an
earlier datagram was caught there: either it completed there or it was pending with a good
checksum); a flip can change how the stream parses (a flipped byte may become 0xFD), so
the parsers run again on the changed datagram, up to ROUNDS times. If that does not settle,
the offending frames' bytes in this datagram are replaced by a filler byte that is no start
byte (`last_filled` names those frames; they are also among the neutralised indexes). Only
then is the state committed, with the bytes that will be sent.

Every other datagram that reaches the target on the same link (the oracle GCS's own, which
leave the same socket) is fed to the stream models in order by the rig (`observe`), and
before the oracle speaks after fuzz bytes the rig sends `resync()`: filler bytes (no start
byte in them) that complete any frame in progress as one the target does not accept,
checked with the models, so every batch leaves the C parser IDLE and the oracle's frames
can neither complete a fuzz frame nor be swallowed by one. The filler is derived from the
model state alone, so a replay of the same datagrams regenerates it byte for byte.

Guarantee: for a target that frames as our decoder or as either C parser (without signing,
or with its signing policy: a target that requires signatures accepts only right-key,
fresh signatures, so unsigned / wrong-key / stale MISSION_CLEAR_ALLs go out intact and must
be ignored), nothing the fuzzer sends - alone, across datagrams, or joined with the
oracle's frames - is an accepted plan-changing or transfer-opening message, as long as the
link delivers every datagram in order. Every plan change, every refused or stalled
download after a batch is then a finding.

Signing state: the decoder here sees the same frames in the same order as the target, so
its per-stream timestamps follow the target's. The one divergence (a frame accepted here
whose checksum is then broken, so the target never sees it) cannot change a later verdict,
because the fuzzer's right-key signatures carry strictly increasing timestamps.
"""

from __future__ import annotations

from bisect import bisect_right
from collections import deque
from typing import Any, Callable, Iterable

from mavconform.reference_impl.wire.codec import FrameDecoder
from mavconform.reference_impl.wire.cparser import OK, PARSE_CHAR, VARIANTS, CParser, MessageTable, ParsedFrame
from mavconform.reference_impl.wire.frame import Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import SigningKey

from . import wire
from .stream_models import Models, bytes_to_idle, stream_offending

INERT: frozenset[str] = frozenset({
    "HEARTBEAT", "MISSION_ACK", "MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ITEM",
    "MISSION_ITEM_INT", "MISSION_CURRENT", "MISSION_ITEM_REACHED", "STATUSTEXT",
    "GLOBAL_POSITION_INT", "COMMAND_ACK",
})

INVALID, VALID = SignatureVerdict.INVALID, SignatureVerdict.VALID

ROUNDS = 16                 # re-parses of one datagram after flips, at most
FILLERS = (0x00, 0x55, 0xAA, 0x11, 0x77, 0x33, 0xCC, 0x01)   # never 0xFD / 0xFE
RESYNC_MAX = 300            # > the longest frame (280 bytes): enough to end any of them
QUEUE_MAX = 4096            # admitted datagrams not yet seen on the wire, kept at most
MEMO_MAX = 20_000           # admit() outcomes kept for datagrams that come again (see admit)


def _target_table() -> MessageTable:
    """Our dialect, then every message pymavlink knows (PX4's and ArduPilot's included)."""
    try:
        from pymavlink.dialects.v20 import all as every
    except ImportError:        # pragma: no cover - pymavlink ships it
        return MessageTable.of(wire._DIALECT)
    return MessageTable.of(wire._DIALECT, every)


TARGET_TABLE = _target_table()


def inert_messages(config: Any) -> frozenset[str]:
    """INERT for a vehicle of this profile. A stray item is inert where an upload ends (a
    timer, a GCS's cancel) or is applied whole: INAV 9.1 has neither (VARIANTS I6; I11, I14
    in docs/real-targets.md): its upload counters outlive the upload, so after MISSION_COUNT
    3 and three items a stray MISSION_ITEM seq 3 is appended (seen on its SITL), and after
    any MISSION_COUNT an item 0 replaces the plan."""
    if config.behaviour.atomic_upload or config.abandoned_upload_ends:
        return INERT
    return INERT - {"MISSION_ITEM", "MISSION_ITEM_INT"}


def _ids(names: frozenset[str]) -> frozenset[int]:
    return frozenset(mid for mid, (name, _) in TARGET_TABLE.entries.items() if name in names)


_INERT_IDS = _ids(INERT)

class Admission:
    """Decodes each datagram as the target would and neutralises what must not go out."""

    def __init__(self, key: bytes | None, require_signature: bool,
                 wall_clock: Callable[[], float], *, variants: Iterable[str] = VARIANTS,
                 inert: frozenset[str] = INERT) -> None:
        self.key = key
        self.inert = inert
        self._inert_ids = _INERT_IDS if inert == INERT else _ids(inert)
        self.wall_clock = wall_clock
        self.decoder = FrameDecoder(signing=SigningKey(key) if key is not None else None,
                                    wall_clock=wall_clock)
        self.require_signature = require_signature
        variants = tuple(variants)
        models: Models = [(variants, CParser(variants[0], table=TARGET_TABLE, key=key,
                                             accept_unsigned=not require_signature,
                                             wall_clock=wall_clock))] if variants else []
        self._plan: Models = models   # the state after every admitted datagram
        self._wire: Models = models   # the state after every datagram the target has read
        self._queue: deque[tuple[bytes, Models]] = deque(maxlen=QUEUE_MAX)
        self._memo: dict[Any, tuple] = {}
        self.neutralised = 0   # frames whose bytes were changed by the rule
        self.filled = 0        # of which replaced by filler (the flips did not settle)
        self.last_filled: list[int] = []
        self.resyncs = 0       # filler datagrams handed out by resync()
        self.leaked = 0        # accepted non-INERT frames observe() saw completed by a later
                               # datagram: the rule failed (0 unless datagrams go out of order)
        self.out_of_order = 0  # observed datagrams that overtook admitted ones

    @property
    def models(self) -> dict[str, CParser]:
        """The stream model of each variant as the target's parser stands (after what it
        has read)."""
        out = {}
        for variants, m in self._wire:
            for v in variants:
                out[v] = view = m.copy()
                view.variant, view.restart = v, v == PARSE_CHAR
        return out

    def accepts(self, frame: Frame) -> bool:
        """Would the target act on this decoded frame (its signature policy passed)?"""
        verdict = frame.signature
        if verdict is SignatureVerdict.INVALID:
            return False
        return not (self.require_signature and verdict is not SignatureVerdict.VALID)

    # --- fuzz datagrams ---------------------------------------------------------------------
    def admit(self, frames: list[bytes]) -> tuple[list[bytes], list[int]]:
        """The frames to send as one datagram, and the indexes of those neutralised.

        Without a key the decoder keeps no state, so the outcome depends on the frames and
        the stream models' state alone, offsets aside: it is kept (specs and whole datagrams
        repeat: Hypothesis mutates what it drew before) and replayed, the models moved to
        the stream offset of now."""
        plan = self._plan
        if self.key is not None or not plan:
            return self._admit(frames)
        offset = plan[0][1].offset       # every group has read the same bytes
        key = (tuple((vs, m.resume_key()) for vs, m in plan), *frames)
        kept = self._memo.get(key)
        if kept is None:
            out, fixed = self._admit(frames)
            if len(self._memo) >= MEMO_MAX:
                self._memo.clear()
            self._memo[key] = (offset, tuple(out), tuple(fixed), tuple(self.last_filled),
                               self._queue[-1][0], self._plan)
            return out, fixed
        at, out, fixed, filled, sent, models = kept
        delta = offset - at
        self._plan = models = [(vs, m.shifted(delta)) for vs, m in models]
        self._queue.append((sent, models))
        self.last_filled = list(filled)
        self.neutralised += len(fixed)
        self.filled += len(filled)
        return list(out), list(fixed)

    def _admit(self, frames: list[bytes]) -> tuple[list[bytes], list[int]]:
        data = b"".join(frames)
        offending = self._decoder_offending(data, self.decoder)
        first = None
        if not offending:
            first = self._stream_offending(self._plan, data)
            if not first[1]:      # the usual datagram: nothing to neutralise
                self._plan = first[0]
                self.last_filled = []
                self._queue.append((data, first[0]))
                return frames, []
        return self._neutralise(frames, data, offending, first)

    def _neutralise(self, frames: list[bytes], data: bytes, offending: list[int],
                    first: tuple[Models, list[tuple[ParsedFrame, int]]] | None) -> tuple[list[bytes], list[int]]:
        """`admit` for a datagram with offending frames: flip, re-parse, settle or fill.
        `first`: the stream models' verdict on `data` already (when no decoder flips)."""
        cur = data
        n = len(data)
        buf = bytearray(data)
        flipped: set[int] = set()
        for at in offending:
            buf[at] ^= 0xFF
            flipped.add(at)
        if flipped:
            cur = bytes(buf)
        models: Models | None = None
        spans: list[tuple[int, int]] = []
        recheck = False
        for r in range(ROUNDS):
            trial, hits = first if r == 0 and first is not None else self._stream_offending(self._plan, cur)
            todo: set[int] = set()
            stuck = False
            for frame, base in hits:
                at = _crc_byte(frame, base, n, flipped)
                if at is None:
                    stuck = True
                else:
                    todo.add(at)
            if recheck:
                # our decoder frames by the length fields, so flips made for the stream
                # parsers cannot move its frames, but one may land in a frame whose checksum
                # was broken and make it match again: look (keyless decoders only: a keyed
                # one moves its timestamps; a valid signature cannot come of a flip anyway)
                for at in self._decoder_offending(cur, self.decoder, already=flipped):
                    todo.add(at)
            if not todo and not stuck:
                models = trial
                break
            spans = [(max(f.start - base, 0), min(f.end - base, n)) for f, base in hits]
            if stuck:
                break
            for at in todo:
                buf[at] ^= 0xFF
                flipped.add(at)
            cur = bytes(buf)
            recheck = self.key is None
        filled: set[int] = set()
        if models is None:
            buf, models, filled = self._fill(buf, spans)
        self._plan = models
        self.last_filled = []
        if not flipped and not filled:
            self._queue.append((data, models))
            return frames, []
        sent = bytes(buf)
        self._queue.append((sent, models))
        starts, total = [], 0
        for f in frames:
            starts.append(total)
            total += len(f)
        touched = sorted({bisect_right(starts, at) - 1 for at in flipped | filled})
        out = list(frames)
        fixed: list[int] = []
        for j in touched:
            mine = sent[starts[j]:starts[j] + len(frames[j])]
            if mine != frames[j]:
                out[j] = mine
                fixed.append(j)
        if filled:
            self.last_filled = sorted({bisect_right(starts, at) - 1 for at in filled})
            self.filled += len(self.last_filled)
        self.neutralised += len(fixed)
        return out, fixed

    def _decoder_offending(self, data: bytes, decoder: FrameDecoder,
                           already: set[int] | None = None) -> list[int]:
        """Offsets of the first checksum byte of each frame the per-datagram decoder accepts
        whose message is not INERT (the second byte if the first was flipped already).
        `FrameDecoder.accepted`: what `feed` would accept, without building the messages."""
        out = []
        inert = self._inert_ids
        require = self.require_signature
        for pos, _, msgid, verdict in decoder.accepted(data):
            if msgid in inert or verdict is INVALID or (require and verdict is not VALID):
                continue
            at = wire.crc_offset(data, pos)
            if already is not None and at in already:
                at += 1
                if at in already:
                    continue    # both flipped: it cannot be accepted any more
            out.append(at)
        return out

    def _stream_offending(self, models: Models, data: bytes) -> tuple[Models, list[tuple[ParsedFrame, int]]]:
        """`stream_offending` (stream_models.py) with this rule's INERT messages."""
        return stream_offending(models, data, self._inert_ids)

    def _fill(self, buf: bytearray, spans: list[tuple[int, int]]) -> tuple[bytearray, Models, set[int]]:
        """The flips did not settle: replace the offending frames' bytes in this datagram
        (then, if need be, the whole datagram) by a filler the models find harmless."""
        n = len(buf)
        for whole in (False, True):
            for filler in FILLERS:
                cand = bytearray(buf)
                for a, b in ([(0, n)] if whole else spans):
                    cand[a:b] = bytes((filler,)) * (b - a)
                trial, hits = self._stream_offending(self._plan, bytes(cand))
                probe = FrameDecoder(signing=SigningKey(self.key) if self.key is not None else None,
                                     wall_clock=self.wall_clock)
                if not hits and not self._decoder_offending(bytes(cand), probe):
                    return cand, trial, {i for a, b in ([(0, n)] if whole else spans) for i in range(a, b)}
        raise RuntimeError("admission: no filler makes this datagram harmless")   # pragma: no cover

    # --- everything else on the link --------------------------------------------------------
    def observe(self, datagram: bytes) -> list[ParsedFrame]:
        """A datagram that reached the target on this link, in order: each admitted one when
        it goes out (recognised, its state is already known), every other one (the oracle
        GCS's frames, a replayed case's datagrams) fed to the stream models. Returns what
        the models completed in it."""
        queue = self._queue
        if queue and queue[0][0] == datagram:
            self._wire = queue.popleft()[1]
            return []
        if not self._wire:
            return []
        base = self._wire[0][1].offset
        wire_models, _ = self._stream_offending(self._wire, datagram)
        done: list[ParsedFrame] = []
        for variants, m in self._wire:
            for v in variants:
                for f in m.copy().feed(datagram, v):
                    done.append(f)
                    if f.result == OK and f.start < base and f.msgid not in self._inert_ids:
                        self.leaked += 1
        self._wire = wire_models
        if queue:
            # it overtook admitted datagrams: their flips were chosen for another state
            self.out_of_order += 1
            plan = wire_models
            rebased = deque(maxlen=QUEUE_MAX)
            for d, _ in queue:
                plan = self._stream_offending(plan, d)[0]
                rebased.append((d, plan))
            self._queue = rebased
            self._plan = plan
        else:
            self._plan = wire_models
        return done

    def pending(self) -> bool:
        """Is the target's C parser (any form of it) in the middle of a frame?"""
        return not all(m.idle for _, m in self._wire)

    def resync(self) -> bytes | None:
        """Filler bytes that bring every stream model back to IDLE, completing the frame in
        progress as one the target does not accept (None if all are IDLE). Call it when the
        datagram is about to be sent: it is counted as sent. Deterministic in the state."""
        if not self.pending():
            return None
        for filler in FILLERS:
            chunk = bytes((filler,)) * RESYNC_MAX
            trial, hits = self._stream_offending(self._wire, chunk)
            if hits or not all(t.idle for _, t in trial):
                continue
            need = max(bytes_to_idle(m, v, filler, RESYNC_MAX) for variants, m in self._wire for v in variants)
            data = chunk[:need]
            self.observe(data)
            self.resyncs += 1
            return data
        raise RuntimeError("admission: no filler ends the frame in progress harmlessly")   # pragma: no cover


def _crc_byte(frame: ParsedFrame, base: int, n: int, flipped: set[int]) -> int | None:
    """The datagram offset of a checksum byte of `frame` that lies in this datagram (of
    length n, starting at stream offset `base`) and was not flipped yet; None if none."""
    for at in (frame.crc - base, frame.crc + 1 - base):
        if 0 <= at < n and at not in flipped:
            return at
    return None
