"""Expectation files: the clauses a given autopilot is known to fail, how, and why.

    # conformance/expectations/px4.toml
    [[deviation]]
    clause = "MIS.UP.09"
    variant = "P3"                      # VARIANTS.md row (or the profile's own id)
    reason = "uncapped 250 ms retries until the 5 s protocol timeout"
    observed = "the item due was requested again * times; expected at most *"
    evidence = "the item due was requested again 19 times; expected at most 5"
    seen_on = "PX4 v1.16.0 SITL (SIH), 2026-11-23"

`--expect NAME` reads conformance/expectations/NAME.toml; `--expect PATH` reads a file.
A clause listed here that fails is a known deviation, but only the failure it names:
`observed` is the verdict's detail with its numbers, ids and quoted values as `*`
(fnmatch), so a different failure of the same clause still fails the run. An entry
without `observed` excuses any failure of its clause. One that passes is reported as
"deviation no longer observed", so the files cannot silently go stale.
`mavconform report expectations RUN.json` drafts such a file from a run.
"""

from __future__ import annotations

import fnmatch
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from mavconform.reference_impl.errors import UsageError

from .catalogue import BY_ID

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

BUNDLED = Path(__file__).parent / "expectations"


OTHER_FAILURE_PREFIX = "fails otherwise than the known deviation"
_VARIABLE = re.compile(r"0x[0-9a-fA-F]+|-?\d+(?:\.\d+)?(?:e[+-]?\d+)?")
_STARS = re.compile(r"\*(?:[ ,.]*\*)+")


def observed_pattern(detail: str) -> str:
    """What a failure looked like, with what varies run to run (counts, times, positions,
    ids) as `*`: the fnmatch pattern an expectation names. Brackets are escaped."""
    pattern = _STARS.sub("*", _VARIABLE.sub("*", detail))
    return pattern.replace("[", "[[]")


@dataclass(frozen=True)
class Deviation:
    clause: str
    reason: str
    variant: str = ""
    observed: str = ""        # fnmatch pattern of the failure it excuses ("": any failure)
    evidence: str = ""        # the failure it was made from, as the run reported it
    seen_on: str = ""         # the target (autopilot and version) it was seen on

    def describe(self) -> str:
        return f"{self.variant}: {self.reason}" if self.variant else self.reason

    def excuses(self, detail: str) -> bool:
        return not self.observed or fnmatch.fnmatchcase(detail, self.observed)


def resolve(name_or_path: str) -> Path:
    path = Path(name_or_path)
    if path.suffix != ".toml" and "/" not in name_or_path and not path.is_file():
        bundled = BUNDLED / f"{name_or_path}.toml"
        if bundled.is_file():
            return bundled
        known = ", ".join(sorted(p.stem for p in BUNDLED.glob("*.toml"))) or "none"
        raise UsageError(f"--expect {name_or_path!r}: no such expectations file or bundled name "
                         f"(bundled: {known})")
    return path


def load(name_or_path: str) -> dict[str, Deviation]:
    path = resolve(name_or_path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read expectations file {str(path)!r}: {exc.strerror}") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise UsageError(f"{path}: not valid TOML: {exc}") from None
    entries = data.get("deviation", [])
    if not isinstance(entries, list):
        raise UsageError(f"{path}: 'deviation' must be an array of tables ([[deviation]])")
    unknown = set(data) - {"deviation", "description"}
    if unknown:
        raise UsageError(f"{path}: unknown key {sorted(unknown)[0]!r} (expected [[deviation]] tables)")
    out: dict[str, Deviation] = {}
    for i, entry in enumerate(entries):
        where = f"{path}: deviation[{i}]"
        if not isinstance(entry, dict):
            raise UsageError(f"{where}: must be a table")
        clause, reason = entry.get("clause"), entry.get("reason")
        if "clause" not in entry:
            raise UsageError(f"{where}: missing 'clause' (the clause id, e.g. \"MIS.UP.04\")")
        if not isinstance(clause, str):
            raise UsageError(f"{where}: 'clause' must be a clause id string, got {clause!r}")
        if clause not in BY_ID:
            raise UsageError(f"{where}: unknown clause {clause!r} (see `mavconform clauses`)")
        if not isinstance(reason, str) or not reason.strip():
            raise UsageError(f"{where}: 'reason' must be a non-empty string")
        extra = set(entry) - {"clause", "reason", "variant", "observed", "evidence", "seen_on"}
        if extra:
            raise UsageError(f"{where}: unknown key {sorted(extra)[0]!r}")
        if clause in out:
            raise UsageError(f"{where}: {clause} is listed twice")
        texts = {}
        for key in ("variant", "observed", "evidence", "seen_on"):
            value = entry.get(key, "")
            if not isinstance(value, str):
                raise UsageError(f"{where}: {key!r} must be a string")
            texts[key] = value.strip()
        out[clause] = Deviation(clause, reason.strip(), **texts)
    return out
