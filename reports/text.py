"""Text shared by the writers: cleaning strings from the wire, and wording events and targets.

Details, STATUSTEXTs and field values come from the target and may hold anything: control
characters (not allowed in XML 1.0, and they garble a terminal or a table), bidirectional
overrides (they can make a report read backwards), lone surrogates (not encodable as UTF-8).
Every writer passes data through `clean` or `one_line` before its own escaping.
"""

from __future__ import annotations

import json
import re
from typing import Any

from mavconform.reports.run_document import NOTE, RX, TX, receive_queue
from mavconform.reports.run_document import run_facts as volatile_facts

# C0 controls but tab and newline, DEL, C1 controls, bidi embeddings/overrides/isolates,
# noncharacters U+FFFE/U+FFFF; lone surrogates are replaced rather than dropped.
_UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069\ufffe\uffff]")
_SURROGATE = re.compile("[\ud800-\udfff]")
NON_FINITE = ("NaN", "Infinity", "-Infinity")  # how a non-finite float travels in fields

# Field names shown shorter (or clearer) in a label. MISSION_ACK's `type` is its result.
_FIELD_NAMES = {"mission_type": "type"}
_ACK_FIELD_NAMES = {"type": "result", "mission_type": "type"}
_LABEL_FIRST = ("seq", "count", "type", "command", "frame", "current", "total", "mission_type")
_LABEL_HIDDEN = ("target_system", "target_component")  # always us / the target: noise


def clean(text: str) -> str:
    """`text` with unsafe characters removed (newlines and tabs kept; CR LF becomes LF)."""
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    return _SURROGATE.sub("\ufffd", _UNSAFE.sub("", text))


def one_line(text: str, limit: int | None = None) -> str:
    """`text` cleaned, on one line (whitespace runs become one space), at most `limit` chars."""
    text = " ".join(clean(text).split())
    if limit is not None and len(text) > limit:
        text = text[:limit - 1].rstrip() + "…"
    return text


def value_text(value: Any) -> str:
    """A field value as JSON text, but a non-finite float's string bare (NaN, not "NaN")."""
    if isinstance(value, str) and value in NON_FINITE:
        return value
    if isinstance(value, (list, tuple)):
        return "[" + ",".join(value_text(v) for v in value) + "]"
    return json.dumps(value, ensure_ascii=False)


def event_label(event: dict[str, Any]) -> str:
    """"MSG seq=1 type=0 ..." for tx/rx events (key fields first); a note's own text."""
    if event["dir"] == NOTE:
        return one_line(event["msg"])
    fields = event["fields"]
    names = _ACK_FIELD_NAMES if event["msg"] == "MISSION_ACK" else _FIELD_NAMES
    order = [k for k in _LABEL_FIRST if k in fields]
    order += sorted(k for k in fields if k not in order and k not in _LABEL_HIDDEN)
    shown: set[str] = set()
    parts = [one_line(event["msg"])]
    for key in order:
        name = names.get(key, key)
        if name in shown or (name != key and name in fields and name not in names):
            name = key  # never two fields under one name
        shown.add(name)
        parts.append(f"{one_line(name)}={one_line(value_text(fields[key]))}")
    return " ".join(parts)


def relative_time(t: float, t0: float) -> str:
    """"+1.500 s": time since the first event of the exchange."""
    return f"+{t - t0:.3f} s"


def exchange_start(exchange: list[dict[str, Any]]) -> float:
    """The time of the earliest event (0 for an empty exchange)."""
    return min((event["t"] for event in exchange), default=0.0)


def exchange_lines(exchange: list[dict[str, Any]], limit: int = 300) -> list[str]:
    """The exchange as text, one event a line: "+0.001 s  target → tester  MISSION_ACK ...".
    `exchange` is events with their times, as `run_document.clause_events` gives them."""
    t0 = exchange_start(exchange)
    lines = []
    for event in exchange[:limit]:
        peer = one_line(event["peer"])
        arrow = {TX: f"{peer} → target", RX: f"target → {peer}", NOTE: "note"}[event["dir"]]
        lines.append(f"{relative_time(event['t'], t0)}  {arrow}  {event_label(event)}")
    if len(exchange) > limit:
        lines.append(f"… {len(exchange) - limit} more events")
    return lines


def identity_text(identity: dict[str, Any] | None, missing: str = "no answer from the target",
                  address: str | None = None) -> str:
    """"system 1 component 1, type 2, autopilot 4, MAVLink 2, at 127.0.0.1:40001"."""
    if identity is None:
        return missing
    if "msp_api" in identity:     # an MSP flight controller (conformance/msp/runner.py)
        parts = [f"MSP API {identity['msp_api']}", f"{identity.get('max_waypoints')} waypoints at most"]
        address = address or identity.get("address")
        return ", ".join(parts + ([f"at {one_line(str(address))}"] if address else []))
    parts = [f"system {identity['system']} component {identity['component']}"]
    for key, word in (("type", "type"), ("autopilot", "autopilot"),
                      ("mavlink_version", "MAVLink")):
        if identity.get(key) is not None:
            parts.append(f"{word} {identity[key]}")
    address = address or identity.get("address")   # a document's is in its volatile section
    if address:
        parts.append(f"at {one_line(str(address))}")
    return ", ".join(parts)


def document_identity(doc: dict[str, Any]) -> str:
    """The target's identity as the document knows it (a fuzz campaign does not record it)."""
    return identity_text(doc["identity"], "not recorded by a fuzz campaign" if "fuzz" in doc
                         else "no answer from the target", volatile_facts(doc)["address"])


def dropped_text(doc: dict[str, Any]) -> str | None:
    """What our sockets' receive queues dropped, for people: "none dropped (receive buffer
    8192 KiB)", "12 datagrams dropped before we read them (...)", "drops unknown (...)";
    None if the run did not record it."""
    queue = receive_queue(doc)
    if queue is None:
        return None
    dropped, granted = queue.get("dropped"), queue.get("buffer_bytes")
    if dropped is None:
        serial = (doc["run"].get("link") or {}).get("kind") == "serial"
        said = "drops unknown (a serial line does not count them)" if serial else \
            "drops unknown (this platform does not count them)"
    elif dropped == 0:
        said = "none dropped"
    else:
        said = f"{dropped} datagram{'' if dropped == 1 else 's'} dropped before we read them"
    return said + (f" (receive buffer {granted // 1024} KiB)" if granted is not None else "")


def link_text(doc: dict[str, Any]) -> str | None:
    """The link to the target and the timing used, for people: "serial at 5760 bytes/s:
    each reply wait + 0.275 s; 1 connection"; for an in-process target, only the clock it
    shared with the suite when faster than real; None otherwise (or for a run document from
    before links were recorded)."""
    link = doc["run"].get("link")
    events = (doc.get("volatile") or {}).get("link")
    msp = msp_stream_text(events.get("msp") if events else None)
    if link and link.get("clock_speed"):
        return (f"in-process, on a clock {link['clock_speed']:g}x real time shared with the target: the "
                "exchanges' times and every bound a clause judged are in that clock's seconds")
    if not link or link.get("kind") == "in-process":
        return msp
    rate = link.get("bytes_per_second")
    if rate is None:
        said = f"{link['kind']} (a network link: reply waits are the protocol's)"
    else:
        said = f"{link['kind']} at {rate:g} bytes/s: each reply wait + {link['reply_allowance_s']:g} s"
    if events:
        lost = sum(1 for e in events.get("history", []) if e["event"].startswith(("closed", "read failed",
                                                                                  "write failed")))
        n = events.get("connections", 0)
        said += f"; {n} connection{'' if n == 1 else 's'}" + (f", {lost} lost" if lost else "")
        dropped = events.get("frames_dropped_link_down", 0)
        if dropped:
            said += f", {dropped} frame{'' if dropped == 1 else 's'} sent while it was down"
    return said + (f"; {msp}" if msp else "")


def msp_stream_text(stats: dict[str, Any] | None) -> str | None:
    """What the MSP reader skipped in a flight controller's stream, for people ("MSP stream:
    31 bytes outside any frame, 2 bad checksums"); None if it skipped nothing."""
    if not stats:
        return None
    names = (("garbage_bytes", "byte outside any frame", "bytes outside any frame"),
             ("bad_checksum", "bad checksum", "bad checksums"), ("bad_header", "bad header", "bad headers"),
             ("oversize", "oversize frame", "oversize frames"), ("truncated", "cut-off frame", "cut-off frames"))
    parts = [f"{stats[k]} {one if stats[k] == 1 else many}" for k, one, many in names if stats.get(k)]
    return "MSP stream: " + ", ".join(parts) if parts else None


def flight_endings(doc: dict[str, Any]) -> list[str]:
    """One line per flight the run made: which clause flew it, as what, and how it ended."""
    out = []
    for flight in doc.get("flights", []):
        state = {True: "disarmed", False: "MAY STILL BE ARMED", None: "arming state unknown"}[flight["disarmed"]]
        out.append(one_line(f"{flight['clause'] or 'a flight'} ({flight['style']}): {state}: {flight['detail']}"))
    return out


def safety_alarm(doc: dict[str, Any]) -> str | None:
    """What the reports say first when a flight did not end with the vehicle disarmed
    (None: every flight did, or none was made)."""
    left = [f for f in doc.get("flights", []) if f["disarmed"] is False]
    if not left:
        return None
    where = ", ".join(f"{f['clause'] or 'a flight'} ({f['style']})" for f in left)
    return one_line(f"THE VEHICLE MAY STILL BE ARMED: the suite could not confirm it disarmed after the flight of "
                    f"{where}: {left[-1]['detail']}. Make it safe by hand before anyone goes near it.")


def seconds(value: float) -> str:
    """A duration for people: "0.310 s", "12.5 s"."""
    return f"{value:.3f} s" if value < 10 else f"{value:.1f} s"


VERDICT_HEADLINES = {"pass": "✅ PASS", "fail": "❌ FAIL", "interrupted": "⏹️ INTERRUPTED"}


def verdict_headline(verdict: str) -> str:
    """"✅ PASS", "❌ FAIL" or "⏹️ INTERRUPTED", for a report's first line."""
    return VERDICT_HEADLINES[verdict]


def interruption(doc: dict[str, Any]) -> str | None:
    """What the reports say first about a run a signal stopped (None for a complete run)."""
    run = doc["run"]
    if not run.get("interrupted") and doc["summary"]["verdict"] != "interrupted":
        return None
    by = f" by {run['interrupted_by']}" if run.get("interrupted_by") else ""
    at = f" during {run['interrupted_at']}" if run.get("interrupted_at") else ""
    return one_line(f"The run was interrupted{by}{at}: it is not a complete result (what it did "
                    "not reach was not checked), and it cannot serve as a --baseline.")
