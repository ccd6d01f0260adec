"""A fuzz campaign: search with one mode, save each finding as a replayable case, report.

The modes (`fuzz.protocol`, `fuzz.frames`) search and shrink; this module is what they
have in common around that: the budget (examples or wall time), the progress counters, the
findings directory (`NAME.json` + `NAME.mcap` per finding, the capture taken by replaying
the case, which also proves the case reproduces), and the run document that the reports
package renders, so CI shows fuzz findings the way it shows conformance failures.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import importlib
import struct
import time
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any, Callable, Iterator

from reference_impl.errors import UsageError
from conformance.harness.exchange import MAX_EVENTS, message_fields
from reference_impl.net.capture import McapCapture
from reference_impl.net.sim import CaptureRecord
from reference_impl.wire.codec import FrameDecoder

from .case import Case, Violation, save_case

MODES = ("protocol", "frames")
SHRINK_LIMIT = 60.0          # s Hypothesis may spend shrinking one campaign's findings, at most
# What a hand-edited case can make a mode's replay raise (bad types or values in its steps).
MALFORMED = (ValueError, TypeError, KeyError, AttributeError, IndexError, OverflowError, struct.error)
MAV_AUTOPILOT_INVALID = 8    # what a GCS puts in its HEARTBEAT


def load_mode(name: str) -> ModuleType:
    """The module of a fuzz mode; it offers `search`, `replay` and `INVARIANTS`."""
    if name not in MODES:
        raise UsageError(f"unknown fuzz mode {name!r} (expected {' or '.join(MODES)})")
    return importlib.import_module(f"fuzz.{name}")


@dataclass(frozen=True)
class CampaignOptions:
    target: str
    mode: str
    seed: int = 0
    examples: int | None = None     # stop after this many examples ...
    time_s: float | None = None     # ... or after this much wall time (whichever comes first)
    findings_dir: str = "fuzz-findings"
    database: Any = None            # a Hypothesis ExampleDatabase, or None for none


@dataclass
class Progress:
    """Counters the progress bar shows; `units` are steps (protocol) or frames (frames)."""

    examples: int = 0
    units: int = 0
    findings: int = 0
    started: float = field(default_factory=time.monotonic)

    @property
    def elapsed(self) -> float:
        return time.monotonic() - self.started


@dataclass(frozen=True)
class Finding:
    case: Case
    path: Path                       # the saved case (JSON)
    capture: Path | None             # the MCAP of its replay
    replayed: Violation | None       # what replaying it showed (None: it did not reproduce)
    exchange: list[dict[str, Any]]   # the replay's frames, as report events

    @property
    def reproduced(self) -> bool:
        return (self.replayed is not None and self.case.violation is not None
                and self.replayed.invariant == self.case.violation.invariant)


@dataclass(frozen=True)
class CampaignResult:
    options: CampaignOptions
    started: dt.datetime
    examples: int
    units: int
    duration_s: float
    findings: list[Finding]
    invariants: dict[str, str]       # name -> what it asserts, for the report's rows


def run_campaign(options: CampaignOptions,
                 on_progress: Callable[[Progress], None] | None = None) -> CampaignResult:
    from conformance.target_uri import parse_target

    parse_target(options.target)     # a bad URI is the user's mistake: say so before searching
    mode = load_mode(options.mode)
    started = dt.datetime.now(dt.timezone.utc)
    progress = Progress()

    def example_done(units: int) -> None:
        progress.examples += 1
        progress.units += units
        if on_progress is not None:
            on_progress(progress)

    # A time budget bounds the search; shrinking what it found gets half as long again.
    shrink = SHRINK_LIMIT if options.time_s is None else min(SHRINK_LIMIT, max(2.0, options.time_s / 2))
    with shrink_time_limit(shrink):
        cases = mode.search(options.target, seed=options.seed, max_examples=options.examples,
                            stop_after=options.time_s, database=options.database,
                            on_example=example_done)
    duration = progress.elapsed
    findings = []
    for case in cases:
        case = Case(case.mode, case.target, case.seed, case.steps, case.violation,
                    {**case.found_by, "campaign_seed": options.seed})
        findings.append(save_finding(mode, case, options.findings_dir,
                                     minimise_until=time.monotonic() + shrink))
        progress.findings += 1
        if on_progress is not None:
            on_progress(progress)
    return CampaignResult(options, started, progress.examples, progress.units, duration,
                          findings, dict(getattr(mode, "INVARIANTS", {})))


MINIMISE_REPLAYS = 400       # bound on the replays the step-removal pass may spend per finding


@contextlib.contextmanager
def shrink_time_limit(seconds: float) -> Iterator[None]:
    """Bound the time Hypothesis spends shrinking (its own cap is 300 s per test). This sets
    a module constant of Hypothesis's engine, the only handle it offers; if a later version
    drops it, shrinking keeps Hypothesis's own cap."""
    try:
        from hypothesis.internal.conjecture import engine
    except ImportError:      # pragma: no cover - a Hypothesis without that module
        yield
        return
    if not hasattr(engine, "MAX_SHRINKING_SECONDS"):
        yield
        return
    before = engine.MAX_SHRINKING_SECONDS
    engine.MAX_SHRINKING_SECONDS = seconds
    try:
        yield
    finally:
        engine.MAX_SHRINKING_SECONDS = before


def minimise(mode: ModuleType, case: Case, budget: int = MINIMISE_REPLAYS,
             until: float | None = None) -> Case:
    """Drop every step the violation does not need, judged by replaying (in-process targets
    only, where a replay is exact and cheap). Hypothesis shrinks the program it generated;
    this pass also removes steps that stayed only because removing them changed how later
    draws were decoded. One pass from the end, repeated while it removes something."""
    from conformance.target_uri import parse_target

    if case.violation is None or not parse_target(case.target).in_process:
        return case
    want = case.violation.invariant
    steps = list(case.steps)
    best = case
    changed = True
    while changed and budget > 0:
        changed = False
        for i in reversed(range(len(steps))):
            if budget <= 0 or (until is not None and time.monotonic() >= until):
                budget = 0
                break
            budget -= 1
            trial = Case(case.mode, case.target, case.seed, tuple(steps[:i] + steps[i + 1:]),
                         case.violation, case.found_by)
            try:
                got = mode.replay(trial)
            except (UsageError, *MALFORMED):
                continue                          # the mode needs that step to read the case
            if got is not None and got.invariant == want:
                steps = list(trial.steps)
                best = Case(case.mode, case.target, case.seed, trial.steps, got, case.found_by)
                changed = True
    return best


def save_finding(mode: ModuleType, case: Case, directory: str | Path, *,
                 minimise_until: float | None = None) -> Finding:
    """Save the case, then replay it once with a capture: the MCAP beside the JSON, and the
    exchange for the report. A case that does not replay to the same invariant is kept and
    flagged, since a finding that cannot be reproduced still happened."""
    case = minimise(mode, case, until=minimise_until)
    path = save_case(case, directory)
    mcap = path.with_suffix(".mcap")
    replayed, exchange = replay_recorded(mode, case, mcap)
    return Finding(case, path, mcap, replayed, exchange)


def replay_recorded(mode: ModuleType, case: Case,
                    mcap: Path | None) -> tuple[Violation | None, list[dict[str, Any]]]:
    recorder = ExchangeRecorder()
    capture = McapCapture(mcap) if mcap is not None else None

    def hook(record: CaptureRecord) -> None:
        recorder(record)
        if capture is not None:
            capture(record)

    try:
        violation = mode.replay(case, capture=hook)
    except UsageError:
        raise
    except MALFORMED as exc:
        raise UsageError(f"the {case.mode} case for {case.target} has a malformed step "
                         f"({type(exc).__name__}: {exc})") from None
    finally:
        if capture is not None:
            capture.close()
    return violation, recorder.events


class ExchangeRecorder:
    """Capture records -> the run document's exchange events (what each side sent).

    The side whose HEARTBEAT names an autopilot is the target: what it sends is `rx`,
    everything else (the fuzzer's GCS, a second GCS, raw bytes) is `tx`. Directions are
    given at the end, when the target is known, since it may speak before its first
    HEARTBEAT. Bytes that do not decode are one note each, so garbage shows as garbage."""

    def __init__(self) -> None:
        self._raw: list[tuple[float, Any, str, str, dict[str, Any]]] = []
        self.omitted = 0
        self._decoders: dict[Any, FrameDecoder] = {}
        self._target: Any = None
        self._t0: float | None = None

    def __call__(self, record: CaptureRecord) -> None:
        if record.kind == "rx":
            return                                  # each datagram once: when it was sent
        if self._t0 is None:
            self._t0 = record.time
        t = round(record.time - self._t0, 6)
        if record.kind == "drop":
            self._add(t, record.src, "note", f"link dropped {len(record.data)} bytes", {})
            return
        decoder = self._decoders.setdefault(record.src, FrameDecoder())
        decoded = 0
        for frame in decoder.feed(record.data):
            msg = getattr(frame, "msg", None)
            if msg is None:                          # a DecodeError
                continue
            decoded += 1
            name = msg.get_type()
            if (name == "HEARTBEAT" and self._target is None
                    and getattr(msg, "autopilot", MAV_AUTOPILOT_INVALID) != MAV_AUTOPILOT_INVALID):
                self._target = record.src
            if name in ("HEARTBEAT", "GLOBAL_POSITION_INT"):
                continue
            self._add(t, record.src, "", name, message_fields(msg))
        if not decoded:
            self._add(t, record.src, "note",
                      f"{len(record.data)} bytes that decode to no frame: {record.data[:24].hex()}"
                      + ("..." if len(record.data) > 24 else ""), {})

    @property
    def events(self) -> list[dict[str, Any]]:
        out = [{"t": t, "dir": kind or ("rx" if src == self._target else "tx"),
                "peer": self._label(src), "msg": msg, "fields": fields}
               for t, src, kind, msg, fields in self._raw]
        if self.omitted:
            last = out[-1]["t"] if out else 0.0
            out.append({"t": last, "dir": "note", "peer": "fuzzer",
                        "msg": f"... {self.omitted} more events in the MCAP capture", "fields": {}})
        return out

    def _label(self, src: Any) -> str:
        if src == self._target:
            return "target"
        return src if isinstance(src, str) else ":".join(map(str, src))

    def _add(self, t: float, src: Any, kind: str, msg: str, fields: dict[str, Any]) -> None:
        if len(self._raw) >= MAX_EVENTS:      # the MCAP keeps them all
            self.omitted += 1
            return
        self._raw.append((t, src, kind, msg, fields))


def parse_duration(text: str) -> float:
    """'90', '90s', '2m', '1h', '1.5m' -> seconds; anything else is a UsageError."""
    raw = text.strip().lower()
    factor = {"s": 1.0, "m": 60.0, "h": 3600.0}.get(raw[-1:], None)
    number = raw[:-1] if factor is not None else raw
    try:
        value = float(number) * (factor or 1.0)
    except ValueError:
        raise UsageError(f"bad duration {text!r}: expected seconds, e.g. 60, 60s, 5m or 1h") from None
    if not value > 0 or value == float("inf"):
        raise UsageError(f"bad duration {text!r}: must be a positive, finite time")
    return value
