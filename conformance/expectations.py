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
An entry may hold for some kinds of vehicle only (`vehicles = ["fixed-wing", "vtol"]`, the
classes of reference_impl/vehicle_class.py): one autopilot stores or flies differently per
vehicle type, so a clause may be listed once per class, never twice for one. Which entries
apply is known once the target's HEARTBEAT says its MAV_TYPE (`Expectations.identify`);
until then, only the entries for every vehicle.
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
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from mavconform.reference_impl.errors import UsageError

from mavconform.reference_impl.vehicle_class import VehicleClass, vehicle_class

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
    vehicles: tuple[str, ...] = ()   # the vehicle classes it holds for (empty: every one)

    def holds_for(self, vehicle: str | None) -> bool:
        return not self.vehicles or vehicle in self.vehicles

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


class Expectations(Mapping[str, Deviation]):
    """An expectations file's deviations by clause, for the vehicle the run is against: the
    entries for every vehicle, and once `identify` has the target's HEARTBEAT, those for its
    class too."""

    def __init__(self, entries: list[Deviation] = (), source: str = "") -> None:
        self.entries = list(entries)
        self.source = source
        self.vehicle: str | None = None
        self._active = self._select()

    def identify(self, identity: dict | None) -> None:
        self.vehicle = vehicle_class((identity or {}).get("type")).value if identity else None
        self._active = self._select()

    def _select(self) -> dict[str, Deviation]:
        return {d.clause: d for d in self.entries if d.holds_for(self.vehicle)}

    def __getitem__(self, clause: str) -> Deviation:
        return self._active[clause]

    def __iter__(self) -> Iterator[str]:
        return iter(self._active)

    def __len__(self) -> int:
        return len(self._active)


VEHICLES = tuple(c.value for c in VehicleClass if c is not VehicleClass.OTHER)


def load(name_or_path: str) -> Expectations:
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
    out: list[Deviation] = []
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
        extra = set(entry) - {"clause", "reason", "variant", "observed", "evidence", "seen_on", "vehicles"}
        if extra:
            raise UsageError(f"{where}: unknown key {sorted(extra)[0]!r}")
        vehicles = _vehicles(entry.get("vehicles", []), where)
        for earlier in out:
            if earlier.clause == clause and (not vehicles or not earlier.vehicles
                                             or set(vehicles) & set(earlier.vehicles)):
                both = sorted(set(vehicles) & set(earlier.vehicles)) or ["every vehicle"]
                raise UsageError(f"{where}: {clause} is listed twice for {', '.join(both)}")
        texts = {}
        for key in ("variant", "observed", "evidence", "seen_on"):
            value = entry.get(key, "")
            if not isinstance(value, str):
                raise UsageError(f"{where}: {key!r} must be a string")
            texts[key] = value.strip()
        out.append(Deviation(clause, reason.strip(), **texts, vehicles=vehicles))
    return Expectations(out, str(path))


def _vehicles(value: object, where: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) and v in VEHICLES for v in value):
        raise UsageError(f"{where}: 'vehicles' must be a list of vehicle classes from "
                         f"{', '.join(VEHICLES)}, got {value!r}")
    return tuple(value)
