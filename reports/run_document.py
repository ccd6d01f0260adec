"""The run document ("mavconform-run/1"): what a conformance run found, as plain JSON.

The runner builds it; every report is a pure function of it. `load_run` checks the shape
once, here, so the writers can index it without guarding each key, and a bad RUN.json is
a one-line `UsageError` naming the file and the JSON path, never a traceback from a writer.
`dump_run` is canonical (sorted keys, fixed indent) so that two runs diff cleanly.

Shape (keys the writers rely on; objects may carry more keys, which are kept):

    format    "mavconform-run/1"
    tool      {name, version}
    run       {target, started, duration_s, ...scalars: seed, time_scale, strict, ...,
               [interrupted: bool, interrupted_at: clause id or phase, interrupted_by: SIGTERM]}
    identity  {system, component, [type, autopilot, mavlink_version, address]} or null
    summary   {total, <one count per outcome>, gating_failures, verdict: pass|fail|interrupted}
    gating    {mode: strict|default|baseline, regressions: [id], fixed: [id]}
    restore   {status: restored|unchanged|failed|skipped, detail}
    capture   file name of the MCAP capture, or null
    clauses   [{id, group, level, role, title, source, requirement, outcome, gating,
                detail, expectation, duration_s,
                exchange: [{t, dir: tx|rx|note, peer, msg, fields: {name: scalar}}]}]

The summary counts must agree with the clauses, so no report shows two different totals,
and a run marked interrupted cannot have the verdict "pass" (what it did not reach is not
known to pass).
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any, NoReturn

from mavconform.reference_impl.errors import UsageError

FORMAT = "mavconform-run/1"

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

TX, RX, NOTE = "tx", "rx", "note"  # tester sent, tester received from the target, commentary
DIRECTIONS = (TX, RX, NOTE)

# run keys every writer shows by name; the rest of `run` is shown as it comes.
RUN_REQUIRED = {"target": ("string",), "started": ("string",), "duration_s": ("number",)}
RUN_KNOWN = {"seed": ("integer", "null"), "time_scale": ("number",), "strict": ("bool",),
             "clauses": ("string",), "expectations": ("string", "null"),
             "baseline": ("string", "null"), "forced_wait_s": ("number", "null"),
             "interrupted": ("bool",), "interrupted_at": ("string", "null"),
             "interrupted_by": ("string", "null")}
IDENTITY_KNOWN = {"type": ("integer",), "autopilot": ("integer",),
                  "mavlink_version": ("integer",), "address": ("string", "null")}
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
    return check_run(document, source)


def check_run(doc: Any, source: str = "run document") -> dict[str, Any]:
    """`doc` itself if it has the shape the writers rely on; else a one-line `UsageError`
    "SOURCE: json.path: problem". Also for a document built in memory by the runner."""
    _Checker(source).document(doc)
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

    def __init__(self, source: str) -> None:
        self.source = source

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
        if (found := doc["format"]) != FORMAT:
            shown = _short(found) if isinstance(found, str) else _describe(found)
            self.fail("format", f"expected {FORMAT!r}, found {shown}")
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
        if doc["run"].get("interrupted") and doc["summary"]["verdict"] == PASS:
            self.fail("summary.verdict", "'pass', but run.interrupted is true: an interrupted "
                                         "run is not known to pass")

    def run(self, run: dict) -> None:
        for key, kinds in RUN_REQUIRED.items():
            self.key(run, key, "run", *kinds)
        for key, value in run.items():
            self.value(value, f"run.{key}", RUN_KNOWN.get(key, SCALAR))
        if run["duration_s"] < 0:
            self.fail("run.duration_s", f"negative duration {run['duration_s']}")

    def identity(self, identity: dict | None) -> None:
        if identity is None:
            return
        self.key(identity, "system", "identity", "integer")
        self.key(identity, "component", "identity", "integer")
        for key, value in identity.items():
            self.value(value, f"identity.{key}", IDENTITY_KNOWN.get(key, SCALAR))

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
        if self.key(clause, "duration_s", path, "number") < 0:
            self.fail(f"{path}.duration_s", f"negative duration {clause['duration_s']}")
        for index, event in enumerate(self.key(clause, "exchange", path, "array")):
            self.event(event, f"{path}.exchange[{index}]")
        return clause_id

    def event(self, event: Any, path: str) -> None:
        self.value(event, path, ("object",))
        self.key(event, "t", path, "number")
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
