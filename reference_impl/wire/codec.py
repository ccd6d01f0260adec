"""Frame codec: MAVLink 1/2 framing and MAVLink 2 signing over a pymavlink dialect.

pymavlink does the payload layout, CRC_EXTRA and the signature arithmetic. This module adds
what a test tool needs on top of it:
- datagram splitting that never raises: garbage, truncation, bad CRC, bad length and
  unknown incompat flags each come back as a `DecodeError` value, and are counted;
- a signature *verdict* per frame instead of a silent drop, so the layer above decides
  what an unsigned or badly signed frame means (handover gating needs to see them);
- a bad signature never moves the stream's timestamp (pymavlink records it before it
  compares signatures, which would let a forged frame lock out the real sender);
- with a `Keyring`, one key per system id: a signed frame is checked against the key of the
  system it claims, and an INVALID verdict says why (`SignatureFault`: bad signature,
  replayed, unknown key). Each system's key keeps its own replay state, per (system,
  component, link id) stream as the signing guide says, and its own local timestamp for the
  one-minute rule, so one GCS whose clock runs ahead cannot make another's frames look stale;
- time from an injected wall clock, so signed traffic is deterministic in virtual time.
"""

from __future__ import annotations

import inspect
import re
import struct
import time
from typing import Any, Callable, Iterable, Iterator

from .checksum import crc16
from .frame import DecodeError, Frame, SignatureFault, SignatureVerdict
from .signing import NEW_STREAM_WINDOW, Keyring, SigningKey, signing_timestamp

MAGIC_V1 = 0xFE
MAGIC_V2 = 0xFD
IFLAG_SIGNED = 0x01
V1_OVERHEAD = 8          # magic, len, seq, sys, comp, msgid + 2 CRC
V2_OVERHEAD = 12         # magic, len, iflags, cflags, seq, sys, comp, msgid*3 + 2 CRC
SIGNATURE_LEN = 13

WallClock = Callable[[], float]


def default_dialect() -> Any:
    """The project's own generated dialect module."""
    from .dialect import mavlink

    return mavlink


class FrameEncoder:
    """Encodes messages as one sender (system, component), with its own sequence counter."""

    def __init__(
        self,
        system: int,
        component: int,
        *,
        dialect: Any = None,
        version: int = 2,
        signing: SigningKey | None = None,
        wall_clock: WallClock = time.time,
    ) -> None:
        if version not in (1, 2):
            raise ValueError(f"MAVLink version must be 1 or 2, got {version}")
        self.dialect = dialect or default_dialect()
        self.version = version
        self._wall_clock = wall_clock
        self._mav = self.dialect.MAVLink(None, system, component)
        self.frames_sent = 0
        self.set_signing(signing)

    @property
    def system(self) -> int:
        return self._mav.srcSystem

    @property
    def component(self) -> int:
        return self._mav.srcComponent

    def set_signing(self, key: SigningKey | None) -> None:
        sig = self._mav.signing
        if key is None:
            sig.secret_key, sig.sign_outgoing = None, False
            return
        sig.secret_key, sig.link_id, sig.sign_outgoing = key.secret, key.link_id, True

    def encode(self, msg: Any, *, version: int | None = None) -> bytes:
        """The frame bytes for `msg`; advances this sender's sequence number."""
        version = version or self.version
        mav = self._mav
        if version == 1:
            msg_id = type(msg).id   # the class's: STATUSTEXT's own `id` field shadows it on the instance
            if msg_id > 255:
                raise ValueError(f"{msg.get_type()} (id {msg_id}) cannot be sent as MAVLink 1")
            if mav.signing.sign_outgoing:
                raise ValueError("MAVLink 1 frames cannot be signed")
        elif mav.signing.sign_outgoing:
            now = signing_timestamp(self._wall_clock())
            if now > mav.signing.timestamp:
                mav.signing.timestamp = now
        data = msg.pack(mav, force_mavlink1=(version == 1))
        if version == 1:
            data = self._without_extensions(msg, data)
        mav.seq = (mav.seq + 1) & 0xFF
        self.frames_sent += 1
        return data if type(data) is bytes else bytes(data)

    def _without_extensions(self, msg: Any, frame: bytes) -> bytes:
        """MAVLink 1 carries no extension fields; pymavlink's v1 pack keeps them, so cut them
        off and recompute the checksum (seed 001: extensions are a MAVLink 2 feature)."""
        base = base_payload_length(type(msg))
        if frame[1] == base:
            return frame
        head = bytes([MAGIC_V1, base]) + frame[2:6]
        payload = frame[6:6 + base]
        crc = self.dialect.x25crc(head[1:] + payload + bytes([msg.crc_extra])).crc
        return head + payload + crc.to_bytes(2, "little")


class FrameDecoder:
    """Splits datagrams into frames and decodes them; bad bytes become `DecodeError`s."""

    def __init__(
        self,
        *,
        dialect: Any = None,
        signing: SigningKey | Keyring | None = None,
        wall_clock: WallClock = time.time,
    ) -> None:
        self.dialect = dialect or default_dialect()
        self._wall_clock = wall_clock
        self._mav = self.dialect.MAVLink(None, 0, 0)
        self._plain = self._mav  # the keyless decoder, used while signing is off
        self._checker = self.dialect.MAVLink(None, 0, 0)   # signature-only checks (see _genuine)
        self._keyring: Keyring | None = None
        self._by_system: dict[int, Any] = {}   # with a keyring: one keyed decoder per system id
        self._unknown = self.dialect.MAVLink_unknown
        self._ignore_crc = bool(getattr(self.dialect, "MAVLINK_IGNORE_CRC", 0))
        self.frames = 0
        self.errors = 0
        self.bad_signatures = 0
        self.set_signing(signing)

    def set_signing(self, key: SigningKey | Keyring | None) -> None:
        """One key for every sender, a keyring (a key per system id), or none (signed frames
        are then UNCHECKED). Replay state starts afresh."""
        self._keyring, self._by_system = None, {}
        if key is None:
            self._mav = self._plain
        elif isinstance(key, Keyring):
            self._mav, self._keyring = self._plain, key
        else:
            self._mav = self._keyed(key)

    def _keyed(self, key: SigningKey) -> Any:
        mav = self.dialect.MAVLink(None, 0, 0)
        mav.signing.secret_key = key.secret
        # Accept everything at pymavlink's level; the verdict is ours to give.
        mav.signing.allow_unsigned_callback = _accept_all
        return mav

    @property
    def signing_enabled(self) -> bool:
        return self._keyring is not None or self._mav.signing.secret_key is not None

    @property
    def keyring(self) -> Keyring | None:
        return self._keyring

    def feed(self, data: bytes) -> list[Frame | DecodeError]:
        """Every frame and every error in one datagram, in order."""
        n = len(data)
        if n > 2 and data[0] == MAGIC_V2 and not data[2] & ~IFLAG_SIGNED:
            # The usual UDP datagram: exactly one well-formed MAVLink 2 frame.
            if data[1] + V2_OVERHEAD + (SIGNATURE_LEN if data[2] & IFLAG_SIGNED else 0) == n:
                return [self._decode_one(data, data[2])]
        out: list[Frame | DecodeError] = []
        for start, end, iflags in _pieces(data):
            if iflags.__class__ is str:
                out.append(self._error(iflags, data[start:end]))
            elif iflags & ~IFLAG_SIGNED:
                out.append(self._error(f"unknown incompat_flags 0x{iflags:02x}", data[start:end]))
            else:
                out.append(self._decode_one(data[start:end], iflags))
        return out

    def accepted(self, data: bytes) -> list[tuple[int, int, int, SignatureVerdict]]:
        """(offset, length, msgid, verdict) of each frame `feed` would return as a `Frame`, with
        the same effect on the signing state, but no message built: what a caller that only
        asks which frames a receiver accepts needs (the frame fuzzer's admission rule decodes
        every datagram it sends). Frames split exactly as in `feed`, and a frame whose msgid
        and checksum pass is one pymavlink decodes (it pads or cuts the payload to the
        message's size; the generated constructors take any value: see
        tests/fuzz/test_frames_admission_decoder.py). `frames` and `errors` are not counted."""
        out: list[tuple[int, int, int, SignatureVerdict]] = []
        keyless = self._keyring is None and self._mav.signing.secret_key is None
        for i, end, iflags in _pieces(data):
            if iflags.__class__ is str or iflags & ~IFLAG_SIGNED:
                continue
            chunk = data[i:end]
            if keyless:                                 # no signing state: verdict by the flag
                msgid = self._check(chunk, iflags)
                if msgid.__class__ is int:
                    out.append((i, end - i, msgid, UNCHECKED if iflags else UNSIGNED))
                continue
            signed = bool(iflags & IFLAG_SIGNED)
            mav, stream_key, saved_ts, stale, no_key = self._signing_context(chunk, signed)
            msgid = self._check(chunk, iflags)
            if msgid.__class__ is int:
                sig_ok = stream_key is not None and bool(mav.check_signature(chunk, chunk[5], chunk[6]))
                verdict, _ = self._verdict(mav, chunk, signed, no_key, stream_key, saved_ts, stale, sig_ok)
                out.append((i, end - i, msgid, verdict))
        return out

    def _decode_one(self, chunk: bytes, iflags: int) -> Frame | DecodeError:
        signed = bool(iflags & IFLAG_SIGNED)
        if not signed and self._mav is self._plain:
            # no key checks an unsigned frame here (none, or a keyring: keys for signed frames
            # only), so there is no signing state to read or keep: most frames
            msg = self._pymavlink(self._plain, chunk)
            if msg.__class__ is DecodeError:
                return msg
            self.frames += 1
            h = msg._header
            return Frame(msg, chunk, h.srcSystem, h.srcComponent)
        mav, stream_key, saved_ts, stale, no_key = self._signing_context(chunk, signed)
        msg = self._pymavlink(mav, chunk)
        if msg.__class__ is DecodeError:
            return msg
        verdict, fault = self._verdict(mav, chunk, signed, no_key, stream_key, saved_ts, stale, msg._signed)
        self.frames += 1
        h = msg._header
        return Frame(msg, chunk, h.srcSystem, h.srcComponent, verdict, chunk[-13] if signed else None, fault)

    def _pymavlink(self, mav: Any, chunk: bytes) -> Any:
        """`mav`'s decode of a framed chunk, or the DecodeError saying why not. pymavlink
        refuses an unknown msgid (MAVLink_unknown) and a bad checksum before any state of
        its own changes, so `accepted`'s checks (`_check`) are not repeated here."""
        try:
            msg = mav.decode(bytearray(chunk))
        except Exception as exc:  # pymavlink raises MAVError, struct.error, ValueError...
            return self._error(_reason(exc), chunk)
        if isinstance(msg, self._unknown):
            # pymavlink's MAVLink_unknown carries id -2 in its header; read the id off the wire.
            return self._error(f"unknown message id {_msgid(chunk)}", chunk)
        return msg

    def _signing_context(self, chunk: bytes, signed: bool) -> tuple[Any, Any, int | None, bool, bool]:
        """(pymavlink decoder, stream key, its saved timestamp, stale, no key) for a frame,
        before pymavlink sees it; moves the decoder's own timestamp to now."""
        mav = self._mav
        stream_key = saved_ts = None
        stale = no_key = False
        if signed and self._keyring is not None:
            mav = self._by_system.get(chunk[5])
            if mav is None:
                key = self._keyring.key_for(chunk[5])
                if key is None:
                    mav, no_key = self._plain, True
                else:
                    mav = self._by_system[chunk[5]] = self._keyed(key)
        if signed and mav.signing.secret_key is not None:
            # (link_id, sys, comp): pymavlink's per-link timestamp key.
            stream_key = (chunk[-13], chunk[5], chunk[6])
            saved_ts = mav.signing.stream_timestamps.get(stream_key)
            now = signing_timestamp(self._wall_clock())
            if now > mav.signing.timestamp:
                mav.signing.timestamp = now
            # pymavlink's timestamp rules, read ahead so a refusal can say "replayed"
            ts = int.from_bytes(chunk[-12:-6], "little")
            stale = ts <= saved_ts if saved_ts is not None else ts + NEW_STREAM_WINDOW < mav.signing.timestamp
        return mav, stream_key, saved_ts, stale, no_key

    def _check(self, chunk: bytes, iflags: int) -> int | str:
        """The msgid of a framed chunk (known incompat flags) whose msgid and checksum pass,
        else why not, as pymavlink's decode says it (it checks them first, before any state
        of its own changes)."""
        msgid = _msgid(chunk)
        crc_at = len(chunk) - (2 + SIGNATURE_LEN if iflags & IFLAG_SIGNED else 2)
        cls = self.dialect.mavlink_map.get(msgid)
        if cls is None:
            return f"unknown message id {msgid}"
        if self._ignore_crc:
            return msgid
        got = chunk[crc_at] | chunk[crc_at + 1] << 8
        good = crc16(chunk[1:crc_at], cls.crc_extra)
        if got != good:
            return f"invalid MAVLink CRC in msgID {msgid} 0x{got:04x} should be 0x{good:04x}"
        return msgid

    def _verdict(self, mav: Any, chunk: bytes, signed: bool, no_key: bool, stream_key: Any,
                 saved_ts: int | None, stale: bool, sig_ok: bool) -> tuple[SignatureVerdict, SignatureFault | None]:
        """The signature verdict of a frame pymavlink took; a refused signature's stream
        timestamp is put back (pymavlink records it before it compares signatures)."""
        if not signed:
            return SignatureVerdict.UNSIGNED, None
        if no_key:
            self.bad_signatures += 1
            return SignatureVerdict.INVALID, SignatureFault.UNKNOWN_KEY
        if stream_key is None:
            return SignatureVerdict.UNCHECKED, None
        if sig_ok:
            return SignatureVerdict.VALID, None
        self.bad_signatures += 1
        if saved_ts is None:
            mav.signing.stream_timestamps.pop(stream_key, None)
        else:
            mav.signing.stream_timestamps[stream_key] = saved_ts
        return SignatureVerdict.INVALID, (SignatureFault.REPLAYED if stale and self._genuine(mav, chunk)
                                          else SignatureFault.BAD_SIGNATURE)

    def _genuine(self, mav: Any, chunk: bytes) -> bool:
        """Whether the signature itself is right for `mav`'s key, whatever its timestamp: the
        difference between a replayed frame and a forged one. pymavlink's own check, run on a
        scratch decoder with no stream history (only reached for refused frames)."""
        checker = self._checker.signing
        checker.secret_key, checker.timestamp = mav.signing.secret_key, 0
        checker.stream_timestamps.clear()
        return bool(self._checker.check_signature(bytearray(chunk), chunk[5], chunk[6]))

    def _error(self, reason: str, raw: bytes) -> DecodeError:
        self.errors += 1
        return DecodeError(reason, bytes(raw))


UNSIGNED, UNCHECKED = SignatureVerdict.UNSIGNED, SignatureVerdict.UNCHECKED


def _pieces(data: bytes) -> Iterator[tuple[int, int, int | str]]:
    """A datagram cut as a MAVLink receiver frames it: (start, end, incompat flags) for each
    frame by its header's length, or (start, end, why) for bytes no frame holds (a run between
    frames, a truncated header or frame at the end). What `feed` and `accepted` both read."""
    n = len(data)
    i = 0
    while i < n:
        magic = data[i]
        if magic != MAGIC_V2 and magic != MAGIC_V1:
            j = _next_start(data, i + 1)
            yield i, j, "bytes outside any frame"
            i = j
            continue
        if i + 1 >= n or (magic == MAGIC_V2 and i + 2 >= n):
            yield i, n, "truncated frame header"
            return
        plen = data[i + 1]
        if magic == MAGIC_V2:
            iflags = data[i + 2]
            total = plen + V2_OVERHEAD + (SIGNATURE_LEN if iflags & IFLAG_SIGNED else 0)
        else:
            iflags = 0
            total = plen + V1_OVERHEAD
        if i + total > n:
            yield i, n, f"truncated frame: header says {total} bytes, {n - i} remain"
            return
        yield i, i + total, iflags
        i += total


def _msgid(chunk: bytes) -> int:
    """The message id in a frame's header."""
    return chunk[5] if chunk[0] == MAGIC_V1 else chunk[7] | chunk[8] << 8 | chunk[9] << 16


def _next_start(data: bytes, i: int) -> int:
    """Where the next start byte (0xFD, 0xFE) at or after `i` is; len(data) if none."""
    a = data.find(b"\xfd", i)
    b = data.find(b"\xfe", i)
    if a < 0:
        return b if b >= 0 else len(data)
    return a if b < 0 or a < b else b


_BASE_LENGTHS: dict[type, int] = {}


def base_payload_length(cls: type) -> int:
    """Payload bytes of a message's base (non-extension) fields.

    Generated classes do not mark extensions, but their constructors give every extension
    field a default and no base field one; and on the wire the base fields come first
    (size-sorted) with the extensions after them in order, one format token per field.
    """
    found = _BASE_LENGTHS.get(cls)
    if found is None:
        params = list(inspect.signature(cls.__init__).parameters.values())[1:]
        n_base = sum(1 for p in params if p.default is inspect.Parameter.empty)
        tokens = re.findall(r"\d*[a-zA-Z?]", cls.unpacker.format.lstrip("<"))
        found = _BASE_LENGTHS[cls] = struct.calcsize("<" + "".join(tokens[:n_base]))
    return found


def _accept_all(_mav: Any, _msgid: int) -> bool:
    return True


def _reason(exc: Exception) -> str:
    text = getattr(exc, "message", None) or str(exc) or type(exc).__name__
    return text.splitlines()[0][:200]


def frames_only(items: Iterable[Frame | DecodeError]) -> list[Frame]:
    return [f for f in items if isinstance(f, Frame)]
