"""A fuzz case: what a campaign found, as data that replays without Hypothesis.

Hypothesis searches and shrinks; what it finally reports is turned into a `Case`: the mode,
the target, the seed of the virtual network, and the shrunk list of steps, each a small
JSON object the mode's `replay` knows how to apply. Replaying a case against an in-process
target (`builtin:` or `mutant:`) in virtual time repeats it exactly: same seed, same
schedule, same bytes. Against a UDP target it repeats the same steps, as closely as a real
network allows.

On disk a case is `NAME.json` (format "mavconform-fuzz-case/1", canonical) beside
`NAME.mcap`, the capture of the exchange as it last ran.
"""

from __future__ import annotations

import hashlib
import json
import math
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mavconform.reference_impl.errors import UsageError

FORMAT = "mavconform-fuzz-case/1"
# What a hand-edited case can make a mode's replay raise (bad types or values in its steps).
MALFORMED = (ValueError, TypeError, KeyError, AttributeError, IndexError, OverflowError, struct.error)
MODES = ("protocol", "frames")
# One-way latency of every simulated link an in-process campaign runs over: a reply then
# comes after its request, as on a real link, so a finding's diagram reads in time, not all
# at one instant. A case records it (`found_by.latency`); a case saved before it existed has
# none and replays as it was found, over links with no latency.
LINK_LATENCY = 0.01


def case_latency(found_by: dict[str, Any]) -> float:
    """The link latency a saved case was found with (0 for cases older than `LINK_LATENCY`)."""
    latency = found_by.get("latency", 0.0)
    if isinstance(latency, bool) or not isinstance(latency, (int, float)) or not 0 <= latency <= 1:
        raise UsageError(f"found_by.latency: expected seconds in [0, 1], got {latency!r:.40}")
    return float(latency)


@dataclass(frozen=True)
class Violation:
    """A broken oracle, in plain words: which invariant, and what was seen."""

    invariant: str            # a short stable name, e.g. "atomic-upload", "target-crash"
    detail: str               # one or two sentences a reader understands without the source
    step: int | None = None   # index of the step after which it was seen (None: at the end)

    def __str__(self) -> str:
        where = f" after step {self.step}" if self.step is not None else ""
        return f"{self.invariant}{where}: {self.detail}"


@dataclass(frozen=True)
class Case:
    mode: str                                  # "protocol" | "frames"
    target: str                                # target URI text, e.g. "builtin:spec"
    seed: int                                  # seeds the virtual network and every random choice
    steps: tuple[dict[str, Any], ...]          # mode-specific, JSON-safe
    violation: Violation | None = None         # what it broke when it was found
    found_by: dict[str, Any] = field(default_factory=dict)  # campaign seed, example number, ...

    @property
    def name(self) -> str:
        """Stable file stem: the mode, the invariant and a digest of what replays."""
        digest = hashlib.sha256(json.dumps(
            [self.mode, self.target, self.seed, list(self.steps)], sort_keys=True,
            default=_json_default).encode()).hexdigest()[:10]
        what = self.violation.invariant if self.violation else "case"
        return f"{self.mode}-{what}-{digest}"

    def to_json(self) -> dict[str, Any]:
        return {
            "format": FORMAT,
            "mode": self.mode,
            "target": self.target,
            "seed": self.seed,
            "steps": [dict(s) for s in self.steps],
            "violation": None if self.violation is None else {
                "invariant": self.violation.invariant, "detail": self.violation.detail,
                "step": self.violation.step},
            "found_by": dict(self.found_by),
        }


def dump_case(case: Case) -> str:
    """Canonical JSON (sorted keys, fixed indent, non-finite floats spelled out)."""
    return json.dumps(_encode(case.to_json()), indent=2, sort_keys=True, allow_nan=False) + "\n"


def save_case(case: Case, directory: str | Path) -> Path:
    """Write `DIR/NAME.json`; returns its path (the caller writes `NAME.mcap` beside it)."""
    out = Path(directory)
    try:
        out.mkdir(parents=True, exist_ok=True)
        path = out / f"{case.name}.json"
        path.write_text(dump_case(case), encoding="utf-8")
    except OSError as exc:
        raise UsageError(f"cannot write fuzz case in {out}: {exc.strerror or exc}") from None
    return path


def load_case(path: str | Path) -> Case:
    """Read a saved case; anything wrong is one `UsageError` line naming the file and key."""
    p = Path(path)
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read fuzz case {p}: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsageError(f"{p}: not a JSON fuzz case ({exc})") from None
    doc = _decode(doc)

    def bad(where: str, why: str) -> UsageError:
        return UsageError(f"{p}: {where}: {why}")

    if not isinstance(doc, dict):
        raise bad("$", "expected a JSON object")
    if doc.get("format") != FORMAT:
        raise bad("$.format", f"expected {FORMAT!r}, got {doc.get('format')!r}")
    mode, target, seed, steps = doc.get("mode"), doc.get("target"), doc.get("seed"), doc.get("steps")
    if mode not in MODES:
        raise bad("$.mode", f"expected one of {', '.join(MODES)}, got {mode!r}")
    if not isinstance(target, str) or not target:
        raise bad("$.target", "expected a target URI string")
    if not isinstance(seed, int) or isinstance(seed, bool):
        raise bad("$.seed", "expected an integer")
    if not isinstance(steps, list) or not all(isinstance(s, dict) for s in steps):
        raise bad("$.steps", "expected a list of objects")
    violation = None
    v = doc.get("violation")
    if v is not None:
        if not (isinstance(v, dict) and isinstance(v.get("invariant"), str)
                and isinstance(v.get("detail"), str)
                and (v.get("step") is None or isinstance(v.get("step"), int))):
            raise bad("$.violation", "expected {invariant: str, detail: str, step: int|null}")
        violation = Violation(v["invariant"], v["detail"], v.get("step"))
    found_by = doc.get("found_by") or {}
    if not isinstance(found_by, dict):
        raise bad("$.found_by", "expected an object")
    return Case(mode, target, seed, tuple(steps), violation, found_by)


# JSON has no NaN or infinity, and fuzz steps are full of them: spell them as {"float": "nan"}.
def _encode(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return {"float": repr(value)}
    if isinstance(value, (bytes, bytearray)):
        return {"hex": bytes(value).hex()}
    if isinstance(value, dict):
        return {str(k): _encode(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_encode(v) for v in value]
    return value


def _decode(value: Any) -> Any:
    if isinstance(value, dict):
        if set(value) == {"float"} and value["float"] in ("nan", "inf", "-inf"):
            return float(value["float"])
        if set(value) == {"hex"} and isinstance(value["hex"], str):
            try:
                return bytes.fromhex(value["hex"])
            except ValueError:
                return value
        return {k: _decode(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_decode(v) for v in value]
    return value


def _json_default(value: Any) -> Any:
    encoded = _encode(value)
    if encoded is value:
        raise TypeError(f"not JSON-safe: {type(value).__name__}")
    return encoded
