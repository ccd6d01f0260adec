"""Checking vectors against a codec: ours here, the independent ones through the same result
records (crosscheck.py).

A codec's *result* for one vector is a dict (one JSON line from a cross-check harness):
    {"id": ..., "ok": true,  "msgid": .., "sysid": .., "compid": .., "seq": .., "fields": {...},
     "signature": {"link_id": .., "timestamp": ..} | null, "reencoded": "hex"}
    {"id": ..., "ok": false, "error": "bad_crc" | ... | "other", "detail": "the library's words"}
`judge` compares it with the vector: a valid vector must decode to its header and fields and
re-encode to its bytes; an invalid one must be refused with its expected error.

Our codec (`ours`): `FrameDecoder` on the vector's bytes, holding the test key for signed
vectors and a wall clock at the signature's time (so the one-minute rule for new streams
holds); then `FrameEncoder` with the same header and signature block (messages.encode).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable

from mavconform.reference_impl.wire.codec import FrameDecoder
from mavconform.reference_impl.wire.frame import DecodeError, SignatureVerdict
from mavconform.reference_impl.wire.signing import SIGNING_EPOCH_UNIX, SigningKey

from .dialect_info import DialectInfo
from .fields import field_differences, message_fields
from .messages import TEST_KEY, encode


@dataclass
class Mismatch:
    vector: str
    what: str          # one line: how the codec's answer differs from the vector

    def __str__(self) -> str:
        return f"{self.vector}: {self.what}"


@dataclass
class Report:
    implementation: str
    checked: int = 0
    mismatches: list[Mismatch] = field(default_factory=list)
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not self.mismatches


def judge(vector: dict[str, Any], result: dict[str, Any] | None, dialect: DialectInfo) -> list[str]:
    """Every way `result` departs from `vector` (empty: it agrees)."""
    if result is None:
        return ["no result for this vector"]
    expected = vector["expected_error"]
    if expected is not None:
        if result.get("ok"):
            return [f"accepted (decoded as msgid {result.get('msgid')}), expected {expected}"]
        if result.get("error") != expected:
            return [f"refused as {result.get('error')} ({result.get('detail', '')}), expected {expected}"]
        return []
    if not result.get("ok"):
        return [f"refused as {result.get('error')} ({result.get('detail', '')})"]
    out = []
    header = vector["header"]
    for key, want in (("msgid", vector["msgid"]), ("sysid", header["sysid"]), ("compid", header["compid"]),
                      ("seq", header["seq"])):
        if result.get(key) != want:
            out.append(f"header {key}: expected {want}, got {result.get(key)}")
    if vector["signed"] and result.get("signature") != vector["signature"]:
        out.append(f"signature block: expected {vector['signature']}, got {result.get('signature')}")
    info = next((m for m in dialect.messages if m.id == vector["msgid"]), None)
    if info is None:
        out.append(f"message id {vector['msgid']} is not in the dialect used to judge")
    else:
        out += field_differences(vector["fields"], result.get("fields"), info)
    if result.get("reencoded") != vector["hex"]:
        out.append(f"re-encoded to {result.get('reencoded')}, expected {vector['hex']}")
    return out


def ours(vector: dict[str, Any], dialect: DialectInfo) -> dict[str, Any]:
    """Our codec's result for one vector."""
    raw = bytes.fromhex(vector["hex"])
    sig = vector.get("signature")
    wall = SIGNING_EPOCH_UNIX + (sig["timestamp"] / 100_000 if sig else 0.0)
    decoder = FrameDecoder(dialect=dialect.module, signing=SigningKey(TEST_KEY) if vector["signed"] else None,
                           wall_clock=lambda: wall)
    items = decoder.feed(raw)
    if not items:
        return {"id": vector["id"], "ok": False, "error": "other", "detail": "nothing decoded"}
    first = items[0]
    if isinstance(first, DecodeError):
        return {"id": vector["id"], "ok": False, "error": classify(first.reason), "detail": first.reason}
    if len(items) > 1:
        return {"id": vector["id"], "ok": False, "error": "other",
                "detail": f"{len(items) - 1} more item(s) after the frame: {items[1]}"}
    if first.signature is SignatureVerdict.INVALID:
        return {"id": vector["id"], "ok": False, "error": "bad_signature", "detail": first.authenticity}
    info = next((m for m in dialect.messages if m.id == first.msgid), None)
    result: dict[str, Any] = {"id": vector["id"], "ok": True, "msgid": first.msgid, "sysid": first.src_system,
                              "compid": first.src_component, "seq": first.seq, "signature": None}
    if first.signature is SignatureVerdict.VALID:
        result["signature"] = {"link_id": first.link_id, "timestamp": int.from_bytes(first.raw[-12:-6], "little")}
    if info is None:   # a message of an included file: decoded, but not ours to judge
        return dict(result, fields={})
    result["fields"] = fields = message_fields(first.msg, info)
    header = {"sysid": first.src_system, "compid": first.src_component, "seq": first.seq}
    signature = result["signature"]
    result["reencoded"] = encode(dialect, info, fields, header, first.version,
                                 key=TEST_KEY if signature else None,
                                 link_id=signature["link_id"] if signature else 0,
                                 timestamp=signature["timestamp"] if signature else 0).hex()
    return result


def classify(reason: str) -> str:
    """Our decoder's reason text -> the vectors' error vocabulary."""
    text = reason.lower()
    if "crc" in text:
        return "bad_crc"
    if "truncated" in text or "length" in text:
        return "bad_length"
    if "unknown message id" in text:
        return "unknown_msgid"
    if "incompat" in text:
        return "unknown_incompat_flags"
    if "signature" in text:
        return "bad_signature"
    return "other"


def check(implementation: str, vectors: Iterable[dict[str, Any]], results: dict[str, dict[str, Any]],
          dialect: DialectInfo) -> Report:
    """Judge every vector against an implementation's results (by vector id)."""
    report = Report(implementation)
    for vec in vectors:
        report.checked += 1
        for what in judge(vec, results.get(vec["id"]), dialect):
            report.mismatches.append(Mismatch(vec["id"], what))
    return report


def exchange_frames(transcript: dict[str, Any], dialect: DialectInfo) -> list[str]:
    """Every frame of an exchange transcript through our codec: decoded to the recorded
    header and fields, re-encoded to the recorded bytes (one line per disagreement)."""
    by_id = {m.id: m for m in dialect.messages}
    out = []
    for n, event in enumerate(transcript["events"]):
        if event["msg"] == "DECODE_ERROR":
            continue
        where = f"event {n} ({event['msg']} at {event['t']} s)"
        items = FrameDecoder(dialect=dialect.module).feed(bytes.fromhex(event["hex"]))
        if len(items) != 1 or isinstance(items[0], DecodeError):
            out.append(f"{where}: does not decode to one frame: {[str(i) for i in items]}")
            continue
        frame = items[0]
        info = by_id.get(frame.msgid)
        header = {"sysid": frame.src_system, "compid": frame.src_component, "seq": frame.seq}
        if (frame.name, frame.msgid, frame.version) != (event["msg"], event["msgid"], event["version"]) or \
                header != {k: event[k] for k in header}:
            out.append(f"{where}: header differs from the transcript's")
        if info is None:
            continue
        diffs = field_differences(event["fields"], message_fields(frame.msg, info), info)
        out += [f"{where}: {d}" for d in diffs]
        again = encode(dialect, info, event["fields"], header, frame.version).hex()
        if again != event["hex"]:
            out.append(f"{where}: re-encoded to {again}, recorded {event['hex']}")
    return out
