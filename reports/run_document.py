"""The run document ("mavconform-run/2"): what a conformance run found, as plain JSON.

The runner builds it; every report is a pure function of it. `load_run` checks the shape
once, here, so the writers can index it without guarding each key, and a bad RUN.json is
a one-line `UsageError` naming the file and the JSON path, never a traceback from a writer.
`dump_run` is canonical (sorted keys, fixed indent) so that two runs diff cleanly.

Two runs of the same target differ only in one top-level section, `volatile`: every value
that changes from run to run without the target behaving differently (when it started, how
long things took, when each message came, the target's ephemeral address, numbers measured
off the clock, the datagrams our own sockets dropped) lives there and nowhere else, so `jq 'del(.volatile)'` on two run.json files
leaves the behaviour to compare. A measured number inside a detail or a note is written
`<name>` in the text and its value is in the volatile section; renderers read times and
texts through `clause_events`, `clause_detail`, `clause_duration` and `run_facts`, which
put them back together, never through the fields directly.

Shape (keys the writers rely on; objects may carry more keys, which are kept):

    format    "mavconform-run/2"
    tool      {name, version}
    run       {target, ...scalars: seed, time_scale, strict, ...,
               [interrupted: bool, interrupted_at: clause id or phase, interrupted_by: SIGTERM],
               [link: {kind: in-process|udp|udpin|tcp|tcpin|serial, bytes_per_second (null: a
                       network link, not limited), reply_allowance_s: what the suite added to
                       each reply wait for the link's speed (harness/link_timing.py),
                       [clock_speed: an in-process target and the suite shared a clock this
                       many times real time; every time and bound is in its seconds]}]}
    identity  {system, component, [type, autopilot, mavlink_version, ...]} or null; an MSP
              flight controller's: {msp_api: "2.5", max_waypoints, [msp_protocol, waypoints,
              mission_valid]}
    summary   {total, <one count per outcome>, gating_failures, [left_armed],
               verdict: pass|fail|interrupted}
    gating    {mode: strict|default|baseline, regressions: [id], fixed: [id]}
    restore   {status: restored|unchanged|failed|skipped, detail}
    capture   file name of the MCAP capture, or null
    [flights  [{clause, style, plan, disarmed: true|false|null, detail}]]   how each flight the
              run made ended (harness/landing.py): disarmed and confirmed by a HEARTBEAT (true),
              possibly still armed (false: summary.left_armed counts them, and any fails the
              run), or not known (null: its HEARTBEAT never shows arming)
    clauses   [{id, group, level, role, title, source, requirement, outcome, gating,
                detail, expectation, exchange: [{dir: tx|rx|note, peer, msg, fields}],
                [decided_by: index in exchange of the event the check judged last, or null]}]
    volatile  {started, duration_s, forced_wait_s (or null), address (the target's, or null),
               [identity: {KEY: {name: text}}],                  an identity text's <name>s
                                                                 (how long the target booted)
               [link: {connections, bytes_written, bytes_read,   a stream link (tcp:, serial:):
                       frames_dropped_link_down,                 what it carried, what was sent
                       frames_dropped_queue_full,                while it was down, and its
                       history: [{t, event}]}],                  connects and losses (t: s
                                                                 from discovery's start)
               [receive_queue: {dropped, buffer_bytes}],         our sockets' kernel receive
                                 queues: datagrams they dropped before we read them (null:
                                 the platform cannot tell) and the smallest buffer granted
                                 (bytes, or null)
               clauses: {ID: {duration_s, events: [t, ...],      one t per exchange event:
                                                                 s from the clause's start
                              [detail: {name: text}],            the detail's <name>s
                              [notes: {"INDEX": {name: text}}],  a note event's <name>s
                              [ambient: [{at, t, dir, peer, msg, fields}]],
                                 streamed messages no check used (MISSION_CURRENT at 1 Hz:
                                 how many fall in a clause is the stream's phase), each at
                                 its index in the whole exchange
                              [host_lag_s],                      how far behind its clock the
                                 tester ran while this was judged, when over the tolerance
                              [first_attempt: {outcome, host_lag_s}]}}}
                                 the attempt run again because it did not pass while the
                                 host lagged (conformance/host_lag.py)

The summary counts must agree with the clauses, so no report shows two different totals,
and a run marked interrupted cannot have the verdict "pass" (what it did not reach is not
known to pass). A volatile key found outside `volatile` is refused, so it cannot creep back.

The older "mavconform-run/1" kept the times in place (run.started, clauses[].duration_s,
exchange[].t, ...). `load_run` still reads it and moves them into `volatile` (nothing is
lost), so an old run.json serves as --baseline and `report render` re-renders it in the
current format; `check_run`, for documents built in memory, takes the current format only.
The checker itself is reports/run_check.py; this module keeps the format's tables, loading and
writing, and the accessors the renderers read volatile values through.
"""

from __future__ import annotations

import copy
import json
import re
from pathlib import Path
from typing import Any


FORMAT = "mavconform-run/2"
FORMAT_1 = "mavconform-run/1"   # times in place; load_run upgrades it

PASS = "pass"
FAIL = "fail"
KNOWN_DEVIATION = "known-deviation"
NOT_APPLICABLE = "not-applicable"
SKIPPED = "skipped"
ERROR = "error"
OUTCOMES = (PASS, FAIL, KNOWN_DEVIATION, NOT_APPLICABLE, SKIPPED, ERROR)  # display order

INTERRUPTED = "interrupted"   # the verdict of a run a signal stopped: neither pass nor fail
VERDICTS = ("pass", "fail", INTERRUPTED)
LEVELS = ("MUST", "SHOULD", "MAY")
GATING_MODES = ("strict", "default", "baseline")
RESTORE_STATUSES = ("restored", "unchanged", "failed", "skipped")

AMBIENT = "ambient"   # a merged-in event of a stream no check used (clause_events)
TX, RX, NOTE = "tx", "rx", "note"  # tester sent, tester received from the target, commentary
DIRECTIONS = (TX, RX, NOTE)

# run keys every writer shows by name; the rest of `run` is shown as it comes.
RUN_REQUIRED = {"target": ("string",)}
RUN_KNOWN = {"seed": ("integer", "null"), "time_scale": ("number",), "strict": ("bool",),
             "clauses": ("string",), "expectations": ("string", "null"),
             "baseline": ("string", "null"),
             "interrupted": ("bool",), "interrupted_at": ("string", "null"),
             "interrupted_by": ("string", "null"), "link": ("object",)}
LINK_KNOWN = {"kind": ("string",), "bytes_per_second": ("number", "null"), "reply_allowance_s": ("number",)}
LINK_OPTIONAL = {"clock_speed": ("number",)}
LINK_COUNTS = ("bytes_written", "bytes_read", "frames_dropped_link_down", "frames_dropped_queue_full",
               "connections")
IDENTITY_KNOWN = {"type": ("integer",), "autopilot": ("integer",),
                  "mavlink_version": ("integer",)}
# optional clause keys: decided_by is an index, so stable (the events' order is)
CLAUSE_KNOWN = {"decided_by": ("integer", "null")}
VOLATILE_KNOWN = {"started": ("string",), "duration_s": ("number",),
                  "forced_wait_s": ("number", "null"), "address": ("string", "null")}
# Where format 1 kept the volatile values (and where format 2 refuses them).
MOVED_RUN = ("started", "duration_s", "forced_wait_s")
MOVED_IDENTITY = ("address",)
PLACEHOLDER = re.compile(r"<([A-Za-z_][A-Za-z0-9_]*)>")   # a measured number in a text
SCALAR = ("string", "number", "bool", "null")

_SURROGATE = re.compile("[\ud800-\udfff]")


def load_run(path: str | Path) -> dict[str, Any]:
    """The run document in `path`, checked (see `check_run`); any problem is one line."""
    from mavconform.reports.run_check import Checker, NonFinite, refuse   # it reads this module's tables
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        refuse(source, "", f"cannot read: not UTF-8 text ({error.reason})")
    except OSError as error:
        refuse(source, "", f"cannot read: {error.strerror or error}")
    try:
        # A NaN/Infinity literal becomes a marker that check_run reports with its path.
        document = json.loads(text, parse_constant=NonFinite)
    except json.JSONDecodeError as error:
        refuse(source, "", f"line {error.lineno} column {error.colno}: invalid JSON: {error.msg}")
    except RecursionError:
        refuse(source, "", "invalid JSON: nested too deeply")
    if isinstance(document, dict) and document.get("format") == FORMAT_1:
        Checker(source, FORMAT_1).document(document)
        document = upgrade_run(document)
    return check_run(document, source)


def check_run(doc: Any, source: str = "run document") -> dict[str, Any]:
    """`doc` itself if it has the shape the writers rely on; else a one-line `UsageError`
    "SOURCE: json.path: problem". Also for a document built in memory by the runner."""
    from mavconform.reports.run_check import Checker
    Checker(source).document(doc)
    return doc


def upgrade_run(doc: dict[str, Any]) -> dict[str, Any]:
    """A checked "mavconform-run/1" document in the current format: a new document, its
    times, durations and address moved into `volatile` (its texts stay as they were)."""
    doc = copy.deepcopy(doc)   # the caller's document is not changed
    run, identity = doc["run"], doc["identity"]
    volatile: dict[str, Any] = {key: run.pop(key, None) for key in MOVED_RUN}
    volatile["address"] = identity.pop("address", None) if identity is not None else None
    volatile["clauses"] = {}
    for clause in doc["clauses"]:   # new dicts: two clauses may share an event object
        volatile["clauses"][clause["id"]] = {"duration_s": clause.pop("duration_s"),
                                             "events": [e["t"] for e in clause["exchange"]]}
        clause["exchange"] = [{k: v for k, v in e.items() if k != "t"} for e in clause["exchange"]]
    doc["volatile"] = volatile
    doc["format"] = FORMAT
    return doc


def dump_run(doc: dict[str, Any]) -> str:
    """Canonical JSON text: sorted keys, indent 2, UTF-8 as is, no NaN, trailing newline.

    A lone surrogate (a string decoded with surrogateescape) cannot be written as UTF-8, so
    it is kept as its JSON escape: the text still loads back to the very same document.
    """
    text = json.dumps(doc, sort_keys=True, indent=2, ensure_ascii=False, allow_nan=False)
    return _SURROGATE.sub(lambda m: f"\\u{ord(m.group()):04x}", text) + "\n"


def outcome_counts(clauses: list[dict[str, Any]]) -> dict[str, int]:
    """Clauses per outcome, every outcome present (in display order)."""
    counts = dict.fromkeys(OUTCOMES, 0)
    for clause in clauses:
        counts[clause["outcome"]] += 1
    return counts


# --- volatile values, for the renderers ------------------------------------------------------

def fill(text: str, values: dict[str, str]) -> str:
    """`text` with each `<name>` that `values` has replaced by its measured value."""
    if not values:
        return text
    return PLACEHOLDER.sub(lambda m: values.get(m.group(1), m.group(0)), text)


def _volatile_clause(doc: dict[str, Any], clause: dict[str, Any]) -> dict[str, Any]:
    return (doc.get("volatile") or {}).get("clauses", {}).get(clause["id"], {})


def clause_events(doc: dict[str, Any], clause: dict[str, Any]) -> list[dict[str, Any]]:
    """The clause's exchange events, in order, each a new dict with its time `t` (s from
    the clause's start) and, for a note, its measured numbers back in its text; the ambient
    events (volatile) merged in where they arrived, each marked `ambient: true`.

    Renderers call this rather than reading `exchange`, which has no times (they are in
    `volatile`). A document without them (format 1 kept them in place) works too."""
    entry = _volatile_clause(doc, clause)
    times = entry.get("events", [])
    notes = entry.get("notes", {})
    events = []
    for index, event in enumerate(clause.get("exchange", [])):
        event = dict(event)
        if index < len(times):
            event["t"] = times[index]
        event.setdefault("t", 0.0)
        if str(index) in notes:
            event["msg"] = fill(event["msg"], notes[str(index)])
        events.append(event)
    for extra in entry.get("ambient", []):   # ascending: each lands where it arrived
        event = {key: value for key, value in extra.items() if key != "at"}
        event[AMBIENT] = True
        events.insert(min(extra["at"], len(events)), event)
    return events


def kept_event_index(events: list[dict[str, Any]], decided_by: int) -> int | None:
    """Where the clause's `decided_by` (an index among its kept events) is in `events`, the
    list `clause_events` returns (ambient events merged in); None if out of range."""
    kept = [index for index, event in enumerate(events) if not event.get(AMBIENT)]
    return kept[decided_by] if 0 <= decided_by < len(kept) else None


def clause_detail(doc: dict[str, Any], clause: dict[str, Any]) -> str:
    """The clause's detail as a person reads it: its measured numbers put back."""
    return fill(clause["detail"], _volatile_clause(doc, clause).get("detail", {}))


def clause_duration(doc: dict[str, Any], clause: dict[str, Any]) -> float | None:
    """How long the clause took, in seconds; None if the document does not say."""
    return _volatile_clause(doc, clause).get("duration_s", clause.get("duration_s"))


def identity_fact(doc: dict[str, Any], key: str) -> Any:
    """identity[key] as a person reads it: measured numbers in its text put back."""
    value = (doc.get("identity") or {}).get(key)
    if not isinstance(value, str):
        return value
    return fill(value, ((doc.get("volatile") or {}).get("identity") or {}).get(key, {}))


def receive_queue(doc: dict[str, Any]) -> dict[str, Any] | None:
    """Our sockets' receive queues in the run: {dropped, buffer_bytes}, each None where not
    known; None if the document does not say (a run before this was recorded)."""
    return (doc.get("volatile") or {}).get("receive_queue")


def run_facts(doc: dict[str, Any]) -> dict[str, Any]:
    """The run's volatile facts, for display: started (UTC, ISO 8601), duration_s,
    forced_wait_s and the target's address (each None if the document does not say)."""
    volatile = doc.get("volatile")
    if volatile is None:   # format 1: in place
        run, identity = doc.get("run", {}), doc.get("identity") or {}
        volatile = {**{key: run.get(key) for key in MOVED_RUN}, "address": identity.get("address")}
    return {key: volatile.get(key) for key in ("started", "duration_s", "forced_wait_s", "address")}
