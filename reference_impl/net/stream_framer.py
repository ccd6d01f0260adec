"""Frames cut from a byte stream: what a TCP connection or a serial line carries.

A UDP datagram arrives whole, so the nodes take each datagram as one or more whole frames.
A stream has no such edges: one read may hold half a frame, or the end of one and the
start of the next, and a serial line adds noise between frames. The frames are found the
way the autopilot on the other end finds ours: by the MAVLink C library's receive parser
(`reference_impl.wire.cparser`, mavlink_parse_char, which resynchronises on the next start
byte after garbage or a bad frame). Each frame it completes, good or bad, goes to the
node as one datagram, so the node's decoder judges it as it judges a datagram's frames
(an unknown message is framed by its length byte, as C frames it); bytes between frames
are counted and dropped.
"""

from __future__ import annotations

from mavconform.reference_impl.wire.cparser import DIALECT_TABLE, OK, PARSE_CHAR, CParser, MessageTable


class StreamFramer:
    """One direction of one stream link. `feed` returns whole frames, in order."""

    def __init__(self, table: MessageTable = DIALECT_TABLE) -> None:
        self._parser = CParser(PARSE_CHAR, table=table)
        self._held = bytearray()   # stream bytes from offset `_base` on, not yet all framed
        self._base = 0
        self._cursor = 0           # stream offset just past the last frame returned
        self.frames = 0            # frames returned
        self.bad = 0               # of them, with a bad checksum (or a message we do not know)
        self.skipped = 0           # bytes that were in no frame

    def feed(self, data: bytes) -> list[bytes]:
        """The frames `data` completes (with bytes fed before it)."""
        self._held += data
        out: list[bytes] = []
        for frame in self._parser.feed(data):
            if frame.start > self._cursor:
                self.skipped += frame.start - self._cursor
            out.append(bytes(self._held[frame.start - self._base:frame.end - self._base]))
            self._cursor = frame.end
            self.frames += 1
            if frame.result != OK:
                self.bad += 1
        keep_from = self._parser.frame_start
        if keep_from is None:   # idle: what follows the last frame is in none
            end = self._base + len(self._held)
            if end > self._cursor:
                self.skipped += end - self._cursor
                self._cursor = end
            keep_from = end
        elif keep_from > self._cursor:   # garbage before the frame now in progress
            self.skipped += keep_from - self._cursor
            self._cursor = keep_from
        del self._held[:keep_from - self._base]
        self._base = keep_from
        return out

    def reset(self) -> None:
        """A new connection: nothing of the old stream is carried over."""
        counts = (self.frames, self.bad, self.skipped)
        self.__init__(self._parser.table)
        self.frames, self.bad, self.skipped = counts


class PassThrough:
    """A framer for a node that frames the stream itself (MSP, reference_impl/msp): each
    read goes to the node as it came; nothing is counted here."""

    frames = bad = skipped = 0

    def feed(self, data: bytes) -> list[bytes]:
        return [data]

    def reset(self) -> None:
        pass
