"""Handover scenario files: who covers what, the flight, the refuges, the links (seed 003, 4.1).

The thesis's mission computer had its mission "written directly on code" and names the file
it should have read instead: waypoints, rally points, GCS parameters, GCS geofences (4.3.1).
`mavconform handover run SCENARIO` reads that file, in JSON (or YAML when PyYAML is
installed), into a frozen `Scenario`; docs/handover-scenarios.md is the schema, and the
shipped examples (`SCENARIOS_DIR`) fly the thesis's delivery under each region method.

Every mistake is one `ScenarioError` line naming the file and the field path, e.g.
`delivery.json: gcs[1].coverage.polygon[2][0]: latitude 95 is outside [-90, 90]`; the CLI
turns it into exit code 2. Coverage entries are read by `regions.coverage_of` (its format,
its messages). `scenario_to_dict` gives the loaded scenario back as plain data for a run
report to echo; signing keys appear there only as a fingerprint unless asked for. Each field
is checked in scenario_fields.py; this module holds the model, reading and echoing.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn, Sequence

from ..errors import UsageError
from ..net.faults import FaultModel, parse_drop_rule
from ..wire.signing import SigningKey
from .emergency import BatteryModel, BatteryState, TriggerPolicy
from .geo import GeoPoint, haversine_m
from .regions import (Coverage, Intersection, RegionMethod, WaypointOwnership)

__all__ = ["FORMAT", "SCENARIOS_DIR", "Flight", "GcsSpec", "LinkFaults", "Scenario", "ScenarioError", "Timeouts",
           "Waypoint", "load_scenario", "scenario_from_dict", "scenario_to_dict"]

FORMAT = "mavconform-handover-scenario/1"
SCENARIOS_DIR = Path(__file__).parent / "scenarios"
YAML_SUFFIXES = (".yaml", ".yml")
SYSID_MAX = 255
SEED_LIMIT = 2**64
# the keys of a link's faults and of the timeouts, as a file spells them (scenario_fields.py reads
# them, scenario_to_dict writes them back)
FAULT_KEYS = ("loss", "duplicate", "reorder", "reorder_delay", "delay", "jitter", "corrupt", "partitions", "drop")
TIMEOUT_KEYS = ("dwell_s", "handover_bound_s", "loss_timeout_s", "outside_grace_s", "max_duration_s")


class ScenarioError(UsageError):
    """A scenario file that cannot be used. `str()` is one line: `FILE: field.path: problem`."""

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(message.splitlines()))


# --- the loaded scenario -------------------------------------------------------------------

@dataclass(frozen=True)
class LinkFaults:
    """One direction of a GCS's link, as `FaultModel`'s fields (seconds, probabilities).

    Frozen data, not a `FaultModel`: that one keeps rule counters, so each run takes a fresh
    one from `model()`.
    """

    loss: float = 0.0
    duplicate: float = 0.0
    reorder: float = 0.0
    reorder_delay: float = 0.05
    delay: float = 0.0
    jitter: float = 0.0
    corrupt: float = 0.0
    partitions: tuple[tuple[float, float], ...] = ()
    drop: tuple[str, ...] = ()     # scripted drops: NAME, NAME#N or NAME#N+ (as `--drop`)

    def model(self) -> FaultModel:
        """A fresh fault model for one direction of the link."""
        return FaultModel(loss=self.loss, duplicate=self.duplicate, reorder=self.reorder,
                          reorder_delay=self.reorder_delay, delay=self.delay, jitter=self.jitter,
                          corrupt=self.corrupt, partitions=self.partitions,
                          rules=tuple(parse_drop_rule(r) for r in self.drop))


@dataclass(frozen=True)
class GcsSpec:
    """One ground station: its name (used for parent and ownership), system id, key, coverage, link."""

    name: str
    sysid: int
    signing: SigningKey | None
    coverage: Coverage
    up: LinkFaults = LinkFaults()      # GCS -> vehicle
    down: LinkFaults = LinkFaults()    # vehicle -> GCS


@dataclass(frozen=True)
class Waypoint:
    """A point the flight passes: `seq` is what MISSION_CURRENT / MISSION_ITEM_REACHED say.

    For a `path` flight seq is the index in the path; for a .plan flight it is the mission
    item's seq. `point.alt` is metres above home.
    """

    seq: int
    point: GeoPoint


@dataclass(frozen=True)
class Flight:
    """The planned route, flown at `speed_m_s`; a waypoint counts as reached within the radius."""

    waypoints: tuple[Waypoint, ...]
    speed_m_s: float
    acceptance_radius_m: float
    plan: str | None = None            # the .plan file as the scenario names it, if from one

    def length_m(self) -> float:
        """Horizontal length of the route, waypoint to waypoint."""
        pts = [w.point for w in self.waypoints]
        return sum(haversine_m(a, b) for a, b in zip(pts, pts[1:]))

    def seqs(self) -> tuple[int, ...]:
        return tuple(w.seq for w in self.waypoints)


@dataclass(frozen=True)
class Timeouts:
    """The scenario's clock: how long to dwell in the handover region before starting it, how
    long a handover may take, how long a silent commander is tolerated, how long outside every
    coverage, and when the whole run stops (every wait has a deadline)."""

    dwell_s: float = 0.0
    handover_bound_s: float = 10.0
    loss_timeout_s: float = 5.0
    outside_grace_s: float = 0.0
    max_duration_s: float = 0.0        # 0 in a file: derived from the flight (see `_timeouts`)

    def triggers(self) -> TriggerPolicy:
        """The emergency triggers these timeouts define."""
        return TriggerPolicy(self.loss_timeout_s, self.outside_grace_s)


@dataclass(frozen=True)
class Scenario:
    """A handover scenario, checked: every name resolves, every number is in range."""

    name: str
    description: str
    seed: int
    region_method: RegionMethod
    vehicle_sysid: int
    gcs: tuple[GcsSpec, ...]
    parent: str
    home: GeoPoint
    flight: Flight
    rally: tuple[GeoPoint, ...]
    battery: BatteryModel
    initial_battery: BatteryState
    timeouts: Timeouts
    source: str = field(default="", compare=False)   # the file, as given, for messages

    def gcs_named(self, name: str) -> GcsSpec:
        for g in self.gcs:
            if g.name == name:
                return g
        raise KeyError(name)

    @property
    def geographic(self) -> bool:
        """Coverage is a place (circle, polygon), not a set of waypoints."""
        return self.region_method is not RegionMethod.WAYPOINTS

    def covering(self, point: GeoPoint) -> tuple[str, ...]:
        """Names of the GCSs whose coverage holds `point` (none under the waypoint method)."""
        if not self.geographic:
            return ()
        return tuple(g.name for g in self.gcs if g.coverage.contains(point))  # type: ignore[union-attr]

    def handover_regions(self) -> tuple[tuple[str, str, Intersection], ...]:
        """(a, b, region) for every pair of GCSs, in file order; () under the waypoint method."""
        if not self.geographic:
            return ()
        return tuple((a.name, b.name, Intersection((a.coverage, b.coverage)))  # type: ignore[arg-type]
                     for i, a in enumerate(self.gcs) for b in self.gcs[i + 1:])

    def ownership(self) -> WaypointOwnership | None:
        """Waypoint seq -> GCS name under the waypoint method, else None."""
        if self.geographic:
            return None
        return WaypointOwnership.from_coverages({g.name: g.coverage for g in self.gcs})  # type: ignore[misc]


# --- reading -------------------------------------------------------------------------------

def shipped_scenarios() -> dict[str, Path]:
    """The scenarios shipped in the package, by name: delivery_flight_circles.json is
    `delivery-flight-circles`."""
    return {p.stem.replace("_", "-"): p for p in sorted(SCENARIOS_DIR.glob("*.json"))}


def scenario_path(text: str) -> Path:
    """A scenario as a user names it: a file, else the name of a shipped one (a file wins,
    but a folder of that name, such as a checkout's `conformance/`, does not)."""
    path = Path(text)
    if path.is_file():
        return path
    shipped = shipped_scenarios()
    if text in shipped:
        return shipped[text]
    raise ScenarioError(f"{text}: no such scenario file (shipped scenarios: {', '.join(shipped)})")


def load_scenario(path: str | Path) -> Scenario:
    """Read and check a scenario file (.json, or .yaml/.yml with PyYAML); a .plan it names is
    found relative to the scenario file."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as error:
        raise ScenarioError(f"{source}: cannot read: not UTF-8 text ({error.reason})") from None
    except OSError as error:
        raise ScenarioError(f"{source}: cannot read: {error.strerror or error}") from None
    if Path(path).suffix.lower() in YAML_SUFFIXES:
        data = _parse_yaml(text, source)
    else:
        data = _parse_json(text, source)
    return scenario_from_dict(data, source=source, base_dir=Path(path).parent)


def _parse_json(text: str, source: str) -> Any:
    def no_duplicates(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
        obj: dict[str, Any] = {}
        for key, value in pairs:
            if key in obj:
                raise ScenarioError(f"{source}: key {key!r} appears twice in one object")
            obj[key] = value
        return obj

    def no_constant(name: str) -> NoReturn:
        raise ScenarioError(f"{source}: {name} is not a number JSON allows")

    try:
        return json.loads(text, object_pairs_hook=no_duplicates, parse_constant=no_constant)
    except json.JSONDecodeError as error:
        raise ScenarioError(f"{source}: line {error.lineno} column {error.colno}: invalid JSON: {error.msg}") from None


def _parse_yaml(text: str, source: str) -> Any:
    try:
        import yaml
    except ImportError:
        raise ScenarioError(f"{source}: reading YAML needs PyYAML (pip install pyyaml); "
                            f"or write the scenario as JSON") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f"line {mark.line + 1} column {mark.column + 1}: " if mark is not None else ""
        problem = getattr(error, "problem", None) or str(error)
        raise ScenarioError(f"{source}: {where}invalid YAML: {problem}") from None


def scenario_from_dict(data: Any, *, source: str = "scenario", base_dir: str | Path = ".") -> Scenario:
    """Check plain data (a parsed file) and build the `Scenario`; `source` prefixes every error."""
    from .scenario_fields import scenario_of   # it builds this module's types
    try:
        return scenario_of(data, source, Path(base_dir))
    except ScenarioError:
        raise
    except UsageError as error:
        raise ScenarioError(f"{source}: {error}") from None


def seq_ranges(seqs: Sequence[int], dash: str = "..") -> str:
    """[0, 1, 2, 5, 7, 8] -> '0..2, 5, 7..8' (sorted seqs)."""
    parts: list[str] = []
    i = 0
    while i < len(seqs):
        j = i
        while j + 1 < len(seqs) and seqs[j + 1] == seqs[j] + 1:
            j += 1
        parts.append(str(seqs[i]) if i == j else f"{seqs[i]}{dash}{seqs[j]}")
        i = j + 1
    return ", ".join(parts)


# --- echo ----------------------------------------------------------------------------------

def scenario_to_dict(s: Scenario, *, secrets: bool = False) -> dict[str, Any]:
    """The scenario as plain data in the file's own schema, for a run report to echo.

    Keys are the file's, values as loaded (defaults filled in, home and rally resolved). Signing
    keys appear as `{"fingerprint": first 8 hex digits of SHA-256(key)}` unless `secrets`, when
    they are `key` (hex) and the result reads back (`scenario_from_dict`) to an equal scenario.
    """
    flight: dict[str, Any] = {"speed_m_s": s.flight.speed_m_s,
                              "acceptance_radius_m": s.flight.acceptance_radius_m}
    if s.flight.plan is not None:
        flight["plan"] = s.flight.plan
    else:
        flight["path"] = [_coords(w.point) for w in s.flight.waypoints]
    return {
        "format": FORMAT,
        "name": s.name,
        "description": s.description,
        "seed": s.seed,
        "region_method": s.region_method.value,
        "vehicle": {"sysid": s.vehicle_sysid},
        "gcs": [_gcs_dict(g, s.region_method, secrets) for g in s.gcs],
        "parent": s.parent,
        "home": _coords(s.home),
        "flight": flight,
        "rally": [_coords(p) for p in s.rally],
        "battery": {"capacity_wh": s.battery.capacity_wh, "consumption_wh_per_m": s.battery.consumption_wh_per_m,
                    "reserve_wh": s.battery.reserve_wh, "initial_wh": s.initial_battery.remaining_wh},
        "timeouts": {k: getattr(s.timeouts, k) for k in TIMEOUT_KEYS},
    }


def _coords(p: GeoPoint) -> list[float]:
    out = [float(p.lat), float(p.lon)]
    return out if p.alt is None else out + [p.alt]


def _gcs_dict(g: GcsSpec, method: RegionMethod, secrets: bool) -> dict[str, Any]:
    cov = g.coverage
    if method is RegionMethod.CIRCLE:
        coverage: Any = {"center": _coords(cov.center), "radius_m": cov.radius_m}  # type: ignore[union-attr]
    elif method is RegionMethod.POLYGON:
        coverage = [_coords(v) for v in cov.vertices]  # type: ignore[union-attr]
    else:
        coverage = sorted(cov.seqs)  # type: ignore[union-attr]
    out: dict[str, Any] = {"name": g.name, "sysid": g.sysid}
    if g.signing is not None:
        key = ({"key": g.signing.secret.hex()} if secrets
               else {"fingerprint": hashlib.sha256(g.signing.secret).hexdigest()[:8]})
        out["signing"] = {**key, "link_id": g.signing.link_id}
    out["coverage"] = {method.value: coverage}
    if g.up == g.down:
        if g.up != LinkFaults():
            out["link"] = _faults_dict(g.up)
    else:
        out["link"] = {"up": _faults_dict(g.up), "down": _faults_dict(g.down)}
    return out


def _faults_dict(f: LinkFaults) -> dict[str, Any]:
    base = LinkFaults()
    out: dict[str, Any] = {}
    for key in FAULT_KEYS:
        value = getattr(f, key)
        if value != getattr(base, key):
            out[key] = [list(w) for w in value] if key == "partitions" else list(value) if key == "drop" else value
    return out
