"""Which mutated frames may be sent as they are: the rule that keeps the plan oracle honest.

The oracle says the stored plans must not change and a normal download must still work.
A mutant can, by accident or by design (`unmutated`, `as_mavlink1`, `garbage_between`, a
checksum that happens to match), be a well-formed frame the target accepts; a well-formed
MISSION_CLEAR_ALL *should* clear the plan, and a well-formed MISSION_REQUEST_LIST from a
fuzz id *should* make the download of the oracle's GCS wait (DENIED). So:

  Every datagram is decoded, before it is sent, by our own decoder configured as the
  target is (its signing key; unsigned frames refused if it requires signatures). A frame
  that decoder accepts is sent only if its message is INERT: it can neither change a
  stored plan nor open a transfer (HEARTBEAT, MISSION_ACK, item requests, items - a stray
  item or request in idle gets at most an error ACK - and vehicle-to-GCS telemetry).
  Any other accepted frame is sent with its checksum broken (one byte flipped, at the
  same position every time, so replays are exact); the step records that it was.

Hence nothing the fuzzer sends is a valid plan-changing or transfer-opening message for a
target that follows its own signing policy, and every plan change, every refused or
stalled download after a batch is a finding. In particular, against a vehicle that
requires signatures, unsigned / wrong-key / stale MISSION_CLEAR_ALLs go out intact and
must be ignored.

Signing state: the decoder here sees the same frames in the same order as the target, so
its per-stream timestamps follow the target's. The one divergence (a frame accepted here
whose checksum is then broken, so the target never sees it) cannot change a later verdict,
because the fuzzer's right-key signatures carry strictly increasing timestamps.
"""

from __future__ import annotations

from bisect import bisect_right
from typing import Callable

from reference_impl.wire.codec import FrameDecoder
from reference_impl.wire.frame import Frame, SignatureVerdict
from reference_impl.wire.signing import SigningKey

from . import wire

INERT: frozenset[str] = frozenset({
    "HEARTBEAT", "MISSION_ACK", "MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_ITEM",
    "MISSION_ITEM_INT", "MISSION_CURRENT", "MISSION_ITEM_REACHED", "STATUSTEXT",
    "GLOBAL_POSITION_INT", "COMMAND_ACK",
})


class Admission:
    """Decodes each datagram as the target would and neutralises what must not go out."""

    def __init__(self, key: bytes | None, require_signature: bool,
                 wall_clock: Callable[[], float]) -> None:
        self.decoder = FrameDecoder(signing=SigningKey(key) if key is not None else None,
                                    wall_clock=wall_clock)
        self.require_signature = require_signature
        self.neutralised = 0   # frames whose checksum was broken by the rule

    def accepts(self, frame: Frame) -> bool:
        """Would the target act on this decoded frame (its signature policy passed)?"""
        verdict = frame.signature
        if verdict is SignatureVerdict.INVALID:
            return False
        return not (self.require_signature and verdict is not SignatureVerdict.VALID)

    def admit(self, frames: list[bytes]) -> tuple[list[bytes], list[int]]:
        """The frames to send as one datagram, and the indexes of those neutralised."""
        items = self.decoder.feed(b"".join(frames))
        offending: list[int] = []
        pos = 0
        for item in items:
            if item.__class__ is Frame and item.msg._type not in INERT and self.accepts(item):
                offending.append(pos + wire.crc_offset(item.raw))
            pos += len(item.raw)
        if not offending:
            return frames, []
        starts, total = [], 0
        for f in frames:
            starts.append(total)
            total += len(f)
        out = list(frames)
        fixed: list[int] = []
        for at in offending:
            j = bisect_right(starts, at) - 1
            local = at - starts[j]
            f = out[j]
            out[j] = f[:local] + bytes([f[local] ^ 0xFF]) + f[local + 1:]
            fixed.append(j)
        self.neutralised += len(fixed)
        return out, fixed
