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
report to echo; signing keys appear there only as a fingerprint unless asked for.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, NoReturn, Sequence

from ..errors import UsageError
from ..net.faults import FaultModel, parse_drop_rule
from ..wire.signing import SigningKey, secret_from_hex, secret_from_passphrase
from .emergency import BatteryModel, BatteryState, TriggerPolicy
from .geo import GeoPoint, haversine_m
from .regions import (Coverage, Intersection, OwnedWaypoints, RegionMethod, WaypointOwnership, _list, _number,
                      _point, _show, coverage_of)

__all__ = ["FORMAT", "SCENARIOS_DIR", "Flight", "GcsSpec", "LinkFaults", "Scenario", "ScenarioError", "Timeouts",
           "Waypoint", "load_scenario", "scenario_from_dict", "scenario_to_dict"]

FORMAT = "mavconform-handover-scenario/1"
SCENARIOS_DIR = Path(__file__).parent / "scenarios"
YAML_SUFFIXES = (".yaml", ".yml")
SYSID_MAX = 255
SEED_LIMIT = 2**64


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
    try:
        return _scenario(data, source, Path(base_dir))
    except ScenarioError:
        raise
    except UsageError as error:
        raise ScenarioError(f"{source}: {error}") from None


def _fail(path: str, problem: str) -> NoReturn:
    raise UsageError(f"{path}: {problem}" if path else problem)


def _obj(value: Any, path: str, allowed: tuple[str, ...], required: tuple[str, ...] = ()) -> Mapping[str, Any]:
    """An object with only `allowed` keys and every `required` one."""
    if not isinstance(value, Mapping):
        _fail(path, f"expected an object, got {_show(value)}")
    for key in value:
        if key not in allowed:
            _fail(path, f"unknown field {_show(key)} (expected {', '.join(allowed)})")
    for key in required:
        if key not in value:
            _fail(_join(path, key), "missing")
    return value


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def _float(value: Any, path: str, *, low: float = 0.0, high: float = math.inf, low_open: bool = False) -> float:
    x = float(_number(value, path))
    if x < low or (low_open and x == low) or x > high:
        bounds = (f"more than {low:g}" if low_open else f"at least {low:g}") + (f" and at most {high:g}"
                                                                              if high < math.inf else "")
        _fail(path, f"must be {bounds}, got {x:g}")
    return x


def _int(value: Any, path: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        _fail(path, f"expected an integer, got {_show(value)}")
    if not low <= value <= high:
        _fail(path, f"{value} is outside {low}..{high}")
    return value


def _str(value: Any, path: str) -> str:
    if not isinstance(value, str):
        _fail(path, f"expected a string, got {_show(value)}")
    return value


def _position(value: Any, path: str) -> GeoPoint:
    """[lat, lon, alt]: alt is required for places the vehicle flies to."""
    point = _point(value, path)
    if point.alt is None:
        _fail(path, "expected [lat, lon, alt] (alt: metres above home)")
    return point


TOP_KEYS = ("format", "name", "description", "seed", "region_method", "vehicle", "gcs", "parent", "home",
            "flight", "rally", "battery", "timeouts")


def _scenario(data: Any, source: str, base_dir: Path) -> Scenario:
    top = _obj(data, "", TOP_KEYS, ("seed", "region_method", "gcs", "parent", "flight", "battery"))
    if "format" in top and top["format"] != FORMAT:
        _fail("format", f"expected {FORMAT!r}, got {_show(top['format'])}")
    name = _str(top["name"], "name") if "name" in top else Path(source).stem
    description = _str(top["description"], "description") if "description" in top else ""
    seed = _int(top["seed"], "seed", 0, SEED_LIMIT - 1)
    method = RegionMethod.parse(top["region_method"], path="region_method")
    vehicle_sysid = 1
    if "vehicle" in top:
        vehicle = _obj(top["vehicle"], "vehicle", ("sysid",))
        if "sysid" in vehicle:
            vehicle_sysid = _int(vehicle["sysid"], "vehicle.sysid", 1, SYSID_MAX)

    gcs_list = _list(top["gcs"], "gcs")
    if not gcs_list:
        _fail("gcs", "empty (a scenario needs at least one GCS)")
    gcs = tuple(_gcs(entry, f"gcs[{i}]", method) for i, entry in enumerate(gcs_list))
    seen_names: dict[str, int] = {}
    seen_ids: dict[int, int] = {}
    for i, g in enumerate(gcs):
        if g.name in seen_names:
            _fail(f"gcs[{i}].name", f"{g.name!r} is also the name of gcs[{seen_names[g.name]}]")
        if g.sysid in seen_ids:
            _fail(f"gcs[{i}].sysid", f"{g.sysid} is also the system id of gcs[{seen_ids[g.sysid]}]")
        if g.sysid == vehicle_sysid:
            _fail(f"gcs[{i}].sysid", f"{g.sysid} is the vehicle's system id")
        seen_names[g.name], seen_ids[g.sysid] = i, i
    parent = _str(top["parent"], "parent")
    if parent not in seen_names:
        _fail("parent", f"no GCS is named {parent!r} (the GCSs are {', '.join(repr(g.name) for g in gcs)})")

    flight, plan_home, plan_rally = _flight(top["flight"], "flight", base_dir)
    first = flight.waypoints[0].point
    home = _point(top["home"], "home") if "home" in top else plan_home or GeoPoint(first.lat, first.lon, 0.0)
    if "rally" in top:
        rally = tuple(_position(p, f"rally[{i}]") for i, p in enumerate(_list(top["rally"], "rally")))
    else:
        rally = plan_rally
    battery, initial = _battery(top["battery"], "battery")
    timeouts = _timeouts(top.get("timeouts", {}), "timeouts", flight)

    scenario = Scenario(name, description, seed, method, vehicle_sysid, gcs, parent, home, flight, rally,
                        battery, initial, timeouts, source)
    _check_geography(scenario)
    return scenario


GCS_KEYS = ("name", "sysid", "signing", "coverage", "link")
COVERAGE_KEYS = tuple(m.value for m in RegionMethod)


def _gcs(entry: Any, path: str, method: RegionMethod) -> GcsSpec:
    spec = _obj(entry, path, GCS_KEYS, ("name", "sysid", "coverage"))
    name = _str(spec["name"], f"{path}.name")
    if not name.strip() or name != name.strip():
        _fail(f"{path}.name", f"must be non-empty, without leading or trailing spaces, got {name!r}")
    sysid = _int(spec["sysid"], f"{path}.sysid", 1, SYSID_MAX)
    signing = _signing(spec["signing"], f"{path}.signing") if spec.get("signing") is not None else None
    cov_path = f"{path}.coverage"
    coverage_spec = _obj(spec["coverage"], cov_path, COVERAGE_KEYS)
    for other in COVERAGE_KEYS:     # a mistake in another method's entry is still a mistake
        if other in coverage_spec and other != method.value:
            coverage_of(coverage_spec, other, path=cov_path)
    coverage = coverage_of(coverage_spec, method, path=cov_path)
    up = down = LinkFaults()
    if "link" in spec:
        up, down = _link(spec["link"], f"{path}.link")
    return GcsSpec(name, sysid, signing, coverage, up, down)


def _signing(value: Any, path: str) -> SigningKey:
    """`key` (64 hex digits) or `passphrase`, as a roster entry (authenticity.py) takes them."""
    spec = _obj(value, path, ("key", "passphrase", "link_id"))
    if ("key" in spec) == ("passphrase" in spec):
        _fail(path, "give exactly one of key (64 hex digits) or passphrase")
    field_ = "key" if "key" in spec else "passphrase"
    text = _str(spec[field_], f"{path}.{field_}")
    try:
        # A passphrase becomes SHA-256 of its ASCII bytes, as MAVProxy's `signing setup` makes keys.
        secret = secret_from_hex(text) if field_ == "key" else secret_from_passphrase(text)
    except ValueError as error:
        _fail(f"{path}.{field_}", str(error))
    link_id = _int(spec["link_id"], f"{path}.link_id", 0, 255) if "link_id" in spec else 0
    return SigningKey(secret, link_id)


FAULT_KEYS = ("loss", "duplicate", "reorder", "reorder_delay", "delay", "jitter", "corrupt", "partitions", "drop")
PROBABILITIES = ("loss", "duplicate", "reorder", "corrupt")


def _link(value: Any, path: str) -> tuple[LinkFaults, LinkFaults]:
    """Both directions alike (fault fields), or `up` / `down` each with their own."""
    if isinstance(value, Mapping) and ("up" in value or "down" in value):
        spec = _obj(value, path, ("up", "down"))
        up = _faults(spec["up"], f"{path}.up") if "up" in spec else LinkFaults()
        down = _faults(spec["down"], f"{path}.down") if "down" in spec else LinkFaults()
        return up, down
    both = _faults(value, path)
    return both, both


def _faults(value: Any, path: str) -> LinkFaults:
    spec = _obj(value, path, FAULT_KEYS)
    numbers: dict[str, float] = {}
    for key in ("loss", "duplicate", "reorder", "reorder_delay", "delay", "jitter", "corrupt"):
        if key in spec:
            high = 1.0 if key in PROBABILITIES else math.inf
            numbers[key] = _float(spec[key], f"{path}.{key}", high=high)
    windows = []
    for i, window in enumerate(_list(spec.get("partitions", []), f"{path}.partitions")):
        where = f"{path}.partitions[{i}]"
        pair = _list(window, where)
        if len(pair) != 2:
            _fail(where, f"expected [start_s, end_s], got {len(pair)} numbers")
        start, end = _float(pair[0], f"{where}[0]"), _float(pair[1], f"{where}[1]")
        if end < start:
            _fail(where, f"ends ({end:g} s) before it starts ({start:g} s)")
        windows.append((start, end))
    rules = []
    for i, rule in enumerate(_list(spec.get("drop", []), f"{path}.drop")):
        text = _str(rule, f"{path}.drop[{i}]")
        try:
            parse_drop_rule(text)
        except UsageError as error:
            _fail(f"{path}.drop[{i}]", str(error))
        rules.append(text.strip())
    return LinkFaults(**numbers, partitions=tuple(windows), drop=tuple(rules))


FLIGHT_KEYS = ("path", "plan", "speed_m_s", "acceptance_radius_m")
DEFAULT_ACCEPTANCE_M = 10.0


def _flight(value: Any, path: str, base_dir: Path) -> tuple[Flight, GeoPoint | None, tuple[GeoPoint, ...]]:
    """The route, and the home and rally points a .plan brings along (None / () for a path)."""
    spec = _obj(value, path, FLIGHT_KEYS)
    if ("path" in spec) == ("plan" in spec):
        _fail(path, "give exactly one of path (a list of [lat, lon, alt]) or plan (a .plan file)")
    radius = (_float(spec["acceptance_radius_m"], f"{path}.acceptance_radius_m", low_open=True)
              if "acceptance_radius_m" in spec else DEFAULT_ACCEPTANCE_M)
    plan_home: GeoPoint | None = None
    plan_rally: tuple[GeoPoint, ...] = ()
    if "path" in spec:
        if "speed_m_s" not in spec:
            _fail(f"{path}.speed_m_s", "missing (the cruise speed of a path flight)")
        points = _list(spec["path"], f"{path}.path")
        waypoints = tuple(Waypoint(i, _position(p, f"{path}.path[{i}]")) for i, p in enumerate(points))
        plan_name = None
        cruise = None
    else:
        plan_name = _str(spec["plan"], f"{path}.plan")
        waypoints, plan_home, plan_rally, cruise = _from_plan(base_dir / plan_name, f"{path}.plan")
    speed = _float(spec["speed_m_s"], f"{path}.speed_m_s", low_open=True) if "speed_m_s" in spec else cruise
    if speed is None or speed <= 0:
        _fail(f"{path}.speed_m_s", "missing (the .plan's cruiseSpeed is 0)")
    if len(waypoints) < 2:
        where = f"{path}.path" if plan_name is None else f"{path}.plan"
        _fail(where, f"a flight needs at least 2 waypoints, got {len(waypoints)}")
    return Flight(waypoints, speed, radius, plan_name), plan_home, plan_rally


def _from_plan(file: Path, path: str) -> tuple[tuple[Waypoint, ...], GeoPoint | None, tuple[GeoPoint, ...], float]:
    """A .plan's positions: every mission item the vehicle flies to (a waypoint, a landing
    spot, in a global frame), then home again for a RETURN_TO_LAUNCH; its home, rally points
    and cruise speed. Items at latitude and longitude 0 mean "here" to QGC and are skipped."""
    from ..files import load_plan
    from ..mission.commands import DESTINATION_COMMANDS
    from ..mission.constants import Cmd
    from ..mission.items import GLOBAL_FRAMES

    try:
        plan = load_plan(file)
    except UsageError as error:
        _fail(path, str(error))
    home = GeoPoint(plan.home[0], plan.home[1], 0.0) if plan.home is not None else None
    home_amsl = plan.home[2] if plan.home is not None else None
    waypoints: list[Waypoint] = []
    for item in plan.mission:
        if item.command == Cmd.NAV_RETURN_TO_LAUNCH and home is not None:
            waypoints.append(Waypoint(item.seq, home))
            continue
        if item.command not in DESTINATION_COMMANDS or item.frame not in GLOBAL_FRAMES or (item.x, item.y) == (0, 0):
            continue
        alt = float(item.z)
        if item.frame in (0, 5) and home_amsl is not None:      # MAV_FRAME_GLOBAL(_INT): AMSL
            alt -= home_amsl
        waypoints.append(Waypoint(item.seq, GeoPoint(item.x / 1e7, item.y / 1e7, alt)))
    rally = tuple(GeoPoint(r.x / 1e7, r.y / 1e7, float(r.z)) for r in plan.rally)
    return tuple(waypoints), home, rally, plan.settings.cruise_speed


BATTERY_KEYS = ("capacity_wh", "consumption_wh_per_m", "reserve_fraction", "reserve_wh", "initial_fraction",
                "initial_wh")


def _battery(value: Any, path: str) -> tuple[BatteryModel, BatteryState]:
    spec = _obj(value, path, BATTERY_KEYS, ("capacity_wh", "consumption_wh_per_m"))
    capacity = _float(spec["capacity_wh"], f"{path}.capacity_wh", low_open=True)
    per_m = _float(spec["consumption_wh_per_m"], f"{path}.consumption_wh_per_m", low_open=True)
    if "reserve_fraction" in spec and "reserve_wh" in spec:
        _fail(path, "give reserve_fraction or reserve_wh, not both")
    if "reserve_wh" in spec:
        reserve = _float(spec["reserve_wh"], f"{path}.reserve_wh", high=capacity)
    else:
        reserve = _float(spec.get("reserve_fraction", 0.0), f"{path}.reserve_fraction", high=1.0) * capacity
    if "initial_fraction" in spec and "initial_wh" in spec:
        _fail(path, "give initial_fraction or initial_wh, not both")
    if "initial_wh" in spec:
        initial = _float(spec["initial_wh"], f"{path}.initial_wh", high=capacity)
    else:
        initial = _float(spec.get("initial_fraction", 1.0), f"{path}.initial_fraction", high=1.0) * capacity
    return BatteryModel(capacity, per_m, reserve), BatteryState(initial)


TIMEOUT_KEYS = ("dwell_s", "handover_bound_s", "loss_timeout_s", "outside_grace_s", "max_duration_s")
RUN_MARGIN_S = 60.0


def _timeouts(value: Any, path: str, flight: Flight) -> Timeouts:
    """Defaults: start the handover at once, allow it 10 s (the XML's takeover window), call the
    commander lost after 5 s; stop the run at twice the flight time plus a minute."""
    spec = _obj(value, path, TIMEOUT_KEYS)
    base = Timeouts()
    got = {key: _float(spec[key], f"{path}.{key}", low_open=key in ("handover_bound_s", "loss_timeout_s",
                                                                   "max_duration_s"))
           for key in TIMEOUT_KEYS if key in spec}
    if "max_duration_s" not in got:
        got["max_duration_s"] = math.ceil(2 * flight.length_m() / flight.speed_m_s + RUN_MARGIN_S)
    merged = Timeouts(**{**{k: getattr(base, k) for k in TIMEOUT_KEYS}, **got})
    if merged.handover_bound_s <= merged.dwell_s:
        _fail(f"{path}.handover_bound_s", f"{merged.handover_bound_s:g} s leaves no time after the "
                                          f"{merged.dwell_s:g} s dwell")
    return merged


def _check_geography(s: Scenario) -> None:
    """What no run could make sense of: the flight starting outside its parent's authority,
    ownership naming waypoints the flight does not have."""
    first = s.flight.waypoints[0]
    where = "flight.path[0]" if s.flight.plan is None else f"flight.plan (waypoint seq {first.seq})"
    parent_index = [g.name for g in s.gcs].index(s.parent)
    if s.geographic:
        if not s.gcs[parent_index].coverage.contains(first.point):  # type: ignore[union-attr]
            _fail(where, f"the flight starts outside the coverage of its parent GCS {s.parent!r}")
        return
    seqs = set(s.flight.seqs())
    owners: dict[int, str] = {}
    for i, g in enumerate(s.gcs):
        owned = g.coverage
        assert isinstance(owned, OwnedWaypoints)
        for seq in sorted(owned.seqs):
            if seq not in seqs:
                _fail(f"gcs[{i}].coverage.waypoints", f"no waypoint {seq} in the flight "
                                                      f"(its seqs: {seq_ranges(sorted(seqs))})")
            if seq in owners:
                _fail(f"gcs[{i}].coverage.waypoints", f"waypoint {seq} is also owned by {owners[seq]!r}")
            owners[seq] = g.name
    owner = owners.get(first.seq)
    if owner is not None and owner != s.parent:
        _fail(where, f"the first waypoint ({first.seq}) belongs to {owner!r}, not to the parent GCS {s.parent!r}")


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
