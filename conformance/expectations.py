"""Expectation files: the clauses a given autopilot is known to fail, and why.

    # conformance/expectations/px4.toml
    [[deviation]]
    clause = "MIS.CAN.01"
    variant = "P2"                      # VARIANTS.md row
    reason = "upload cancellation is ignored; the vehicle times out by itself"

`--expect NAME` reads conformance/expectations/NAME.toml; `--expect PATH` reads a file.
A clause listed here that fails is a known deviation; one that passes is reported as
"deviation no longer observed", so the files cannot silently go stale.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

from reference_impl.errors import UsageError

from .catalogue import BY_ID

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

BUNDLED = Path(__file__).parent / "expectations"


@dataclass(frozen=True)
class Deviation:
    clause: str
    reason: str
    variant: str = ""

    def describe(self) -> str:
        return f"{self.variant}: {self.reason}" if self.variant else self.reason


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
        if not isinstance(clause, str) or clause not in BY_ID:
            raise UsageError(f"{where}: unknown clause {clause!r}")
        if not isinstance(reason, str) or not reason.strip():
            raise UsageError(f"{where}: 'reason' must be a non-empty string")
        extra = set(entry) - {"clause", "reason", "variant"}
        if extra:
            raise UsageError(f"{where}: unknown key {sorted(extra)[0]!r}")
        if clause in out:
            raise UsageError(f"{where}: {clause} is listed twice")
        out[clause] = Deviation(clause, reason.strip(), str(entry.get("variant", "")))
    return out
