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
                              [ambient: [{at, t, dir, peer, msg, fields}]]}}}
                                 streamed messages no check used (MISSION_CURRENT at 1 Hz:
                                 how many fall in a clause is the stream's phase), each at
                                 its index in the whole exchange

The summary counts must agree with the clauses, so no report shows two different totals,
and a run marked interrupted cannot have the verdict "pass" (what it did not reach is not
known to pass). A volatile key found outside `volatile` is refused, so it cannot creep back.

The older "mavconform-run/1" kept the times in place (run.started, clauses[].duration_s,
exchange[].t, ...). `load_run` still reads it and moves them into `volatile` (nothing is
lost), so an old run.json serves as --baseline and `report render` re-renders it in the
current format; `check_run`, for documents built in memory, takes the current format only.
"""

from __future__ import annotations

import copy
import json
import math
import re
from pathlib import Path
from typing import Any, NoReturn

from mavconform.reference_impl.errors import UsageError

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
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        _fail(source, "", f"cannot read: not UTF-8 text ({error.reason})")
    except OSError as error:
        _fail(source, "", f"cannot read: {error.strerror or error}")
    try:
        # A NaN/Infinity literal becomes a marker that check_run reports with its path.
        document = json.loads(text, parse_constant=_NonFinite)
    except json.JSONDecodeError as error:
        _fail(source, "", f"line {error.lineno} column {error.colno}: invalid JSON: {error.msg}")
    except RecursionError:
        _fail(source, "", "invalid JSON: nested too deeply")
    if isinstance(document, dict) and document.get("format") == FORMAT_1:
        _Checker(source, FORMAT_1).document(document)
        document = upgrade_run(document)
    return check_run(document, source)


def check_run(doc: Any, source: str = "run document") -> dict[str, Any]:
    """`doc` itself if it has the shape the writers rely on; else a one-line `UsageError`
    "SOURCE: json.path: problem". Also for a document built in memory by the runner."""
    _Checker(source).document(doc)
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


# --- checking ------------------------------------------------------------------------------

class _NonFinite:
    """A NaN/Infinity literal, which JSON does not have (fields carry them as strings)."""

    def __init__(self, name: str) -> None:
        self.name = name


def _fail(source: str, path: str, problem: str) -> NoReturn:
    message = f"{source}: {path}: {problem}" if path else f"{source}: {problem}"
    raise UsageError(" ".join(message.split())) from None  # one line, whatever was quoted


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _is(value: Any, kind: str) -> bool:
    if kind == "string":
        return type(value) is str  # not an Enum member: writers format and hash it as text
    if kind == "integer":
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == "number":
        return (isinstance(value, (int, float)) and not isinstance(value, bool)
                and math.isfinite(value))
    if kind == "bool":
        return isinstance(value, bool)
    if kind == "null":
        return value is None
    if kind == "object":
        return isinstance(value, dict)
    if kind == "array":
        return isinstance(value, (list, tuple))
    raise AssertionError(kind)


def _describe(value: Any) -> str:
    for python_type, name in ((bool, "a bool"), (dict, "an object"), ((list, tuple), "an array"),
                              (type(None), "null")):
        if isinstance(value, python_type):
            return name
    if type(value) is str:
        return f"the string {_short(value)}"
    if isinstance(value, str):
        return f"{type(value).__name__} {_short(str.__str__(value))} (write its .value)"
    if isinstance(value, (int, float)):
        return f"the number {value}"
    return f"a {type(value).__name__}"


def _short(value: str, limit: int = 40) -> str:
    return repr(value if len(value) <= limit else value[:limit] + "…")


class _Checker:
    """Typed access to the document; every problem names its JSON path."""

    def __init__(self, source: str, format_: str = FORMAT) -> None:
        self.source = source
        self.format = format_
        self.old = format_ == FORMAT_1   # times in place, no `volatile`

    def fail(self, path: str, problem: str) -> NoReturn:
        _fail(self.source, path, problem)

    def value(self, value: Any, path: str, kinds: tuple[str, ...]) -> Any:
        if any(_is(value, kind) for kind in kinds):
            return value
        names = [f"{'an' if k[0] in 'aeiou' else 'a'} {k}" if k != "null" else "null"
                 for k in kinds]
        self.fail(path, f"expected {' or '.join(names)}, found {_describe(value)}")

    def key(self, obj: dict, key: str, path: str, *kinds: str) -> Any:
        if key not in obj:
            self.fail(path, f"missing {key!r}")
        return self.value(obj[key], _join(path, key), kinds)

    def optional(self, obj: dict, key: str, path: str, *kinds: str) -> None:
        if key in obj:
            self.value(obj[key], _join(path, key), kinds)

    def choice(self, obj: dict, key: str, path: str, choices: tuple[str, ...]) -> str:
        value = self.key(obj, key, path, "string")
        if value not in choices:
            self.fail(_join(path, key), f"expected one of {', '.join(map(repr, choices))}, "
                                        f"found {_short(value)}")
        return value

    def count(self, obj: dict, key: str, path: str) -> int:
        value = self.key(obj, key, path, "integer")
        if value < 0:
            self.fail(_join(path, key), f"expected a count, found {value}")
        return value

    def non_finite(self, value: Any, path: str) -> None:
        """Refuse NaN/Infinity anywhere: dump_run could not write them back."""
        if isinstance(value, _NonFinite) or (isinstance(value, float) and not math.isfinite(value)):
            name = value.name if isinstance(value, _NonFinite) else repr(value)
            self.fail(path, f"{name} is not a JSON number (write it as a string)")
        if isinstance(value, dict):
            for key, item in value.items():
                if not isinstance(key, str):
                    self.fail(path, f"object key {key!r} is not a string")
                self.non_finite(item, _join(path, key))
        elif isinstance(value, (list, tuple)):
            for index, item in enumerate(value):
                self.non_finite(item, f"{path}[{index}]")

    # --- the document ---

    def document(self, doc: Any) -> None:
        if not isinstance(doc, dict):
            self.fail("", f"expected a JSON object, found {_describe(doc)}")
        if "format" not in doc:
            self.fail("", f"missing 'format' (expected {FORMAT!r}: not a mavconform run?)")
        if (found := doc["format"]) != self.format:
            if found == FORMAT_1:
                self.fail("format", f"{FORMAT_1!r} is the older layout, with its times in place: "
                                    "read it with load_run, which upgrades it")
            shown = _short(found) if isinstance(found, str) else _describe(found)
            self.fail("format", f"expected {self.format!r}, found {shown}")
        try:
            self.non_finite(doc, "")
        except RecursionError:
            self.fail("", "nested too deeply")
        tool = self.key(doc, "tool", "", "object")
        self.key(tool, "name", "tool", "string")
        self.key(tool, "version", "tool", "string")
        self.run(self.key(doc, "run", "", "object"))
        self.identity(self.key(doc, "identity", "", "object", "null"))
        self.key(doc, "capture", "", "string", "null")
        gating = self.key(doc, "gating", "", "object")
        self.choice(gating, "mode", "gating", GATING_MODES)
        for key in ("regressions", "fixed"):
            for index, item in enumerate(self.key(gating, key, "gating", "array")):
                self.value(item, f"gating.{key}[{index}]", ("string",))
        restore = self.key(doc, "restore", "", "object")
        self.choice(restore, "status", "restore", RESTORE_STATUSES)
        self.key(restore, "detail", "restore", "string")
        clauses = self.key(doc, "clauses", "", "array")
        first_index: dict[str, int] = {}
        for index, clause in enumerate(clauses):
            clause_id = self.clause(clause, f"clauses[{index}]")
            if clause_id in first_index:
                self.fail(f"clauses[{index}].id", f"{_short(clause_id)} is already "
                                                  f"clauses[{first_index[clause_id]}]")
            first_index[clause_id] = index
        self.summary(self.key(doc, "summary", "", "object"), clauses)
        self.flights(doc)
        if not self.old:
            self.volatile(self.key(doc, "volatile", "", "object"), clauses)
        if doc["run"].get("interrupted") and doc["summary"]["verdict"] == PASS:
            self.fail("summary.verdict", "'pass', but run.interrupted is true: an interrupted "
                                         "run is not known to pass")

    def moved(self, obj: dict, keys: tuple[str, ...], path: str) -> None:
        """Format 2 keeps these in `volatile`: here they would make two runs differ."""
        for key in keys:
            if key in obj:
                self.fail(_join(path, key), f"belongs in the volatile section, not here ({FORMAT})")

    def run(self, run: dict) -> None:
        for key, kinds in RUN_REQUIRED.items():
            self.key(run, key, "run", *kinds)
        known = RUN_KNOWN
        if self.old:
            self.key(run, "started", "run", "string")
            self.key(run, "duration_s", "run", "number")
            self.duration(run, "run")
            known = {**RUN_KNOWN, **VOLATILE_KNOWN}
        else:
            self.moved(run, MOVED_RUN, "run")
        for key, value in run.items():
            self.value(value, f"run.{key}", known.get(key, SCALAR))
        if isinstance(run.get("link"), dict):
            for key, kinds in LINK_KNOWN.items():
                self.key(run["link"], key, "run.link", *kinds)
            for key, kinds in LINK_OPTIONAL.items():
                self.optional(run["link"], key, "run.link", *kinds)

    def identity(self, identity: dict | None) -> None:
        if identity is None:
            return
        if "msp_api" in identity:     # an MSP flight controller's (conformance/msp/runner.py)
            self.key(identity, "msp_api", "identity", "string")
            self.key(identity, "max_waypoints", "identity", "integer")
        else:
            self.key(identity, "system", "identity", "integer")
            self.key(identity, "component", "identity", "integer")
        if not self.old:
            self.moved(identity, MOVED_IDENTITY, "identity")
        known = {**IDENTITY_KNOWN, "address": ("string", "null")} if self.old else IDENTITY_KNOWN
        for key, value in identity.items():
            self.value(value, f"identity.{key}", known.get(key, SCALAR))

    def clause(self, clause: Any, path: str) -> str:
        self.value(clause, path, ("object",))
        clause_id = self.key(clause, "id", path, "string")
        if not clause_id.strip():
            self.fail(f"{path}.id", "empty clause id")
        for key in ("group", "role", "title", "source", "requirement", "detail"):
            self.key(clause, key, path, "string")
        self.choice(clause, "level", path, LEVELS)
        self.choice(clause, "outcome", path, OUTCOMES)
        self.key(clause, "gating", path, "bool")
        self.key(clause, "expectation", path, "string", "null")
        if self.old:
            self.key(clause, "duration_s", path, "number")
            self.duration(clause, path)
        else:
            self.moved(clause, ("duration_s",), path)
        exchange = self.key(clause, "exchange", path, "array")
        for index, event in enumerate(exchange):
            self.event(event, f"{path}.exchange[{index}]")
        for key, kinds in CLAUSE_KNOWN.items():
            self.optional(clause, key, path, *kinds)
        decided = clause.get("decided_by")
        if decided is not None and not 0 <= decided < len(exchange):
            self.fail(f"{path}.decided_by", f"{decided} is not the index of an event in the "
                                            f"exchange ({len(exchange)} events)")
        return clause_id

    def event(self, event: Any, path: str, *, timed: bool = False) -> None:
        self.value(event, path, ("object",))
        if self.old or timed:
            self.key(event, "t", path, "number")
        else:
            self.moved(event, ("t",), path)
        self.choice(event, "dir", path, DIRECTIONS)
        if not self.key(event, "peer", path, "string"):
            self.fail(f"{path}.peer", "empty peer name")
        self.key(event, "msg", path, "string")
        for name, value in self.key(event, "fields", path, "object").items():
            field_path = f"{path}.fields.{name}"
            if isinstance(value, (list, tuple)):  # a MAVLink array field
                for index, item in enumerate(value):
                    self.value(item, f"{field_path}[{index}]", SCALAR)
            else:
                self.value(value, field_path, SCALAR)

    def duration(self, obj: dict, path: str) -> None:
        if obj["duration_s"] < 0:
            self.fail(f"{path}.duration_s", f"negative duration {obj['duration_s']}")

    def volatile(self, volatile: dict, clauses: list[dict]) -> None:
        for key, kinds in VOLATILE_KNOWN.items():
            (self.key if key in ("started", "duration_s") else self.optional)(
                volatile, key, "volatile", *kinds)
        self.duration(volatile, "volatile")
        if "identity" in volatile:
            for key, values in self.value(volatile["identity"], "volatile.identity", ("object",)).items():
                self.values(values, f"volatile.identity.{key}")
        if "receive_queue" in volatile:
            queue = self.value(volatile["receive_queue"], "volatile.receive_queue", ("object",))
            for key in ("dropped", "buffer_bytes"):
                if self.key(queue, key, "volatile.receive_queue", "integer", "null") is not None:
                    self.count(queue, key, "volatile.receive_queue")
        if "link" in volatile:
            link = self.value(volatile["link"], "volatile.link", ("object",))
            for key in LINK_COUNTS:
                if key in link:
                    self.key(link, key, "volatile.link", "integer")
                    self.count(link, key, "volatile.link")
            self.optional(link, "history", "volatile.link", "array")
            for i, event in enumerate(link.get("history") or []):
                if not isinstance(event, dict):
                    self.fail(f"volatile.link.history[{i}]", "expected an object")
                    continue
                self.key(event, "t", f"volatile.link.history[{i}]", "number")
                self.key(event, "event", f"volatile.link.history[{i}]", "string")
        per_clause = self.key(volatile, "clauses", "volatile", "object")
        by_id = {clause["id"]: clause for clause in clauses}
        for clause_id in per_clause:
            if clause_id not in by_id:
                self.fail(f"volatile.clauses.{clause_id}", "no clause has this id")
        for clause_id, clause in by_id.items():
            path = f"volatile.clauses.{clause_id}"
            if clause_id not in per_clause:
                self.fail("volatile.clauses", f"missing {clause_id!r}")
            entry = self.value(per_clause[clause_id], path, ("object",))
            self.key(entry, "duration_s", path, "number")
            self.duration(entry, path)
            times = self.key(entry, "events", path, "array")
            for index, t in enumerate(times):
                self.value(t, f"{path}.events[{index}]", ("number",))
            if len(times) != len(clause["exchange"]):
                self.fail(f"{path}.events", f"{len(times)} times for "
                                            f"{len(clause['exchange'])} exchange events")
            self.values(entry.get("detail", {}), f"{path}.detail")
            for index, values in self.key(entry, "notes", path, "object").items() \
                    if "notes" in entry else ():
                if not index.isdigit() or int(index) >= len(clause["exchange"]) \
                        or clause["exchange"][int(index)]["dir"] != NOTE:
                    self.fail(f"{path}.notes.{index}", "not the index of a note in the exchange")
                self.values(values, f"{path}.notes.{index}")
            self.ambient(entry, len(clause["exchange"]), path)

    def ambient(self, entry: dict, kept: int, path: str) -> None:
        """Stream events no check used, each at its index in the whole exchange (ascending;
        the kept events fill the other indices)."""
        if "ambient" not in entry:
            return
        ambient = self.key(entry, "ambient", path, "array")
        last = -1
        for index, event in enumerate(ambient):
            where = f"{path}.ambient[{index}]"
            self.event(event, where, timed=True)
            at = self.key(event, "at", where, "integer")
            if not last < at < kept + len(ambient):
                self.fail(f"{where}.at", f"{at} is not an index after {last} in an exchange of "
                                         f"{kept + len(ambient)} events")
            if event["dir"] != RX:
                self.fail(f"{where}.dir", f"an ambient event is one received ({RX!r}), not {event['dir']!r}")
            last = at

    def values(self, values: Any, path: str) -> None:
        """Measured numbers of a text, by the <name> that stands for each."""
        self.value(values, path, ("object",))
        for name, text in values.items():
            self.value(text, f"{path}.{name}", ("string",))

    def flights(self, doc: dict) -> None:
        """How the run's flights ended; one left armed is counted and cannot pass."""
        if "flights" not in doc:
            if "left_armed" in doc["summary"]:
                self.fail("summary.left_armed", "counted, but there is no flights section")
            return
        left = 0
        for index, flight in enumerate(self.key(doc, "flights", "", "array")):
            where = f"flights[{index}]"
            self.value(flight, where, ("object",))
            for key in ("clause", "style", "plan", "detail"):
                self.key(flight, key, where, "string")
            left += self.key(flight, "disarmed", where, "bool", "null") is False
        if (stated := self.count(doc["summary"], "left_armed", "summary")) != left:
            self.fail("summary.left_armed", f"{stated}, but {left} flights ended not disarmed")
        if left and doc["summary"]["verdict"] == PASS:
            self.fail("summary.verdict", "'pass', but a flight left the vehicle armed")

    def summary(self, summary: dict, clauses: list[dict]) -> None:
        if (total := self.count(summary, "total", "summary")) != len(clauses):
            self.fail("summary.total", f"{total}, but there are {len(clauses)} clauses")
        for outcome, found in outcome_counts(clauses).items():
            if (stated := self.count(summary, outcome, "summary")) != found:
                self.fail(f"summary.{outcome}",
                          f"{stated}, but {found} clauses have outcome {outcome!r}")
        gating = sum(clause["gating"] for clause in clauses)
        if (stated := self.count(summary, "gating_failures", "summary")) != gating:
            self.fail("summary.gating_failures", f"{stated}, but {gating} clauses are gating")
        self.choice(summary, "verdict", "summary", VERDICTS)


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
