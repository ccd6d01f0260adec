"""A model of the MAVLink C library's receive parser: one link's byte stream, as PX4 and
ArduPilot read it. The frame fuzzer judges what a target admits by it
(fuzz/frames/admission.py); stream links cut their frames with it (net/stream_framer.py).

Our own decoder (reference_impl/wire/codec.py) splits each datagram on its own, by the
frames' length fields. The parser real autopilots run does not: it is the byte-at-a-time
state machine of the generated C library (pymavlink generator/C/include_v2.0/
mavlink_helpers.h), fed every datagram of a link in order, with its state carried from one
datagram to the next. This module mirrors it, frame by frame rather than byte by byte but
with the same outcome for every byte, so the frame fuzzer can tell what such a target would
accept. The C functions it mirrors:

  mavlink_frame_char_buffer()  the state machine (IDLE, GOT_STX .. GOT_MSGID3, GOT_PAYLOAD,
                               GOT_CRC1 / GOT_BAD_CRC1, SIGNATURE_WAIT[_BAD_CRC]);
  mavlink_parse_char()         the wrapper over it (via mavlink_frame_char()): a BAD_CRC or
                               BAD_SIGNATURE frame is a parse error, the state goes IDLE, and
                               if the byte that ended it is MAVLINK_STX (0xFD) it is taken as
                               the start of the next frame (GOT_STX);
  mavlink_get_msg_entry()      the message table: a msgid not in it is always BAD_CRC;
  mavlink_signature_check()    only with a signing key (status->signing set); without one the
                               13 signature bytes are taken unread.

Who uses which (the source mirrors in /work/sitl):
  PX4 v1.16   src/modules/mavlink/mavlink_receiver.cpp:3216: `mavlink_parse_char(
              _mavlink.get_channel(), buf[i], &msg, &_status)` for each byte of each UDP
              datagram: variant PARSE_CHAR. Its generated headers (build/px4_sitl_default/
              mavlink/mavlink_helpers.h) predate the SIGNATURE_WAIT_BAD_CRC state; under
              mavlink_parse_char that makes no difference (the one frame it concerns, signed
              with a bad checksum, is reported BAD_CRC at its second checksum byte by both,
              and the wrapper resets there), which tests/fuzz/test_frames_admission.py checks
              against those headers compiled, when the mirror is present. No signing in the
              receiver: status->signing stays NULL.
  ArduPilot   libraries/GCS_MAVLink/GCS_Common.cpp:1970: `mavlink_frame_char_buffer(
              channel_buffer(), channel_status(), c, &msg, &status)` for each byte, current
              headers: variant FRAME_CHAR_BUFFER (no restart after a bad frame). Only
              MAVLINK_FRAMING_OK reaches handle_message (GCS_Common.cpp:1881
              raw_packetReceived -> MAVLink_routing::check_and_forward, MAVLink_routing.cpp:97,
              returns false for the others). status->signing is NULL unless a key is set
              (GCS_Signing.cpp:160).

What the C code does, and so this model:
  - IDLE skips every byte but 0xFD (v2) and 0xFE (v1). A v1 frame has no flag bytes and
    a 1-byte msgid; it can be neither signed nor carry incompat flags.
  - The length byte is never refused (MAVLINK_MAX_PAYLOAD_LEN is 255 in both autopilots),
    and MAVLINK_CHECK_MESSAGE_LENGTH is defined by neither: a payload shorter or longer than
    the message's is framed as the length byte says; a short v2 payload is zero-filled (a
    copy, no effect on framing). The table's min/max lengths are therefore not needed.
  - An incompat flag other than 0x01 sends the parser IDLE right after the flag byte: the
    rest of that frame (header, payload, checksum) is scanned again for a start byte, so a
    frame inside its payload is found.
  - The checksum (X.25 over len .. payload, then the msgid's CRC_EXTRA) decides OK /
    BAD_CRC; an unknown msgid is BAD_CRC whatever the checksum.
  - A frame with the signed flag (0x01) and a good checksum waits for 13 more bytes,
    whatever they are (in the next datagram if this one ends: SIGNATURE_WAIT), then is OK
    without a key. With a bad checksum it is reported BAD_CRC at its second checksum byte;
    mavlink_parse_char resets there, while mavlink_frame_char_buffer goes on to swallow the
    13 bytes (SIGNATURE_WAIT_BAD_CRC) and reports BAD_CRC again after them (one
    ParsedFrame here, ending after them).
  - mavlink_parse_char's restart at GOT_STX keeps the previous frame's "MAVLink 1" flag:
    after a bad v1 frame that ends in 0xFD, the next frame is read with the v1 layout.
  - With a key: an unsigned frame is BAD_SIGNATURE (no accept_unsigned_callback) unless
    `accept_unsigned`; a signed one is checked as mavlink_signature_check does (SHA-256 of
    key + frame up to the timestamp; streams by (sysid, compid, link id), a new stream's
    timestamp at most 60 s old, a known stream's strictly increasing), and moves the
    stream's timestamp as C does. With `accept_unsigned` the C code also takes a frame
    whose signature fails (the callback is asked in both places).

Not modelled: the legacy headers under mavlink_frame_char_buffer (they report a signed
bad-checksum frame OK after its 13 bytes; no autopilot here runs that pair), statistics,
an accept_unsigned_callback that looks at the msgid (`accept_unsigned` is all or nothing),
link loss and reordering. The message table is a parameter: a target that knows a msgid
the table lacks would frame such a frame OK where the model says BAD_CRC.

    parser = CParser(PARSE_CHAR)
    for datagram in link:
        for frame in parser.feed(datagram):     # ParsedFrame, offsets in the fed stream
            ...
    parser.awaiting_signature()   # a good-checksum frame the next 13 bytes would complete
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from typing import Any, Callable, Mapping, NamedTuple

from .checksum import crc16
from .codec import IFLAG_SIGNED
from .codec import MAGIC_V1 as STX_V1      # MAVLINK_STX_MAVLINK1
from .codec import MAGIC_V2 as STX_V2      # MAVLINK_STX
from .codec import SIGNATURE_LEN as SIGNATURE_BLOCK_LEN
from .codec import default_dialect
from .signing import signing_timestamp

MAX_SIGNING_STREAMS = 16
SIGNING_TIMESTAMP_LIMIT = 60 * 100_000      # MAVLINK_SIGNING_TIMESTAMP_LIMIT s, in 10 us units

# MAVLINK_FRAMING_*
OK = 1
BAD_CRC = 2
BAD_SIGNATURE = 3
RESULT_NAMES = {OK: "OK", BAD_CRC: "BAD_CRC", BAD_SIGNATURE: "BAD_SIGNATURE"}

# The variants (see the module docstring)
PARSE_CHAR = "mavlink_parse_char"
FRAME_CHAR_BUFFER = "mavlink_frame_char_buffer"
VARIANTS = (PARSE_CHAR, FRAME_CHAR_BUFFER)

_HEADER = {True: 5, False: 9}    # bytes after the start byte, before the payload (v1, v2)


@dataclass(frozen=True)
class MessageTable:
    """msgid -> (name, CRC_EXTRA): what mavlink_get_msg_entry() finds (lengths do not
    matter for framing, see the module docstring)."""

    entries: Mapping[int, tuple[str, int]]

    @classmethod
    def of(cls, *dialects: Any) -> "MessageTable":
        """The messages of pymavlink dialect modules; the first dialect naming an id wins."""
        entries: dict[int, tuple[str, int]] = {}
        for dialect in dialects:
            for mid, msg in dialect.mavlink_map.items():
                entries.setdefault(mid, (msg.msgname, msg.crc_extra))
        return cls(entries)

    def name(self, msgid: int) -> str | None:
        entry = self.entries.get(msgid)
        return entry[0] if entry is not None else None


DIALECT_TABLE = MessageTable.of(default_dialect())   # our own dialect, as the frame fuzzer uses it
_frame = tuple.__new__   # ParsedFrame without its Python-level __new__ (the parser's hot loop)

class ParsedFrame(NamedTuple):
    """A frame the parser completed (or, from `awaiting_signature`, is completing).

    Offsets are positions in the whole stream fed so far (the first byte ever fed is 0).
    `start` is the start byte (for a mavlink_parse_char restart: the byte that ended the
    bad frame before), `end` is one past the last byte the frame took, `crc` the first
    checksum byte (the second is `crc + 1`)."""

    start: int
    end: int
    crc: int
    msgid: int
    result: int          # OK, BAD_CRC or BAD_SIGNATURE; OK for a good frame awaiting its signature
    v1: bool
    signed: bool
    sysid: int
    compid: int

    @property
    def ok(self) -> bool:
        return self.result == OK

    def describe(self) -> str:
        return (f"msgid {self.msgid} from {self.sysid}/{self.compid} at {self.start}..{self.end} "
                f"({'v1' if self.v1 else 'v2'}{', signed' if self.signed else ''}): "
                f"{RESULT_NAMES[self.result]}")


class CParser:
    """One channel of the C parser (persistent across `feed` calls). `copy()` is cheap."""

    __slots__ = ("variant", "table", "restart", "offset", "diverged", "_buf", "_start", "_v1",
                 "_secret", "accept_unsigned", "_wall_clock", "_timestamp", "_streams")

    def __init__(self, variant: str = PARSE_CHAR, *, table: MessageTable = DIALECT_TABLE,
                 key: bytes | None = None, accept_unsigned: bool = False,
                 wall_clock: Callable[[], float] | None = None) -> None:
        if variant not in VARIANTS:
            raise ValueError(f"unknown C parser variant {variant!r} (known: {', '.join(VARIANTS)})")
        self.variant = variant
        self.table = table
        self.restart = variant == PARSE_CHAR       # mavlink_parse_char's wrapper
        self.offset = 0             # stream bytes fed so far
        self.diverged = False       # did the last feed meet a frame the variants part on
                                    # (a bad one ending on 0xFD, a signed one with a bad checksum)?
        self._buf = b""             # the frame in progress, from its start byte
        self._start = 0             # its stream offset
        self._v1 = False            # MAVLINK_STATUS_FLAG_IN_MAVLINK1
        self._secret = key          # status->signing->secret_key (None: status->signing NULL)
        self.accept_unsigned = accept_unsigned
        self._wall_clock = wall_clock
        self._timestamp = 0         # status->signing->timestamp
        self._streams: dict[tuple[int, int, int], int] = {}

    def copy(self) -> "CParser":
        new = CParser.__new__(CParser)
        new.variant, new.table, new.restart = self.variant, self.table, self.restart
        new.offset, new._buf, new._start, new._v1 = self.offset, self._buf, self._start, self._v1
        new.diverged = False
        new._secret, new.accept_unsigned, new._wall_clock = self._secret, self.accept_unsigned, self._wall_clock
        new._timestamp = self._timestamp
        new._streams = dict(self._streams) if self._streams else {}
        return new

    def shifted(self, delta: int) -> "CParser":
        """A copy, as if `delta` more bytes had been fed before everything (stream offsets
        move by `delta`; the state does not)."""
        new = self.copy()
        new.offset += delta
        new._start += delta
        return new

    def resume_key(self) -> tuple:
        """What parsing the next bytes depends on, stream offsets aside, for parsers of one
        table and configuration: equal keys parse the same bytes alike (at offsets apart by
        the difference of their `offset`s: see `shifted`)."""
        buf = self._buf
        return (buf, self._v1 if buf else None, self._timestamp,
                frozenset(self._streams.items()) if self._streams else None)

    def same_state(self, other: "CParser") -> bool:
        """Would `other` parse the next bytes as this one does, but for its variant? (IDLE, the
        last frame's start and v1 flag are left over: the next start byte sets both.)"""
        return (self.offset == other.offset and self._buf == other._buf
                and (not self._buf or (self._start == other._start and self._v1 == other._v1))
                and self.table is other.table and self._secret == other._secret
                and self.accept_unsigned == other.accept_unsigned and self._timestamp == other._timestamp
                and self._streams == other._streams)

    @property
    def idle(self) -> bool:
        """In MAVLINK_PARSE_STATE_IDLE: the next byte can only start a frame."""
        return not self._buf

    @property
    def frame_start(self) -> int | None:
        """The stream offset of the frame in progress, or None when idle (a stream framer
        keeps the bytes from there on, reference_impl/net/stream_framer.py)."""
        return self._start if self._buf else None

    @property
    def takes_any_signature(self) -> bool:
        """Would a good-checksum signed frame be accepted whatever its 13 signature bytes?"""
        return self._secret is None or self.accept_unsigned

    # --- feeding ----------------------------------------------------------------------------
    def feed(self, data: bytes, variant: str | None = None) -> list[ParsedFrame]:
        """Parse `data` (the next bytes of the link); every frame completed in it, in order.
        `variant` parses these bytes as another variant would (the state is the same for
        both until a frame they part on: see `diverged`)."""
        restart = self.restart if variant is None else variant == PARSE_CHAR
        if self._secret is not None and self._wall_clock is not None:
            now = signing_timestamp(self._wall_clock())
            if now > self._timestamp:
                self._timestamp = now
        if self._buf:
            buf = self._buf + data
            base = self._start
            in_frame = True
        else:
            buf = bytes(data)
            base = self.offset
            in_frame = False
        self.offset += len(data)
        self.diverged = False
        n = len(buf)
        out: list[ParsedFrame] = []
        i = start = 0
        v1 = self._v1
        entries = self.table.entries
        while True:
            if not in_frame:
                a = buf.find(STX_V2, i)
                b = buf.find(STX_V1, i)
                if a < 0:
                    if b < 0:
                        break
                    start = b
                elif 0 <= b < a:
                    start = b
                else:
                    start = a
                v1 = buf[start] == STX_V1
                in_frame = True
            p = start + 1                       # the length byte
            if n <= p:
                break
            if not v1:
                if n <= p + 1:
                    break
                iflags = buf[p + 1]
                if iflags & ~IFLAG_SIGNED:      # unknown incompat flag: IDLE, rescan after it
                    in_frame = False
                    i = p + 2
                    continue
            else:
                iflags = 0
            crc_at = p + (5 if v1 else 9) + buf[p]
            if n < crc_at + 2:
                break
            if v1:
                msgid = buf[p + 4]
            else:
                msgid = buf[p + 6] | buf[p + 7] << 8 | buf[p + 8] << 16
            entry = entries.get(msgid)
            crc_ok = entry is not None and \
                crc16(buf[p:crc_at], entry[1]) == buf[crc_at] | buf[crc_at + 1] << 8
            signed = bool(iflags & IFLAG_SIGNED)
            end = crc_at + 2
            if signed and not crc_ok:
                self.diverged = True            # the two variants part here
            if signed and (crc_ok or not restart):
                end += SIGNATURE_BLOCK_LEN
                if n < end:
                    break                       # SIGNATURE_WAIT[_BAD_CRC]
                sig_ok = self._signature_ok(buf[start:end])
                if not sig_ok and self.accept_unsigned:
                    sig_ok = True
                result = BAD_CRC if not crc_ok else OK if sig_ok else BAD_SIGNATURE
            else:
                result = OK if crc_ok else BAD_CRC
                if result == OK and self._secret is not None and not signed and not self.accept_unsigned:
                    result = BAD_SIGNATURE
            out.append(_frame(ParsedFrame, (base + start, base + end, base + crc_at, msgid, result, v1, signed,
                                            buf[p + 2 if v1 else p + 4], buf[p + 3 if v1 else p + 5])))
            if result != OK and buf[end - 1] == STX_V2:
                self.diverged = True
                if restart:
                    start = end - 1             # GOT_STX, the v1 flag kept
                    continue
            in_frame = False
            i = end
        if in_frame:
            self._buf = buf[start:]
            self._start = base + start
        else:
            self._buf = b""
        self._v1 = v1
        return out

    def _signature_ok(self, frame: bytes) -> bool:
        """mavlink_signature_check(): True without a key (status->signing NULL)."""
        secret = self._secret
        if secret is None:
            return True
        block = frame[-SIGNATURE_BLOCK_LEN:]
        if hashlib.sha256(secret + frame[:-6]).digest()[:6] != block[7:]:
            return False
        link_id = block[0]
        stamp = int.from_bytes(block[1:7], "little")
        stream = (frame[5], frame[6], link_id)
        last = self._streams.get(stream)
        if last is None:
            if len(self._streams) >= MAX_SIGNING_STREAMS:
                return False
            if stamp + SIGNING_TIMESTAMP_LIMIT < self._timestamp:
                return False
        elif stamp <= last:
            return False
        self._streams[stream] = stamp
        if stamp > self._timestamp:
            self._timestamp = stamp
        return True

    # --- the frame in progress --------------------------------------------------------------
    def _pending_header(self) -> tuple[int, int, bool, int] | None:
        """(crc_at, msgid, signed, iflags) of the frame in progress once its header and
        payload are in, relative to its start byte; None before that."""
        buf = self._buf
        if not buf:
            return None
        v1 = self._v1
        hdr = _HEADER[v1]
        if len(buf) < 1 + hdr:
            return None
        crc_at = 1 + hdr + buf[1]
        if len(buf) < crc_at:
            return None
        msgid = buf[5] if v1 else buf[7] | buf[8] << 8 | buf[9] << 16
        iflags = 0 if v1 else buf[2]
        return crc_at, msgid, bool(iflags & IFLAG_SIGNED), iflags

    def pending(self) -> ParsedFrame | None:
        """The frame in SIGNATURE_WAIT[_BAD_CRC], if that is where the parser is: its
        checksum is in, it waits for signature bytes. `result` is OK if the checksum was
        good (without a key, or with `accept_unsigned`, the next bytes then complete it as
        OK whatever they are: see `takes_any_signature`), BAD_CRC if not; `end` is where it
        will end."""
        buf = self._buf
        if self._v1 or len(buf) < 12 or not buf[2] & IFLAG_SIGNED:
            return None                 # no signed frame with its checksum in
        head = self._pending_header()
        if head is None:
            return None
        crc_at, msgid, signed, _ = head
        if not signed or len(buf) < crc_at + 2:
            return None
        entry = self.table.entries.get(msgid)
        good = entry is not None and crc16(buf[1:crc_at], entry[1]) == buf[crc_at] | buf[crc_at + 1] << 8
        s = self._start
        return ParsedFrame(s, s + crc_at + 2 + SIGNATURE_BLOCK_LEN, s + crc_at, msgid, OK if good else BAD_CRC,
                           False, True, buf[5], buf[6])

    def awaiting_signature(self) -> ParsedFrame | None:
        """The pending frame the next bytes will complete as OK whatever they are (a good
        checksum, and no key to check the signature with), else None."""
        frame = self.pending()
        return frame if frame is not None and frame.ok and self.takes_any_signature else None

    def c_state(self) -> str:
        """The MAVLINK_PARSE_STATE_* name the C parser is in now (IDLE for UNINIT too)."""
        buf = self._buf
        k = len(buf)
        if k == 0:
            return "IDLE"
        if k == 1:
            return "GOT_STX"
        v1 = self._v1
        if v1:
            before = {2: "GOT_COMPAT_FLAGS", 3: "GOT_SEQ", 4: "GOT_SYSID", 5: "GOT_COMPID"}
        else:
            before = {2: "GOT_LENGTH", 3: "GOT_INCOMPAT_FLAGS", 4: "GOT_COMPAT_FLAGS", 5: "GOT_SEQ",
                      6: "GOT_SYSID", 7: "GOT_COMPID", 8: "GOT_MSGID1", 9: "GOT_MSGID2"}
        if k in before:
            return before[k]
        crc_at = 1 + _HEADER[v1] + buf[1]
        if k < crc_at:
            return "GOT_MSGID3"
        if k == crc_at:
            return "GOT_PAYLOAD"
        msgid = buf[5] if v1 else buf[7] | buf[8] << 8 | buf[9] << 16
        entry = self.table.entries.get(msgid)
        crc = crc16(buf[1:crc_at], entry[1]) if entry is not None else None
        if k == crc_at + 1:
            return "GOT_CRC1" if crc is not None and crc & 0xFF == buf[crc_at] else "GOT_BAD_CRC1"
        good = crc is not None and crc == buf[crc_at] | buf[crc_at + 1] << 8
        return "SIGNATURE_WAIT" if good else "SIGNATURE_WAIT_BAD_CRC"
