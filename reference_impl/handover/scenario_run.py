"""Fly a handover scenario in virtual time: `mavconform handover run` without the reports.

The scenario's vehicle (system manager, mission computer, roster) and one GCS per scenario GCS
(its key, operator-control client and handover agent), each on a link with the scenario's
faults, on one `SimNetwork` seeded by the scenario (or `seed`). The parent takes control,
uploads the flight and starts it; then the run goes on until the flight has ended and the
mission computer is back on_load (a handover under way runs to its end first), or until
`timeouts.max_duration_s` of virtual time, whichever comes first. Every loop is bounded by it.

What happened is read from the vehicle node as it happens: a thin wrapper (`_Watch`) around it
on the network looks at its event queues after every datagram and poll, so every event has the
exact virtual time it happened at, whoever drives the network (the blocking setup calls
included). The result (`ScenarioRun`) is plain data, names instead of system ids; reports/
handover_report.py writes it out. Same scenario and seed: the same run, event for event.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass, field
from typing import Any, Callable

from ..mission.constants import Cmd
from ..mission.items import MissionType
from ..session import TargetUnresponsive
from ..vehicle import VehicleNode
from ..wire.dialect import mavlink as _d
from .control_results import ControlChanged, OwnerLost
from .geo import GeoPoint, haversine_m
from .mission_computer import HandoverFinished, HandoverResult, HandoverStarted
from .mission_computer_transitions import McState
from .scenario import Scenario
from .scenario_fleet import VEHICLE, ScenarioFleet, build_fleet, flight_items, gcs_address
from .scenario_traffic import HandoverTraffic

__all__ = ["THESIS_STEPS", "HandoverRecord", "ScenarioRun", "TrackPoint", "run_scenario"]

# The thesis's six messages (4.5), by step number (docs/handover.md maps each to MAVLink).
THESIS_STEPS = {1: "HANDOVER_REQUEST", 2: "ON_HANDOVER", 3: "OK_HANDOVER", 4: "CONNECT_HANDOVER",
                5: "DRONE_CONNECTED", 6: "DISCONNECT_HANDOVER"}
SAMPLE_PERIOD = 1.0        # s of virtual time between track samples (owner changes are sampled too)
DISCOVERY_S = 20.0         # each GCS must hear the vehicle's HEARTBEAT within this
SETUP_TRIES = 3            # control request and upload, each, under the scenario's loss
START_TRIES = 10           # MISSION_START sends, 2 s apart
BISECTIONS = 12            # a region crossing between two samples, found to 2^-12 of their gap
Marker = Callable[[str, str], None]     # (label, level): the MCAP's markers channel


class TrackPoint(tuple):
    """(t, lat, lon, owner name or None): what reports/handover_map.py draws."""

    __slots__ = ()

    def __new__(cls, t: float, lat: float, lon: float, owner: str | None) -> "TrackPoint":
        return super().__new__(cls, (t, lat, lon, owner))


@dataclass(frozen=True)
class HandoverRecord:
    """One handover: the mission computer's result, in names, with where it started."""

    number: int
    commander: str
    partner: str
    region: str                    # "A+B" (geographic) or "legs of B" (waypoint method)
    result: HandoverResult
    owner_after: str | None
    position: tuple[float, float]  # where the vehicle was at the start


@dataclass
class ScenarioRun:
    """What a run did. `events` is the timeline (dicts, time order); `track` the flight, sampled."""

    scenario: Scenario
    seed: int
    events: list[dict[str, Any]] = field(default_factory=list)
    handovers: list[HandoverRecord] = field(default_factory=list)
    track: list[TrackPoint] = field(default_factory=list)
    traffic: HandoverTraffic | None = None
    setup_failure: str | None = None
    mission_started: float | None = None
    flight_ended: float | None = None
    flight_complete: bool = False   # the last waypoint was reached
    end: float = 0.0               # virtual time when the run stopped
    stopped_by: str = "setup-failed"   # or "flight-ended" (and no handover under way), "max-duration"
    network_steps: int = 0
    links: dict[str, dict[str, int]] = field(default_factory=dict)         # "A -> vehicle": LinkStats counts
    rejections: dict[str, dict[str, int]] = field(default_factory=dict)    # node: frames dropped by signature verdict

    @property
    def finished(self) -> bool:
        """The flight ended, and no handover was still under way, within the run's bound."""
        return self.stopped_by == "flight-ended"

    def exchange(self, h: HandoverRecord) -> list[dict[str, Any]]:
        """The messages of handover `h` (sequence_diagram events), from its start to its end."""
        return self.traffic.exchange(h.result.started, h.result.finished) if self.traffic is not None else []


def run_scenario(s: Scenario, *, seed: int | None = None, capture: Any = None) -> ScenarioRun:
    """Fly scenario `s` (seed: the scenario's unless given). `capture`: a capture hook with
    `mark(label, clock=, level=)` (an `McapCapture`): it gets every datagram, and a marker at the
    mission start, at each handover's start and end, at an owner loss and at the flight's end."""
    run = ScenarioRun(s, s.seed if seed is None else seed)
    watch: _Watch | None = None
    clock: Any = None

    def mark(label: str, level: str) -> None:
        if capture is not None:
            capture.mark(label, clock=clock, level=level)

    def wrap(vehicle: VehicleNode) -> Any:
        nonlocal watch
        watch = _Watch(vehicle, run, mark)
        return watch

    fleet = build_fleet(s, seed=run.seed, node_of=wrap)
    assert watch is not None
    clock = fleet.net.clock
    lanes = {gcs_address(g): g.name for g in s.gcs}
    run.traffic = HandoverTraffic(fleet.vehicle, VEHICLE, lanes)
    fleet.net.add_capture(run.traffic)
    if capture is not None:
        fleet.net.add_capture(capture)
    run.setup_failure = _setup(fleet, run)
    if run.setup_failure is None:
        _fly(fleet, watch, run)
    else:
        watch.event(fleet.net.clock.now(), "setup-failed", detail=run.setup_failure)
    run.end = fleet.net.clock.now()
    run.network_steps = fleet.net.steps
    run.links = {f"{src} -> {dst}": {f.name: getattr(stats, f.name) for f in dataclasses.fields(stats)}
                 for (src, dst), stats in sorted(fleet.net.stats.items())}
    nodes = {"vehicle": fleet.vehicle, **{name: session.gcs for name, session in fleet.sessions.items()}}
    run.rejections = {name: dict(sorted(node.endpoint.rejections.items())) for name, node in nodes.items()}
    run.events.sort(key=lambda e: e["t"])          # stable: same-time events keep their order
    return run


# --- the parent's part: control, upload, start ----------------------------------------------
def _setup(fleet: ScenarioFleet, run: ScenarioRun) -> str | None:
    """Bring the flight up as an operator would; a reason if that did not work (not a usage error:
    the scenario's links may be that bad)."""
    s, net = fleet.scenario, fleet.net
    limit = s.timeouts.max_duration_s
    for name, session in fleet.sessions.items():
        try:
            session.wait_for_target(max(0.0, min(DISCOVERY_S, limit - net.clock.now())))
        except TargetUnresponsive:
            return f"GCS {name} heard no HEARTBEAT from the vehicle within {DISCOVERY_S:g} s"
    parent = fleet.sessions[s.parent]
    for _ in range(SETUP_TRIES):
        control = parent.request_control()
        if control.ok:
            break
    else:
        return f"the parent GCS {s.parent} did not get control ({control.outcome.value}: {control.detail})"
    items = flight_items(s)
    for _ in range(SETUP_TRIES):
        upload = parent.upload(MissionType.MISSION, items)
        if upload.ok:
            break
    else:
        return f"the parent GCS {s.parent} could not upload the flight: {upload.summary()}"
    run.events.append({"t": _t(net.clock.now()), "kind": "mission-uploaded", "gcs": s.parent, "items": len(items)})
    vehicle = fleet.vehicle
    start = _d.MAVLink_command_long_message(s.vehicle_sysid, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0)
    for _ in range(START_TRIES):
        parent.gcs.send(start)
        if net.run_until(lambda: vehicle.flight.flying, timeout=2.0):
            return None
    return f"the vehicle did not start the flight after {START_TRIES} MISSION_START from {s.parent}"


def _fly(fleet: ScenarioFleet, watch: "_Watch", run: ScenarioRun) -> None:
    """Run to the flight's end (or the bound), sampling the track every SAMPLE_PERIOD."""
    net, limit = fleet.net, fleet.scenario.timeouts.max_duration_s
    done = watch.done
    for _ in range(int(math.ceil(limit / SAMPLE_PERIOD)) + 2):
        now = net.clock.now()
        if done() or now >= limit:
            break
        net.run_until(done, timeout=min(SAMPLE_PERIOD, limit - now))
        watch.sample(net.clock.now())
    now = net.clock.now()
    watch.sample(now)
    run.stopped_by = "flight-ended" if done() else "max-duration"
    if not done():
        watch.event(now, "run-stopped", detail=f"max_duration_s ({limit:g} s) reached: "
                    + ("the flight had not ended" if run.flight_ended is None else "a handover was still under way"))
    _region_events(fleet.scenario, run)


# --- watching the vehicle ---------------------------------------------------------------------
class _Watch:
    """The vehicle node as the network sees it, plus: after every datagram and poll, new
    control and handover events, owner changes and waypoints reached become timeline events."""

    def __init__(self, vehicle: VehicleNode, run: ScenarioRun, mark: Marker) -> None:
        self.vehicle = vehicle
        self.run = run
        self.mark = mark
        s = run.scenario
        self.names = {g.sysid: g.name for g in s.gcs}
        self._pairs = {frozenset((a, b)): f"{a}+{b}" for a, b, _ in s.handover_regions()}
        self._last_control: Any = None
        self._last_handover: Any = None
        self._owner = 0
        self._progress = (0, False, False, False)   # seq, running, complete, flying (a divert too)
        self._count = 0                        # handovers started
        self._current: tuple[int, HandoverStarted, tuple[float, float]] | None = None
        self._mc = vehicle.mission_computer

    # DatagramNode, delegated
    def datagram_received(self, data: bytes, source: Any, now: float) -> None:
        self.vehicle.datagram_received(data, source, now)
        self._look(now)

    def poll(self, now: float) -> None:
        self.vehicle.poll(now)
        self._look(now)

    def next_deadline(self) -> float | None:
        return self.vehicle.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Any]]:
        return self.vehicle.take_outgoing()

    def done(self) -> bool:
        """The flight ended and the mission computer is back on_load (no handover under way)."""
        return self.run.flight_ended is not None and self._mc.state is McState.ON_LOAD

    # --- events -------------------------------------------------------------------------------
    def name(self, sysid: int) -> str | None:
        return None if not sysid else self.names.get(sysid, f"GCS {sysid}")

    def event(self, now: float, kind: str, **fields: Any) -> dict[str, Any]:
        e = {"t": _t(now), "kind": kind, **fields}
        self.run.events.append(e)
        return e

    def sample(self, now: float) -> None:
        if self.run.mission_started is None:
            return
        p = self.vehicle.flight.where(now)
        track = self.run.track
        point = TrackPoint(_t(now), round(p.lat, 7), round(p.lon, 7), self.name(self._owner))
        if track and track[-1][0] == point[0]:
            track[-1] = point
        else:
            track.append(point)

    def _look(self, now: float) -> None:
        v = self.vehicle
        control, handover = v.control_events, v.handover_events
        if control and control[-1] is not self._last_control:
            for action in _new(control, self._last_control):
                self._on_control(action, now)
            self._last_control = control[-1]
        if handover and handover[-1] is not self._last_handover:
            for action in _new(handover, self._last_handover):
                self._on_handover(action, now)
            self._last_handover = handover[-1]
        progress = v.server.progress
        state = (progress.seq, progress.running, progress.complete, v.flight.flying)
        if state != self._progress:
            self._on_progress(self._progress, state, now)
            self._progress = state
        if v.owner != self._owner:
            self._owner = v.owner
            self.sample(now)
        v.events.clear()       # the CLI's log lines: read here as events instead, kept bounded

    def _on_control(self, action: Any, now: float) -> None:
        if isinstance(action, ControlChanged):
            self.event(now, "control-changed", owner=self.name(action.owner), previous=self.name(action.previous),
                       takeover_allowed=action.takeover_allowed, reason=action.reason)
        elif isinstance(action, OwnerLost):
            self.event(now, "owner-lost", gcs=self.name(action.sysid), silent_s=_t(action.at - action.last_heard))
            self.mark(f"GCS {self.name(action.sysid)} lost", "warning")
        else:
            self.event(now, _emergency_kind(type(action).__name__), type=type(action).__name__, fields=_plain(action))

    def _on_handover(self, action: Any, now: float) -> None:
        if isinstance(action, HandoverStarted):
            p = self.vehicle.flight.where(now)
            self._count += 1
            number = self._count
            self._current = (number, action, (p.lat, p.lon))
            region = self._region(action.region)
            self.event(now, "handover-started", handover=number, commander=self.name(action.commander),
                       partner=self.name(action.partner), region=region)
            self.mark(f"handover {number} {self.name(action.commander)}->{self.name(action.partner)} started "
                      f"(region {region})", "info")
        elif isinstance(action, HandoverFinished):
            self._finished(action.result, now)
        else:   # the emergency procedure's events (EmergencyStarted, EmergencyEnded, ...)
            kind = _emergency_kind(type(action).__name__)
            self.event(now, kind, type=type(action).__name__, fields=_plain(action))
            self.mark(f"{kind}: {type(action).__name__}", "warning")

    def _finished(self, r: HandoverResult, now: float) -> None:
        if self._current is None:          # a finish without its start: cannot happen, kept readable
            self._count += 1
            self._current = (self._count, HandoverStarted(r.commander, r.partner, "", r.started), (0.0, 0.0))
        number, started, position = self._current
        self._current = None
        region = self._region(started.region)
        record = HandoverRecord(number, self.name(r.commander) or "", self.name(r.partner) or "", region, r,
                                self.name(r.owner), (round(position[0], 7), round(position[1], 7)))
        self.run.handovers.append(record)
        for step, at in r.steps:
            self.event(at, "handover-step", handover=number, step=step, message=THESIS_STEPS.get(step, ""))
        self.event(now, "handover-finished", handover=number, outcome=r.outcome.name, owner=record.owner_after,
                   duration_s=_t(r.duration), detail=r.detail)
        level = "info" if r.outcome.name == "COMPLETED" else "warning"
        self.mark(f"handover {number} {record.commander}->{record.partner} {r.outcome.name} after "
                  f"{r.duration:.2f} s, gcs_main {record.owner_after}", level)

    def _on_progress(self, old: tuple[int, bool, bool, bool], new: tuple[int, bool, bool, bool], now: float) -> None:
        """The flight's start (flying, first time), each waypoint reached, its end (not flying:
        the mission done, or landed at an emergency's refuge)."""
        run = self.run
        seq, running, complete, flying = new
        if flying and run.mission_started is None:
            run.mission_started = now
            p = self.vehicle.flight.where(now)
            extra = ({"covered_by": list(run.scenario.covering(GeoPoint(p.lat, p.lon)))}
                     if run.scenario.geographic else {})
            self.event(now, "mission-started", owner=self.name(self.vehicle.owner), **extra)
            self.mark("mission started", "info")
            self.sample(now)
            return
        if run.mission_started is None:
            return
        if old[1] and (seq != old[0] or complete):
            reached = old[0]
            owner = run.scenario.ownership()
            extra = {"leg_owner": owner.owner(reached)} if owner is not None else {}
            self.event(now, "waypoint-reached", seq=reached, **extra)
        if old[3] and not flying and run.flight_ended is None:
            run.flight_ended, run.flight_complete = now, complete
            self.sample(now)
            self.event(now, "flight-ended", complete=complete)
            self.mark("flight ended" + ("" if complete else " (not at its last waypoint)"), "info")

    def _region(self, name: str) -> str:
        """The mission computer's region name ("255+254", "legs of 254") in GCS names, a pair
        in scenario order ("A+B", as the timeline's region events name it)."""
        prefix = "legs of "
        if name.startswith(prefix):
            return prefix + (self.name(int(name[len(prefix):])) or name)
        try:
            names = [self.name(int(part)) or part for part in name.split("+")]
        except ValueError:
            return name
        return self._pairs.get(frozenset(names), "+".join(names))


def _emergency_kind(type_name: str) -> str:
    """"emergency-started" for EmergencyStarted, "emergency-ended" for EmergencyEnded, else "emergency"."""
    for suffix, kind in (("Started", "emergency-started"), ("Ended", "emergency-ended")):
        if type_name.endswith(suffix):
            return kind
    return "emergency"


def _new(queue: Any, last: Any) -> list[Any]:
    """The items appended to a bounded deque since `last` (its newest item when last looked)."""
    out = []
    for item in reversed(queue):
        if item is last:
            break
        out.append(item)
    out.reverse()
    return out


# --- where the flight entered and left coverage ------------------------------------------------
def _region_events(s: Scenario, run: ScenarioRun) -> None:
    """Coverage and handover-region entries and exits along the track (geographic methods),
    each between two samples found by bisection on the straight line between them. These are
    the regions themselves; the mission computer starts a handover after its dwell. (Exact
    polygon tests are dear, so each sample is tested once per coverage, and a pair's region
    is read from its two coverages.)"""
    if not s.geographic or len(run.track) < 2:
        return
    names = [g.name for g in s.gcs]
    coverage = {g.name: g.coverage for g in s.gcs}
    pairs = [(a, b) for a, b, _ in s.handover_regions()]

    def covering(p: TrackPoint, q: TrackPoint | None = None, f: float = 0.0) -> dict[str, bool]:
        lat, lon = (p[1], p[2]) if q is None else (p[1] + (q[1] - p[1]) * f, p[2] + (q[2] - p[2]) * f)
        point = GeoPoint(lat, lon)
        return {n: coverage[n].contains(point) for n in names}  # type: ignore[union-attr]

    def regions(cov: dict[str, bool]) -> dict[tuple[str, str], bool]:
        return {(k, n): v for n, v in cov.items() for k in ("coverage",)} | {
            ("region", f"{a}+{b}"): cov[a] and cov[b] for a, b in pairs}

    before = regions(covering(run.track[0]))
    for a, b in zip(run.track, run.track[1:]):
        after = regions(covering(b))
        for key, now_in in after.items():
            if before[key] == now_in:
                continue
            lo, hi = 0.0, 1.0
            for _ in range(BISECTIONS):
                mid = (lo + hi) / 2
                if regions(covering(a, b, mid))[key] == now_in:
                    hi = mid
                else:
                    lo = mid
            kind, name = key
            run.events.append({"t": _t(a[0] + (b[0] - a[0]) * hi), "kind": f"{kind}-{'entered' if now_in else 'left'}",
                               ("gcs" if kind == "coverage" else "region"): name})
        before = after


# --- helpers ------------------------------------------------------------------------------------
def _t(seconds: float) -> float:
    """Virtual seconds as the timeline writes them (microseconds)."""
    return round(seconds, 6)


def _plain(value: Any) -> Any:
    """An event object as JSON data: dataclasses as dicts, enums by name, floats rounded."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, enum.Enum):
        return value.name
    if isinstance(value, float):
        return round(value, 7) if math.isfinite(value) else str(value)
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if value is None or isinstance(value, (bool, int, str)):
        return value
    return str(value)


def distance_m(track: list[TrackPoint]) -> float:
    """Ground distance along sampled track points."""
    return sum(haversine_m(GeoPoint(a[1], a[2]), GeoPoint(b[1], b[2])) for a, b in zip(track, track[1:]))
