"""A handover scenario file's fields, each checked and turned into the model scenario.py
defines (`scenario_of`, which `scenario_from_dict` calls): every mistake one UsageError naming
the field path; docs/handover-scenarios.md is the schema."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping, NoReturn

from ..errors import UsageError
from ..net.faults import parse_drop_rule
from ..wire.signing import SigningKey, secret_from_hex, secret_from_passphrase
from .emergency import BatteryModel, BatteryState
from .geo import GeoPoint
from .regions import OwnedWaypoints, RegionMethod, _list, _number, _point, _show, coverage_of
from .scenario import (FAULT_KEYS, FORMAT, SEED_LIMIT, SYSID_MAX, TIMEOUT_KEYS, Flight, GcsSpec, LinkFaults, Scenario,
                       Timeouts, Waypoint, seq_ranges)


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


def scenario_of(data: Any, source: str, base_dir: Path) -> Scenario:
    """Plain data (a parsed scenario file) checked field by field and built into a `Scenario`;
    a mistake is a UsageError naming the field path (scenario_from_dict adds the source)."""
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
