"""The run document's shape, checked (`run_document.check_run`): every key the writers rely on,
of the kind they expect, with counts that agree; the first problem is one line naming where
("run.json: clauses[3].exchange[2].dir: expected one of 'tx', 'rx', 'note'")."""

from __future__ import annotations

import math
from typing import Any, NoReturn

from mavconform.reference_impl.errors import UsageError
from mavconform.reports.run_document import (
    CLAUSE_KNOWN, DIRECTIONS, FORMAT, FORMAT_1, GATING_MODES, IDENTITY_KNOWN, LEVELS, LINK_COUNTS, LINK_KNOWN,
    LINK_OPTIONAL, MOVED_IDENTITY, MOVED_RUN, NOTE, OUTCOMES, PASS, RESTORE_STATUSES, RUN_KNOWN, RUN_REQUIRED, RX,
    SCALAR, VERDICTS, VOLATILE_KNOWN, outcome_counts)


class NonFinite:
    """A NaN/Infinity literal, which JSON does not have (fields carry them as strings)."""

    def __init__(self, name: str) -> None:
        self.name = name


def refuse(source: str, path: str, problem: str) -> NoReturn:
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


class Checker:
    """Typed access to the document; every problem names its JSON path."""

    def __init__(self, source: str, format_: str = FORMAT) -> None:
        self.source = source
        self.format = format_
        self.old = format_ == FORMAT_1   # times in place, no `volatile`

    def fail(self, path: str, problem: str) -> NoReturn:
        refuse(self.source, path, problem)

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
        if isinstance(value, NonFinite) or (isinstance(value, float) and not math.isfinite(value)):
            name = value.name if isinstance(value, NonFinite) else repr(value)
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
