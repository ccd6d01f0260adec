"""Known deviations: where a codec is known to answer a vector otherwise, and why.

`known_deviations.toml` beside this module lists them (`[[deviation]]` tables with
`implementation`, `vectors` and `observed` as fnmatch patterns over the vector id and the
mismatch line, and `reason`), as the conformance suite's expectations files list a
target's known failures: a listed mismatch does not fail a check, anything else does, and
an entry that matches nothing any more is reported, so the list stays exact.
"""

from __future__ import annotations

import fnmatch
import sys
from dataclasses import dataclass
from pathlib import Path

from mavconform.reference_impl.errors import UsageError

from .verify import Mismatch, Report

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

PATH = Path(__file__).resolve().parent / "known_deviations.toml"


@dataclass(frozen=True)
class Deviation:
    implementation: str
    vectors: str
    observed: str
    reason: str

    def excuses(self, implementation: str, mismatch: Mismatch) -> bool:
        return (implementation == self.implementation and fnmatch.fnmatchcase(mismatch.vector, self.vectors)
                and fnmatch.fnmatchcase(mismatch.what, self.observed))


def load(path: Path = PATH) -> tuple[Deviation, ...]:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise UsageError(f"cannot read {path}: {exc.strerror or exc}") from None
    except tomllib.TOMLDecodeError as exc:
        raise UsageError(f"{path}: {exc}") from None
    out = []
    for n, entry in enumerate(data.get("deviation", []), 1):
        try:
            out.append(Deviation(entry["implementation"], entry["vectors"], entry["observed"], entry["reason"]))
        except (KeyError, TypeError) as exc:
            raise UsageError(f"{path}: deviation {n}: missing {exc}") from None
    return tuple(out)


@dataclass
class Sorted:
    unexpected: list[Mismatch]
    known: list[tuple[Mismatch, Deviation]]
    unused: list[Deviation]      # listed for this implementation, matched nothing


def sort(report: Report, deviations: tuple[Deviation, ...]) -> Sorted:
    mine = [d for d in deviations if d.implementation == report.implementation]
    used: set[Deviation] = set()
    out = Sorted([], [], [])
    for mismatch in report.mismatches:
        hit = next((d for d in mine if d.excuses(report.implementation, mismatch)), None)
        if hit is None:
            out.unexpected.append(mismatch)
        else:
            used.add(hit)
            out.known.append((mismatch, hit))
    out.unused = [d for d in mine if d not in used]
    return out


def counted(known: list[tuple[Mismatch, Deviation]]) -> list[tuple[Deviation, int]]:
    """Each deviation that excused something, with how many mismatches, in first-seen order."""
    counts: dict[Deviation, int] = {}
    for _, dev in known:
        counts[dev] = counts.get(dev, 0) + 1
    return list(counts.items())
