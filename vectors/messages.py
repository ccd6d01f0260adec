"""Message vectors: fixed frames for every message of a dialect, valid and deliberately broken.

Per message (the dialect rule: dialect_info.py), in this order (docs/vectors.md lists each):
- valid: all fields zero (a 1-byte payload: MAVLink 2 never truncates below one byte);
  typical values with the extensions zero (truncated payload) and set; MAVLink 1 (ids up to
  255, base fields only); MAVLink 2 signed with the published test key; and field edges:
  every integer at its max and min, floats at +-FLT_MAX, NaN, +-inf, the smallest
  subnormal and -0.0, latitudes/longitudes at +-90/+-180 degrees;
- invalid, each labelled with the error a decoder must report: a bad checksum, a length
  byte one more than the frame holds (bad_length) or one less (the checksum is then read
  from the payload: bad_crc), a MAVLink 1 frame whose payload is shorter than the message
  with a correct checksum (bad_length: MAVLink 1 has no truncation), a signature by
  another key and a tampered signature (bad_signature);
then, once per dialect, unknown message ids (MAVLink 1 and 2) and an unknown incompat flag.

Everything is drawn from `random.Random(stable_seed(seed, vector id))`, so one vector's
values never depend on another's, and regenerating gives the same bytes.
"""

from __future__ import annotations

import hashlib
import math
import random
import string
import struct
from typing import Any, Callable, Iterator

from mavconform.reference_impl.net.clock import DEFAULT_WALL_EPOCH
from mavconform.reference_impl.net.sim import stable_seed
from mavconform.reference_impl.wire.codec import MAGIC_V1, MAGIC_V2, FrameEncoder
from mavconform.reference_impl.wire.signing import SigningKey, signing_timestamp

from .dialect_info import INT_RANGES, DialectInfo, FieldInfo, MessageInfo
from .fields import from_json, to_json

# The published test key (docs/vectors.md): SHA-256 of this ASCII passphrase, as MAVProxy's
# `signing setup` makes a key from a passphrase.
TEST_KEY_PASSPHRASE = "mavconform golden vectors"
TEST_KEY = hashlib.sha256(TEST_KEY_PASSPHRASE.encode("ascii")).digest()
WRONG_KEY_PASSPHRASE = "not the golden key"
WRONG_KEY = hashlib.sha256(WRONG_KEY_PASSPHRASE.encode("ascii")).digest()
LINK_ID = 1
# Signed vectors' timestamps: this one (2026-01-01T00:00:00Z), plus one per signed vector in
# file order, so the whole file read as one stream is also in timestamp order.
BASE_TIMESTAMP = signing_timestamp(DEFAULT_WALL_EPOCH)
DEFAULT_SEED = 0

FLT_MAX = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]
FLT_TRUE_MIN = struct.unpack("<f", b"\x01\x00\x00\x00")[0]
DBL_MAX = 1.7976931348623157e308
DBL_TRUE_MIN = 5e-324
LAT_MAX, LON_MAX = 900_000_000, 1_800_000_000     # degE7
_TEXT = string.ascii_letters + string.digits + " .:-_"

# the errors a decoder must report (docs/vectors.md)
ERRORS = ("bad_crc", "bad_length", "unknown_msgid", "bad_signature", "unknown_incompat_flags")


def generate(dialect: DialectInfo, seed: int = DEFAULT_SEED) -> list[dict[str, Any]]:
    """Every message vector of `dialect`, in file order."""
    out: list[dict[str, Any]] = []
    for info in dialect.messages:
        out.extend(_message_vectors(dialect, info, seed))
    out.extend(_dialect_vectors(dialect, seed))
    signed = 0
    for index, vec in enumerate(out):   # header seq and signing timestamps follow file order
        vec["header"]["seq"] = index & 0xFF
        if vec["signed"]:
            vec["signature"]["timestamp"] = BASE_TIMESTAMP + signed
            signed += 1
        vec["hex"] = vec.pop("_build")(vec).hex()
    return out


# --- valid vectors -----------------------------------------------------------------------

Values = Callable[[FieldInfo, random.Random], Any]


def _message_vectors(dialect: DialectInfo, info: MessageInfo, seed: int) -> Iterator[dict[str, Any]]:
    name = info.name
    floats = any(f.is_float for f in info.fields)
    signed_ints = any(INT_RANGES.get(f.type, (0, 0))[0] < 0 for f in info.fields)
    positions = _positions(info)
    ext = info.has_extensions
    plans: list[tuple[str, str, Values, bool]] = [   # variant, description, values, extensions set
        ("v2-zero", "every field zero: the payload truncates to its first byte", _zero, False),
        ("v2-ext-zero" if ext else "v2-typical",
         "typical values, extension fields zero (truncated payload)" if ext else "typical values",
         _typical, False),
    ]
    if ext:
        plans.append(("v2-ext-set", "typical values, extension fields set", _typical, True))
    plans.append(("v2-max", "every integer at its maximum, floats at +FLT_MAX, strings full (no NUL)",
                  _maximum, True))
    if floats or signed_ints:
        plans.append(("v2-min", "every integer at its minimum, floats at -FLT_MAX", _minimum, True))
    if floats:
        plans += [
            ("v2-nan", "floats NaN (0x7fc00000), other fields typical", _float_edge(math.nan), True),
            ("v2-inf", "floats +infinity, other fields typical", _float_edge(math.inf), True),
            ("v2-ninf", "floats -infinity, other fields typical", _float_edge(-math.inf), True),
            ("v2-subnormal", "floats at the smallest subnormal, other fields typical", _float_edge(None), True),
            ("v2-negzero", "floats -0.0 (a non-zero byte: no truncation), other fields typical",
             _float_edge(-0.0), True),
        ]
    if positions:
        plans += [
            ("v2-latlon-max", "latitude +90 and longitude +180 degrees (degE7), other fields typical",
             _position_edge(positions, 1), True),
            ("v2-latlon-min", "latitude -90 and longitude -180 degrees (degE7), other fields typical",
             _position_edge(positions, -1), True),
        ]
    typical_id = f"{name}/{'v2-ext-set' if ext else 'v2-typical'}"
    for variant, description, values, with_ext in plans:
        vid = f"{name}/{variant}"
        fields = _values(info, values, with_ext, _rng(seed, vid))
        yield _valid(dialect, info, vid, description, fields, _rng(seed, vid, "header"), 2)
    if info.fits_v1:
        vid = f"{name}/v1"
        fields = _values(info, _typical, False, _rng(seed, vid))
        yield _valid(dialect, info, vid, "MAVLink 1: base fields only (extensions are a MAVLink 2 feature)",
                     fields, _rng(seed, vid, "header"), 1)
    vid = f"{name}/v2-signed"
    fields = _values(info, _typical, True, _rng(seed, vid))
    signed = _valid(dialect, info, vid, f"MAVLink 2 signed with the test key, link id {LINK_ID}",
                    fields, _rng(seed, vid, "header"), 2, signed=True)
    yield signed
    yield from _invalid_vectors(dialect, info, seed, typical_id, signed)


def _valid(dialect: DialectInfo, info: MessageInfo, vid: str, description: str, fields: dict[str, Any],
           rng: random.Random, version: int, *, signed: bool = False, key: bytes = TEST_KEY) -> dict[str, Any]:
    header = {"sysid": rng.randint(1, 255), "compid": rng.randint(0, 255), "seq": 0}

    def build(vec: dict[str, Any]) -> bytes:
        sig = vec["signature"]
        return encode(dialect, info, fields, vec["header"], version,
                      key=key if sig else None, link_id=sig["link_id"] if sig else 0,
                      timestamp=sig["timestamp"] if sig else 0)
    return {"id": vid, "description": description, "message": info.name, "msgid": info.id,
            "version": version, "signed": signed, "header": header,
            "signature": {"link_id": LINK_ID, "timestamp": 0} if signed else None,
            "fields": fields, "expected_error": None, "_build": build}


def encode(dialect: DialectInfo, info: MessageInfo, fields: dict[str, Any], header: dict[str, int],
           version: int, *, key: bytes | None = None, link_id: int = 0, timestamp: int = 0) -> bytes:
    """One frame with our codec, every header byte pinned (also how `verify` re-encodes)."""
    msg = info.cls(**{f.name: from_json(fields[f.name], f) for f in info.fields})
    signing = SigningKey(key, link_id) if key is not None else None
    enc = FrameEncoder(header["sysid"], header["compid"], dialect=dialect.module, version=version,
                       signing=signing, wall_clock=_epoch)
    # FrameEncoder numbers frames itself and stamps signatures from its clock; a vector pins both.
    enc._mav.seq = header["seq"]
    enc._mav.signing.timestamp = timestamp
    return enc.encode(msg)


def _epoch() -> float:
    return 0.0   # signing_timestamp(0) is 0: never newer than the pinned timestamp


def _values(info: MessageInfo, values: Values, with_ext: bool, rng: random.Random) -> dict[str, Any]:
    out = {}
    for f in info.fields:
        if f.const_value is not None:
            value = f.const_value      # uint8_t_mavlink_version: encoders write the dialect's version
        elif f.extension and not with_ext:
            value = _zero(f, rng)
        else:
            value = values(f, rng)
        out[f.name] = to_json(value, f)
    return out


def _rng(seed: int, *parts: str) -> random.Random:
    return random.Random(stable_seed(seed, *parts))


def _each(f: FieldInfo, one: Callable[[], Any]) -> Any:
    if f.is_string:
        return one()
    return [one() for _ in range(f.array_length)] if f.array_length else one()


def _zero(f: FieldInfo, rng: random.Random) -> Any:
    return _each(f, lambda: "" if f.is_string else (0.0 if f.is_float else 0))


def _typical(f: FieldInfo, rng: random.Random) -> Any:
    if f.is_string:
        return "".join(rng.choice(_TEXT) for _ in range(rng.randint(1, f.array_length)))
    if f.is_float:
        return _each(f, lambda: _as_wire(round(rng.uniform(-1000.0, 1000.0), 3), f))
    lo, hi = INT_RANGES[f.type]
    return _each(f, lambda: rng.randint(lo, hi) or 1)     # non-zero: a typical value is set


def _maximum(f: FieldInfo, rng: random.Random) -> Any:
    if f.is_string:
        return "".join(rng.choice(_TEXT) for _ in range(f.array_length))
    if f.is_float:
        return _each(f, lambda: FLT_MAX if f.type == "float" else DBL_MAX)
    return _each(f, lambda: INT_RANGES[f.type][1])


def _minimum(f: FieldInfo, rng: random.Random) -> Any:
    if f.is_string:
        return ""
    if f.is_float:
        return _each(f, lambda: -FLT_MAX if f.type == "float" else -DBL_MAX)
    return _each(f, lambda: INT_RANGES[f.type][0])


def _float_edge(value: float | None) -> Values:
    def values(f: FieldInfo, rng: random.Random) -> Any:
        if not f.is_float:
            return _typical(f, rng)
        edge = value if value is not None else (FLT_TRUE_MIN if f.type == "float" else DBL_TRUE_MIN)
        return _each(f, lambda: edge)
    return values


def _positions(info: MessageInfo) -> dict[str, int]:
    """Integer latitude/longitude fields and their sign of scale: `lat*`/`lon*` with units
    degE7, or `x`/`y` (int32) in a message with a `frame` field (MISSION_ITEM_INT,
    COMMAND_INT), as docs/vectors.md states. Value: 1 latitude, 2 longitude."""
    names = {f.name for f in info.fields}
    out = {}
    for f in info.fields:
        if f.type != "int32_t" or f.array_length:
            continue
        if f.units == "degE7" and f.name.startswith("lat"):
            out[f.name] = 1
        elif f.units == "degE7" and f.name.startswith("lon"):
            out[f.name] = 2
        elif "frame" in names and f.name in ("x", "y"):
            out[f.name] = 1 if f.name == "x" else 2
    return out


def _position_edge(positions: dict[str, int], sign: int) -> Values:
    def values(f: FieldInfo, rng: random.Random) -> Any:
        kind = positions.get(f.name)
        if kind is None:
            return _typical(f, rng)
        return sign * (LAT_MAX if kind == 1 else LON_MAX)
    return values


def _as_wire(value: float, f: FieldInfo) -> float:
    return struct.unpack("<f", struct.pack("<f", value))[0] if f.type == "float" else value


# --- invalid vectors ---------------------------------------------------------------------

def _invalid_vectors(dialect: DialectInfo, info: MessageInfo, seed: int, typical_id: str,
                     signed: dict[str, Any]) -> Iterator[dict[str, Any]]:
    name = info.name
    base_fields = _values(info, _typical, True, _rng(seed, typical_id))

    def broken(variant: str, error: str, description: str, mutate: Callable[[bytes], bytes],
               *, version: int = 2, fields: dict[str, Any] | None = None, sign: bool = False,
               key: bytes = TEST_KEY) -> dict[str, Any]:
        vid = f"{name}/{variant}"
        vec = _valid(dialect, info, vid, description, fields or base_fields, _rng(seed, vid, "header"),
                     version, signed=sign, key=key)
        build = vec["_build"]
        vec["_build"] = lambda v: mutate(build(v))
        vec["expected_error"] = error
        vec["fields"] = None
        vec["derived_from"] = typical_id if not sign else signed["id"]
        return vec

    yield broken("bad-crc", "bad_crc", "the checksum's low byte inverted", _flip_crc)
    yield broken("length-over", "bad_length",
                 "the length byte one more than the payload: the frame ends before the length says",
                 _length(+1))
    yield broken("length-under", "bad_crc",
                 "the length byte one less than the payload: the checksum is read from the payload's "
                 "last byte and the first checksum byte, so it does not match", _length(-1))
    if info.fits_v1 and info.base_length > 1:
        yield broken("v1-short-payload", "bad_length",
                     "MAVLink 1 with the payload's last byte cut off and a correct checksum: MAVLink 1 "
                     "has no truncation, so the payload is shorter than the message",
                     lambda raw: _v1_cut(raw, info.crc_extra, dialect), version=1,
                     fields=_values(info, _typical, False, _rng(seed, typical_id)))
    yield broken("wrong-key", "bad_signature",
                 f"signed with another key (SHA-256 of {WRONG_KEY_PASSPHRASE!r}), checked with the test key",
                 lambda raw: raw, sign=True, key=WRONG_KEY)
    yield broken("bad-signature", "bad_signature", "signed with the test key, the signature's last byte inverted",
                 _flip_last, sign=True)


def _dialect_vectors(dialect: DialectInfo, seed: int) -> Iterator[dict[str, Any]]:
    """Frames no message of the dialect explains: unknown ids, an unknown incompat flag."""
    v2_unknown = next(i for i in range(0xFFFFFF, 0, -1) if i not in dialect.all_ids)
    v1_unknown = next(i for i in range(0xFF, 0, -1) if i not in dialect.all_ids)
    payload = bytes([1, 2, 3, 4])
    for vid, version, msgid in (("unknown-msgid/v2", 2, v2_unknown), ("unknown-msgid/v1", 1, v1_unknown)):
        rng = _rng(seed, vid, "header")
        header = {"sysid": rng.randint(1, 255), "compid": rng.randint(0, 255), "seq": 0}
        yield {"id": vid, "description": f"MAVLink {version} frame of message id {msgid}, which the dialect "
               "does not define; checksum computed with CRC_EXTRA 0", "message": None, "msgid": msgid,
               "version": version, "signed": False, "header": header, "signature": None, "fields": None,
               "expected_error": "unknown_msgid",
               "_build": lambda v, version=version, msgid=msgid: _raw_frame(dialect, version, v["header"], msgid,
                                                                            payload, 0, 0)}
    first = dialect.messages[0]
    base = f"{first.name}/{'v2-ext-set' if first.has_extensions else 'v2-typical'}"
    fields = _values(first, _typical, True, _rng(seed, base))
    vid = "unknown-incompat-flag/v2"
    rng = _rng(seed, vid, "header")
    header = {"sysid": rng.randint(1, 255), "compid": rng.randint(0, 255), "seq": 0}

    def build(v: dict[str, Any]) -> bytes:
        raw = encode(dialect, first, fields, v["header"], 2)
        return _raw_frame(dialect, 2, v["header"], first.id, raw[10:-2], first.crc_extra, 0x02)
    yield {"id": vid, "description": f"a valid {first.name} frame with incompat_flags 0x02 (no such flag is "
           "defined) and a checksum computed over it: receivers must drop it", "message": first.name,
           "msgid": first.id, "version": 2, "signed": False, "header": header, "signature": None,
           "fields": None, "expected_error": "unknown_incompat_flags", "derived_from": base, "_build": build}


def _raw_frame(dialect: DialectInfo, version: int, header: dict[str, int], msgid: int, payload: bytes,
               crc_extra: int, incompat: int) -> bytes:
    if version == 1:
        head = bytes([MAGIC_V1, len(payload), header["seq"], header["sysid"], header["compid"], msgid])
    else:
        head = bytes([MAGIC_V2, len(payload), incompat, 0, header["seq"], header["sysid"], header["compid"],
                      msgid & 0xFF, msgid >> 8 & 0xFF, msgid >> 16])
    crc = dialect.module.x25crc(head[1:] + payload + bytes([crc_extra])).crc
    return head + payload + crc.to_bytes(2, "little")


def _flip_crc(raw: bytes) -> bytes:
    i = len(raw) - 2
    return raw[:i] + bytes([raw[i] ^ 0xFF]) + raw[i + 1:]


def _flip_last(raw: bytes) -> bytes:
    return raw[:-1] + bytes([raw[-1] ^ 0xFF])


def _length(delta: int) -> Callable[[bytes], bytes]:
    def mutate(raw: bytes) -> bytes:
        if raw[1] + delta > 0xFF:       # a full 255-byte payload: cut the frame's last byte instead
            return raw[:-1]
        return raw[:1] + bytes([raw[1] + delta]) + raw[2:]
    return mutate


def _v1_cut(raw: bytes, crc_extra: int, dialect: DialectInfo) -> bytes:
    head, payload = raw[:6], raw[6:-3]
    head = head[:1] + bytes([len(payload)]) + head[2:]
    crc = dialect.module.x25crc(head[1:] + payload + bytes([crc_extra])).crc
    return head + payload + crc.to_bytes(2, "little")
