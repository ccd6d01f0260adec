"""The thesis's handover procedure over MAVLink operator control (seed 003 ch. 4, docs/handover.md): HO.SEQ.*

The target is a vehicle whose mission computer hands command from one GCS to another when it
flies into a handover region (the intersection of two GCSs' coverages), over the exchange
docs/handover.md maps the thesis's six messages to: (1) the vehicle invites the partner with
MAV_CMD_REQUEST_OPERATOR_CONTROL naming it in param4; (2) the partner requests control, is
refused, and the vehicle relays the request to the commander; (3) the commander allows takeover;
(4) the partner's request is granted, CONTROL_STATUS names it, and the vehicle sends it the
connect notice; (5) the partner acknowledges the notice; (6) the old commander releases.

What the tester knows. The handover scenario (`TargetUri.handover_scenario`: the file given
with `--handover-scenario`, else the shipped conformance scenario) says who the parent GCS is,
every GCS's system id and coverage, the dwell and the bound. The tester plays the parent as the
commander (A) and the GCS whose region the scenario's path enters first as the partner (B),
with their system ids (`Session.gcs`). `route_of` works that out once: the region, and the
point the flight holds at (the middle of the path's first stretch inside it). The geographic
methods only (circle, polygon): under the waypoint method the handover follows mission seqs,
so the tester would have to fly the scenario's own mission, which it does not.

How a target is driven. Two flights, each an observation several clauses decide from
(`Session.shared`). A takes control, uploads a short mission (from where the vehicle is,
straight to the hold point via a waypoint just past the region's edge, held there, and
straight back), starts it as its autopilot accepts (`harness.flight`) and the testers watch:
- the cooperative flight (HO.SEQ.01-06, 08): B answers the invitation and requests control;
  A acknowledges the relayed request, waits `AUTH_HOLD` (B asks once more meanwhile), then
  allows takeover; B asks again; B acknowledges the connect notice; A releases; each sends
  MAV_CMD_DO_SET_MISSION_CURRENT -1 (the current item, as HO.CTL.10); then, still held in
  the region, the tester watches for a new invitation;
- the silent-commander flight (HO.SEQ.07): B requests as before, A acknowledges the relay and
  does nothing else; B asks again whenever CONTROL_STATUS shows takeover allowed (as its
  operator-control client would), until the bound (and a margin) has passed.
The hold keeps the vehicle in the region for everything a flight watches: the cooperative
one's steps and watch, the silent one's whole bound. (The waypoint at the edge puts the hold
inside the region however a flight model spends it: a real vehicle at the waypoint, our
FlightSim as a slower leg to it.)

Applicability. A target with no system manager (no CONTROL_STATUS, or 32100 answered
UNSUPPORTED) is not-applicable as for HO.CTL. A target with one but no mission computer
sends no invitation: when none reaches B within the dwell and `INVITE_GRACE` of the vehicle's
first position report inside the region, every HO.SEQ clause is not-applicable (decided once
per run, on the first flight). The flights need `--allow-flight` (on for builtin targets).

Setup and cleanup. A flight starts from an uncontrolled target (a GCS of ours in control
releases first; another operator's control leaves the clause undecided) with the vehicle in
the parent's coverage and in no handover region (else undecided: the region would not be
entered). Whatever happens, the flight is waited out (bounded), the GCS in control puts the
mission plan back, the vehicle is sent home (MAV_CMD_NAV_RETURN_TO_LAUNCH, as after the
progress clauses' flight), and every GCS releases control. Steps a clause builds on but does not
judge make it undecided, naming the clause that does. Every wait is bounded.
"""

from __future__ import annotations

import bisect
import math
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Iterator

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.hysteresis import signed_distance_m
from mavconform.reference_impl.handover.regions import Intersection, RegionMethod
from mavconform.reference_impl.handover.scenario import Scenario
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult, MissionState
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.vehicle_class import VehicleClass
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.wire.frame import Frame

from ..harness import flight as flying
from ..harness.flight_plan import landing_item, takeoff_item
from ..harness.flight_styles import FlightStyle
from ..harness.landing import land_and_disarm
from ..harness.vehicle_watch import InboxReader, VehicleWatch
from ..harness import procedures
from ..harness.match import msg
from ..harness.measured import Measured
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed, Skipped
from ..session import Session
from ..target_uri import handover_config
from . import check
from .operator_control import (REQUEST_ACK, STATUS_WAIT, TAKEOVER, _latest_status, _shown, _status_text,
                               _system_manager, _unsupported, release_if_ours)

MISSION = MissionType.MISSION
FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT   # the path's altitudes are metres above home
RELAYED = msg(("COMMAND_LONG", "COMMAND_INT"), command=cm.REQUEST_CONTROL)   # 32100 from the vehicle
REQUEST_TIMEOUT = 10.0   # param 3 of the testers' own requests (s), as HO.CTL's
INVITE_GRACE = 3.0       # s after the dwell, counted from the first position report inside the region
AUTH_HOLD = 1.5          # s the commander waits before it authorises (HO.SEQ.03's window)
FORWARD_WAIT = 3.0       # s for the relayed request: the first send and a resend at the manager's 1.5 s
NOTICE_WAIT = 3.0        # s for the connect notice after the grant
WATCH_EXTRA = 2.0        # s beyond the dwell that HO.SEQ.08 watches the vehicle inside the region
HOLD_SLACK = 3.0         # s of the cooperative flight's hold beyond what it watches
BOUND_MARGIN = 2.0       # s beyond the bound that HO.SEQ.07 watches
MIN_SPEED = 2.0          # m/s: the slowest flight the bounds allow for
FLIGHT_MARGIN = 20.0     # s on top of a flight's bound
SAMPLE_M = 2.0           # m between the points the path is sampled at
ENTRY_DEPTH = 6.0        # m inside the region the flight's entry waypoint lies
POSITION = "GLOBAL_POSITION_INT"
_COOPERATIVE, _SILENT = "ho.handover", "ho.silent_commander"
_NO_MC = "ho.no_mission_computer"


# --- what the scenario says the flights are ---------------------------------------------------

@dataclass(frozen=True)
class Route:
    """The handover the tester plays out of a scenario (`route_of`)."""

    scenario: str
    parent: int                      # the commander, A
    partner: int                     # B: the GCS whose region with A the path enters first
    parent_coverage: Any
    regions: tuple[tuple[int, Intersection], ...]   # every handover region of the parent, by the other GCS
    hold: GeoPoint                   # the middle of the path's first stretch inside A and B's region
    alt: float                       # m above home, the path's there
    dwell: float
    bound: float
    commit: float                    # s from a handover's start by which control must have moved

    @property
    def region(self) -> Intersection:
        return dict(self.regions)[self.partner]

    def inside(self, point: GeoPoint) -> bool:
        return self.region.contains(point)

    def where(self, point: GeoPoint) -> str:
        d = signed_distance_m(self.region, point)
        return f"{-d:.0f} m inside" if d <= 0 else f"{d:.0f} m outside"

    @property
    def pair(self) -> str:
        return f"GCSs {self.parent} and {self.partner}"


def route_of(scenario: Scenario, *, option: str = "") -> Route:
    """The handover the clauses fly for `scenario`, or a `UsageError` saying why there is none."""
    where = option or (scenario.source or scenario.name)
    if scenario.region_method is RegionMethod.WAYPOINTS:
        raise UsageError(f"{where}: the handover clauses need a circle or polygon scenario: under the waypoint "
                         "method a handover follows the mission's seqs, and the clauses fly a mission of their own")
    parent = scenario.gcs_named(scenario.parent)
    regions = tuple((g.sysid, Intersection((parent.coverage, g.coverage))) for g in scenario.gcs
                    if g.sysid != parent.sysid)
    run: list[GeoPoint] = []
    partner = None
    for point in _sampled([w.point for w in scenario.flight.waypoints]):
        inside = [sysid for sysid, region in regions if region.contains(point)]
        if partner is None and inside:
            partner = inside[0]
        if partner is not None:
            if partner not in inside:
                break
            run.append(point)
    if partner is None:
        raise UsageError(f"{where}: the flight's path never enters a handover region of the parent GCS "
                         f"{scenario.parent!r} (where its coverage meets another GCS's)")
    lengths = [0.0]
    for a, b in zip(run, run[1:]):
        lengths.append(lengths[-1] + haversine_m(a, b))
    middle = run[bisect.bisect_left(lengths, lengths[-1] / 2)] if len(run) > 1 else run[0]
    config = handover_config(scenario)
    return Route(scenario.name, parent.sysid, partner, parent.coverage, regions,
                 GeoPoint(middle.lat, middle.lon), float(middle.alt or 0.0), config.dwell, config.bound,
                 config.commit_timeout)


def _sampled(points: list[GeoPoint]) -> Iterator[GeoPoint]:
    """Points along the path every SAMPLE_M or less, straight in lat/lon (as a flight model
    interpolates a leg), altitudes too."""
    for a, b in zip(points, points[1:]):
        n = max(1, math.ceil(haversine_m(a, b) / SAMPLE_M))
        alt_a, alt_b = a.alt or 0.0, b.alt or 0.0
        for k in range(n):
            f = k / n
            yield GeoPoint(float(a.lat) + (float(b.lat) - float(a.lat)) * f,
                           float(a.lon) + (float(b.lon) - float(a.lon)) * f, alt_a + (alt_b - alt_a) * f)
    last = points[-1]
    yield GeoPoint(float(last.lat), float(last.lon), last.alt or 0.0)


def _route(s: Session) -> Route:
    cached = s.cache.get("ho.route")
    if cached is None:
        try:
            cached = s.cache["ho.route"] = route_of(s.uri.handover_scenario)
        except UsageError as exc:
            raise PreconditionFailed(str(exc)) from None
    return cached


# --- reading what came ---------------------------------------------------------------------------

def _since(t: Tester, when: float) -> list[tuple[float, Frame]]:
    """What `t` received from `when` on (the inbox is in arrival order)."""
    inbox = t.node.inbox
    start = bisect.bisect_left(inbox, when, key=lambda entry: entry[0])
    return inbox[start:]


def _position(frame: Frame) -> GeoPoint | None:
    msg = frame.msg
    if msg._type != POSITION or not (msg.lat or msg.lon):
        return None
    return GeoPoint.from_e7(msg.lat, msg.lon)


def _positions(t: Tester, since: float, until: float) -> list[tuple[float, GeoPoint]]:
    out = []
    for at, frame in _since(t, since):
        if at > until:
            break
        p = _position(frame)
        if p is not None:
            out.append((at, p))
    return out


def _statuses(t: Tester, since: float, until: float) -> list[tuple[float, Frame]]:
    return [(at, f) for at, f in _since(t, since) if at <= until and f.msg._type == "CONTROL_STATUS"]


def _request_to(frame: Frame, gcs: int) -> bool:
    """MAV_CMD_REQUEST_OPERATOR_CONTROL (a request, param1 1) from the vehicle to `gcs`: an
    invitation or a connect notice to the partner, a relayed request to the commander."""
    msg = frame.msg
    return (cm.is_request_control(msg) and getattr(msg, "target_system", 0) == gcs
            and msg.param1 == cm.ACTION_REQUEST)


def _arrival(t: Tester, frame: Frame) -> float:
    return next((at for at, f in reversed(t.node.inbox) if f is frame), t.now())


def _result(frame: Frame | None) -> str:
    return "no COMMAND_ACK" if frame is None else procedures.command_result_name(frame.msg.result)


def _accepted(frame: Frame | None) -> bool:
    return frame is not None and frame.msg.result == CommandResult.ACCEPTED


def _params(frame: Frame) -> str:
    msg = frame.msg
    return ", ".join(f"param{i}={getattr(msg, f'param{i}'):g}" for i in (1, 2, 3, 4))


# --- the GCSs' steps ---------------------------------------------------------------------------

def _id(t: Tester) -> int:
    return t.node.endpoint.system


def _ask(t: Tester, action: float, allow: bool = False, timeout: float = REQUEST_TIMEOUT) -> Frame | None:
    """32100 from `t` for itself; the COMMAND_ACK to it (None after the reply timeout)."""
    t.mark()
    t.send(cm.request_command(t.target, action, allow, timeout, _id(t)))
    return t.poll_for(REQUEST_ACK, t.timings.default_timeout)


def _ack(t: Tester, frame: Frame) -> None:
    """COMMAND_ACK ACCEPTED of a 32100 the vehicle sent `t` ("That owning GCS must ACK")."""
    t.send(cm.command_ack(cm.REQUEST_CONTROL, CommandResult.ACCEPTED, (frame.src_system, frame.src_component)))


def _command(t: Tester) -> Frame | None:
    """MAV_CMD_DO_SET_MISSION_CURRENT -1 0 (the current item, no reset), as HO.CTL.10 sends it."""
    t.mark()
    t.send(m.command_long_message(Cmd.DO_SET_MISSION_CURRENT, t.target, -1.0, 0.0))
    return t.poll_for(msg("COMMAND_ACK", command=int(Cmd.DO_SET_MISSION_CURRENT)), t.timings.default_timeout)


def _gcss(s: Session, route: Route) -> tuple[Tester, Tester]:
    """The commander A and the partner B, with this clause's exchange."""
    a, b = s.gcs(route.parent), s.gcs(route.partner)
    for x in (a, b):
        x.exchange = s.t.exchange
    return a, b


def _uncontrolled(s: Session, route: Route) -> None:
    """A GCS of ours in control releases; another operator's control leaves it undecided."""
    release_if_ours(s.t, [*s.testers(), *_gcss(s, route)])


# --- a flight --------------------------------------------------------------------------------

@dataclass
class _Flight:
    route: Route
    a: Tester
    b: Tester
    here: GeoPoint
    hold_s: float
    started: float
    last_seq: int


def _mission(route: Route, here: GeoPoint, hold_s: float, vehicle: VehicleClass) -> list[MissionItem]:
    """Take off where the vehicle is, fly straight to the hold point, hold there (NAV_WAYPOINT
    param1, the hold time), fly straight back and land, at the path's altitude there; with a
    waypoint where that leg has just entered the region, so however a flight model spends a
    hold (at the waypoint, or as a slower leg to it: our FlightSim) it is spent inside the
    region. The take-off and landing are the vehicle class's (harness.flight_plan): an
    autopilot may refuse a mission without them (ArduCopter armed on the ground: a take-off
    first; PX4 fixed-wing and VTOL: a landing)."""
    entry = _entry(route, here)
    points = [*([(entry, 0.0)] if entry is not None else []), (route.hold, hold_s), (here, 0.0)]
    x, y = round(float(here.lat) * 1e7), round(float(here.lon) * 1e7)
    body = [takeoff_item(vehicle, x, y, route.alt)]
    body += [MissionItem(0, FRAME_GLOBAL_RELATIVE_ALT, int(Cmd.NAV_WAYPOINT), param1=hold,
                         x=round(float(p.lat) * 1e7), y=round(float(p.lon) * 1e7), z=route.alt, mission_type=MISSION)
             for p, hold in points]
    body.append(landing_item(vehicle, x, y))
    return [replace(item, seq=seq) for seq, item in enumerate(body)]


def _entry(route: Route, here: GeoPoint) -> GeoPoint | None:
    """ENTRY_DEPTH past where the straight leg from `here` to the hold point enters the
    region (None when that is at the hold point itself)."""
    points = list(_sampled([here, route.hold]))
    for i, point in enumerate(points):
        if route.inside(point):
            travelled = 0.0
            for a, b in zip(points[i:], points[i + 1:]):
                travelled += haversine_m(a, b)
                if travelled >= ENTRY_DEPTH:
                    return b if haversine_m(b, route.hold) >= ENTRY_DEPTH else None
            return None
    return None


def _here(a: Tester) -> GeoPoint:
    """Where the vehicle is now: a GLOBAL_POSITION_INT sent from now on (one sent before may
    be a second old, from the last flight's last leg), else the latest (`harness.flight`)."""
    a.mark()
    frame = a.poll_for(flying.POSITION, flying.POSITION_WAIT, forced=True)
    lat, lon = (frame.msg.lat, frame.msg.lon) if frame is not None else flying.where(a)
    return GeoPoint.from_e7(lat, lon)


def _check_start(route: Route, here: GeoPoint) -> None:
    """The flight must start in A's coverage, in no handover region, and enter A and B's first."""
    if not route.parent_coverage.contains(here) or any(r.contains(here) for _, r in route.regions):
        raise PreconditionFailed(f"the vehicle is at {float(here.lat):.6f}, {float(here.lon):.6f}: not in GCS "
                                 f"{route.parent}'s coverage alone (scenario {route.scenario!r}), so a flight from "
                                 "there would not enter the handover region from the commander's side; bring it "
                                 "into the parent GCS's coverage, outside every handover region")
    for point in _sampled([here, route.hold]):
        entered = [sysid for sysid, region in route.regions if region.contains(point)]
        if entered:
            if entered[0] != route.partner:
                raise PreconditionFailed(f"the straight leg from the vehicle to the hold point enters GCS "
                                         f"{entered[0]}'s handover region first, not GCS {route.partner}'s")
            return


@contextmanager
def _flight(s: Session, route: Route, hold_s: float) -> Iterator[_Flight]:
    """Take control as A, upload and start the flight; afterwards wait it out, put the plan
    back and release (see the module docstring)."""
    a, b = _gcss(s, route)
    _uncontrolled(s, route)
    before = procedures.stored(a, MISSION)
    a.note(f"GCS {route.parent} (the commander) takes control for the flight")
    frame = _ask(a, cm.ACTION_REQUEST)
    _unsupported(frame)
    if not _accepted(frame):
        raise PreconditionFailed(f"setup: GCS {route.parent}'s request for control got {_result(frame)} "
                                 "(HO.CTL.02 judges that)")
    flight = None
    style = watch = None   # set once the vehicle may be started: from then on it is landed and disarmed
    try:
        here = _here(a)
        _check_start(route, here)
        vehicle_style = flying.style_of(s.identity)
        items = _mission(route, here, hold_s, vehicle_style.vehicle)
        accepted = procedures.ensure_plan(a, items, MISSION)
        procedures.await_plan_taken(a, accepted)
        a.note(f"the flight: take off, straight to the hold point {route.where(route.hold)} the handover region "
               f"of {route.pair}, held {hold_s:g} s, back and land")
        started = a.now()
        style, watch = vehicle_style, VehicleWatch(a, since=started)
        flying.start(a, watch, style)
        flight = _Flight(route, a, b, here, hold_s, started, len(items) - 1)
        yield flight
    finally:
        _land(s, route, a, b, flight, before, (style, watch))


def _flight_wait(flight: _Flight) -> float:
    """Unscaled bound on the whole flight, at the slowest speed allowed for."""
    leg = haversine_m(flight.here, flight.route.hold)
    return 2 * leg / MIN_SPEED + flight.hold_s + FLIGHT_MARGIN


def _ended(flight: _Flight) -> Callable[[], bool]:
    last = flight.last_seq
    reader = InboxReader(flight.a, flight.started)
    done = [False]

    def check() -> bool:
        for _, frame in reader.new():
            msg = frame.msg
            if (msg._type == "MISSION_ITEM_REACHED" and msg.seq == last) or (
                    msg._type == "MISSION_CURRENT" and msg.seq == last
                    and getattr(msg, "mission_state", 0) == MissionState.COMPLETE):
                done[0] = True
        return done[0]
    return check


def _land(s: Session, route: Route, a: Tester, b: Tester, flight: _Flight | None, before: list[MissionItem],
          started: tuple[FlightStyle | None, VehicleWatch | None]) -> None:
    keep = a.decided_by
    if flight is not None:
        a.note("afterwards: the flight is waited out")
        if not a.wait_until(_ended(flight), _flight_wait(flight)):
            a.note(f"the flight did not end within {_flight_wait(flight) * s.scale:g} s; going on")
    last = _latest_status(a)
    owner = last.msg.gcs_main if last is not None else 0
    holder = {route.parent: a, route.partner: b}.get(owner, a)
    style, watch = started
    if style is not None and watch is not None:   # whether the flight flew or its start failed
        if holder is not a:
            watch = VehicleWatch(holder, since=watch.since)
        s.record_flight(style.name, "the handover flight", land_and_disarm(holder, watch, style, None))
    holder.note(f"afterwards: GCS {_id(holder)} puts back the mission plan it found, and every GCS releases control")
    reply = procedures.upload(holder, before, MISSION) if before else procedures.clear(holder, MISSION)
    if reply is None or reply.msg.type != MissionResult.ACCEPTED:
        holder.note("the plan could not be put back from here (the run puts back what it can at its end)")
    for tester in {id(x): x for x in (*s.testers(), a, b)}.values():
        tester.node.heartbeats = True
        _ask(tester, cm.ACTION_RELEASE)
    a.decided_by = keep


def _await_invitation(s: Session, flight: _Flight) -> tuple[float, Frame]:
    """The invitation to B (when it came, and the frame). None when the vehicle has been
    inside the region for the dwell and INVITE_GRACE: it has no mission computer, and every
    HO.SEQ clause is not-applicable (remembered for the run)."""
    route, a, b = flight.route, flight.a, flight.b
    positions, inbox_b = InboxReader(a, flight.started), InboxReader(b, flight.started)
    ended = _ended(flight)
    state: dict[str, Any] = {"inside": None, "invitation": None}
    grace = (route.dwell + INVITE_GRACE) * s.scale

    def done() -> bool:
        for at, frame in inbox_b.new():
            if _request_to(frame, route.partner):
                state["invitation"] = (at, frame)
                return True
        for at, frame in positions.new():
            p = _position(frame)
            if p is not None and state["inside"] is None and route.inside(p):
                state["inside"] = at
        if state["inside"] is not None and a.now() >= state["inside"] + grace:
            return True
        return ended()

    wait = haversine_m(flight.here, route.hold) / MIN_SPEED + flight.hold_s + route.dwell + INVITE_GRACE
    a.wait_until(done, wait)
    if state["invitation"] is not None:
        b.decided_by_frame(state["invitation"][1])
        return state["invitation"]
    if state["inside"] is None:
        raise PreconditionFailed(f"the vehicle never reported a position inside the handover region of "
                                 f"{route.pair} within {wait * s.scale:g} s of the start (the flight heads for "
                                 f"a point {route.where(route.hold)} it)")
    reason = (f"no MAV_CMD_REQUEST_OPERATOR_CONTROL invitation reached GCS {route.partner} within "
              f"{grace:g} s of the vehicle's first position report inside the handover region of {route.pair} "
              f"(scenario {route.scenario!r}): the target has no mission computer running the handover "
              "sequence (or one loaded otherwise than the scenario says)")
    s.cache[_NO_MC] = reason
    raise NotApplicable(reason)


def _partner_asks(flight: _Flight, invitation: Frame) -> Frame | None:
    """B acknowledges the invitation and requests control, takeover not allowed, with the
    invitation's timeout (docs/handover.md step 2)."""
    b = flight.b
    _ack(b, invitation)
    b.note(f"GCS {_id(b)} (the partner) acknowledges the invitation and asks for control")
    return _ask(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(invitation.msg.param3))


# --- the cooperative flight (HO.SEQ.01-06, 08) ------------------------------------------------

@dataclass
class _Cooperative:
    stop: BaseException | None = None      # the flight's own verdict: not-applicable, undecided, ...
    route: Route | None = None
    started: float = 0.0                   # MISSION_START
    invitation: Frame | None = None
    invited_at: float = 0.0
    asked_at: float = 0.0
    request_ack: Frame | None = None       # B's first request
    repeat_ack: Frame | None = None        # B's request again, before A authorised
    forward: Frame | None = None
    held: list[tuple[float, Frame]] = field(default_factory=list)   # CONTROL_STATUS before A authorised
    allow_ack: Frame | None = None         # A's re-request with takeover allowed
    grant_ack: Frame | None = None         # B's request after it
    named: Frame | None = None             # CONTROL_STATUS naming B
    notice: Frame | None = None
    release_ack: Frame | None = None
    old_command: Frame | None = None
    new_command: Frame | None = None
    watch: tuple[float, float] = (0.0, 0.0)
    reinvitation: Frame | None = None
    a: Tester | None = field(default=None, repr=False)
    b: Tester | None = field(default=None, repr=False)

    @property
    def early(self) -> bool:
        """B was granted control before A authorised."""
        return _accepted(self.request_ack) or _accepted(self.repeat_ack)

    @property
    def granted(self) -> bool:
        return self.early or _accepted(self.grant_ack)


def _cooperative(s: Session, route: Route) -> _Cooperative:
    obs = _Cooperative(route=route)
    hold = route.dwell + route.dwell + (AUTH_HOLD + WATCH_EXTRA + HOLD_SLACK) * s.scale
    try:
        with _flight(s, route, round(hold, 1)) as flight:
            a, b = obs.a, obs.b = flight.a, flight.b
            obs.started = flight.started
            obs.invited_at, obs.invitation = _await_invitation(s, flight)
            obs.asked_at = a.now()
            a.mark()
            obs.request_ack = _partner_asks(flight, obs.invitation)
            obs.forward = a.poll_for(RELAYED, FORWARD_WAIT)
            if obs.forward is not None:
                _ack(a, obs.forward)
            if not obs.early:
                a.note(f"GCS {route.parent} (the commander) takes {AUTH_HOLD * s.scale:g} s before it authorises; "
                       f"GCS {route.partner} asks again meanwhile")
                obs.repeat_ack = _ask(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(obs.invitation.msg.param3))
                a.wait_until(lambda: False, AUTH_HOLD)
            obs.held = _statuses(a, obs.asked_at, a.now())
            if not obs.early:
                a.note(f"GCS {route.parent} authorises: it re-requests control with takeover allowed")
                obs.allow_ack = _ask(a, cm.ACTION_REQUEST, allow=True)
                b.note(f"GCS {route.partner} asks again")
                obs.grant_ack = _ask(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(obs.invitation.msg.param3))
            if obs.granted:
                _after_grant(s, obs, flight)
    except (NotApplicable, PreconditionFailed, Skipped) as exc:
        obs.stop = exc
    return obs


def _after_grant(s: Session, obs: _Cooperative, flight: _Flight) -> None:
    route, a, b = flight.route, flight.a, flight.b
    obs.named = a.poll_for(msg("CONTROL_STATUS", gcs_main=route.partner), STATUS_WAIT, forced=True)
    obs.notice = b.poll_for(RELAYED, NOTICE_WAIT)
    if obs.notice is not None:
        _ack(b, obs.notice)
        b.note(f"GCS {route.partner} acknowledges the connect notice (step 5)")
    a.note(f"GCS {route.parent} lets go (step 6): it releases control")
    obs.release_ack = _ask(a, cm.ACTION_RELEASE)
    watch_from = a.now()
    a.note(f"GCS {route.parent}, the old commander, sends MAV_CMD_DO_SET_MISSION_CURRENT -1 (the current item)")
    obs.old_command = _command(a)
    b.note(f"GCS {route.partner}, the new commander, sends the same")
    obs.new_command = _command(b)
    watch = (route.dwell + WATCH_EXTRA) * s.scale
    a.note(f"the vehicle holds in the region: watched {watch:g} s for a new handover")
    reader = InboxReader(a, watch_from)

    def reinvited() -> bool:
        for _, frame in reader.new():
            if _request_to(frame, route.parent):
                obs.reinvitation = frame
                return True
        return False
    a.wait_until(reinvited, route.dwell + WATCH_EXTRA)
    obs.watch = (watch_from, a.now())


def _observed(s: Session) -> _Cooperative:
    route = _applicable(s)
    obs = s.shared(_COOPERATIVE, lambda: _cooperative(s, route))
    _gcss(s, route)
    _reraise(obs.stop)
    return obs


def _applicable(s: Session) -> Route:
    _system_manager(s)
    if _NO_MC in s.cache:
        raise NotApplicable(s.cache[_NO_MC])
    if not s.allow_flight:
        raise Skipped("needs --allow-flight: the handover clauses fly the vehicle into a handover region")
    return _route(s)


def _reraise(stop: BaseException | None) -> None:
    if stop is not None:
        raise type(stop)(*stop.args)


def _undecided_without_grant(obs: _Cooperative, what: str) -> None:
    if obs.early:
        return
    if not _accepted(obs.allow_ack):
        raise PreconditionFailed(f"{what}: the commander's re-request with takeover allowed got "
                                 f"{_result(obs.allow_ack)}")
    if not obs.granted:
        raise PreconditionFailed(f"{what}: the partner was not granted control after the commander authorised "
                                 "(HO.SEQ.04 judges that)")


# --- the clauses --------------------------------------------------------------------------------

@check("HO.SEQ.01")
def invitation(s: Session) -> None:
    obs = _observed(s)
    route, b, inv = obs.route, obs.b, obs.invitation
    b.decided_by_frame(inv)
    msg = inv.msg
    wrong = []
    if msg.param4 != route.partner:
        wrong.append(f"param4={msg.param4:g} (expected {route.partner}: the GCS invited)")
    if not cm.TIMEOUT_MIN <= msg.param3 <= cm.TIMEOUT_MAX:
        wrong.append(f"param3={msg.param3:g} (expected a request timeout in {cm.TIMEOUT_MIN:g}..{cm.TIMEOUT_MAX:g} s)")
    if wrong:
        raise ClauseFailed(f"the invitation to GCS {route.partner} (MAV_CMD_REQUEST_OPERATOR_CONTROL, "
                           f"{_params(inv)}) had {'; '.join(wrong)}")
    # the vehicle's position reports either side of it (1 Hz: the entry may fall between two)
    near = _positions(obs.a, obs.started, obs.watch[1] or obs.a.now())
    before = [p for at, p in near if at <= obs.invited_at][-1:]
    after = [p for at, p in near if at > obs.invited_at][:1]
    if before + after and not any(route.inside(p) for p in before + after):
        said = "; ".join(route.where(p) for p in before + after)
        raise ClauseFailed(Measured(f"the invitation to GCS {route.partner} came while the vehicle reported "
                                    f"itself outside the handover region of {route.pair} (the positions just "
                                    f"before and after it: <where>); expected it on entering the region",
                                    where=said))


@check("HO.SEQ.02")
def request_relayed(s: Session) -> None:
    obs = _observed(s)
    route, a = obs.route, obs.a
    if _accepted(obs.request_ack):
        raise PreconditionFailed(f"GCS {route.partner}'s request was granted at once, so there was nothing to "
                                 "relay (HO.SEQ.03 judges that)")
    if obs.forward is None:
        raise ClauseFailed(f"GCS {route.partner}'s request for control (answered {_result(obs.request_ack)}) did not "
                           f"reach the commander, GCS {route.parent}, within {FORWARD_WAIT * s.scale:g} s; expected "
                           "the same MAV_CMD_REQUEST_OPERATOR_CONTROL relayed to it (param4 = the partner)")
    a.decided_by_frame(obs.forward)
    msg = obs.forward.msg
    if msg.param1 != cm.ACTION_REQUEST or msg.param4 != route.partner:
        raise ClauseFailed(f"the request relayed to the commander, GCS {route.parent}, had {_params(obs.forward)}; "
                           f"expected param1=1 (a request) and param4={route.partner} (the partner)")


@check("HO.SEQ.03")
def no_switch_before_authorisation(s: Session) -> None:
    obs = _observed(s)
    route, a, b = obs.route, obs.a, obs.b
    for frame, which in ((obs.request_ack, "request"), (obs.repeat_ack, "repeated request")):
        if _accepted(frame):
            b.decided_by_frame(frame)
            raise ClauseFailed(f"GCS {route.partner}'s {which} for control was granted (MAV_RESULT_ACCEPTED) before "
                               f"the commander, GCS {route.parent}, authorised the handover; expected it refused "
                               "until then")
    for at, frame in obs.held:
        if frame.msg.gcs_main != route.parent:
            _shown(a, frame)
            raise ClauseFailed(Measured(f"<after> s after GCS {route.partner} asked for control, before the "
                                        f"commander authorised, {_status_text(frame)} came; expected "
                                        f"gcs_main={route.parent} until the commander's word",
                                        after=f"{at - obs.asked_at:.2f}"))
    if obs.repeat_ack is not None:
        b.decided_by_frame(obs.repeat_ack)


@check("HO.SEQ.04")
def switch_after_authorisation(s: Session) -> None:
    obs = _observed(s)
    route, a, b = obs.route, obs.a, obs.b
    if obs.early:
        raise PreconditionFailed(f"GCS {route.partner} was granted control before the commander authorised "
                                 "(HO.SEQ.03 judges that)")
    if not _accepted(obs.allow_ack):
        raise PreconditionFailed(f"setup: the commander's re-request with takeover allowed got {_result(obs.allow_ack)}")
    if not _accepted(obs.grant_ack):
        if obs.grant_ack is not None:
            b.decided_by_frame(obs.grant_ack)
        raise ClauseFailed(f"after the commander, GCS {route.parent}, authorised (re-requested control with "
                           f"takeover allowed: MAV_RESULT_ACCEPTED), GCS {route.partner}'s request was answered "
                           f"{_result(obs.grant_ack)}; expected MAV_RESULT_ACCEPTED")
    if obs.named is None:
        raise ClauseFailed(f"GCS {route.partner} was granted control, but no CONTROL_STATUS with "
                           f"gcs_main={route.partner} came within {STATUS_WAIT * s.scale:g} s")
    _shown(a, obs.named)


@check("HO.SEQ.05")
def connect_notice(s: Session) -> None:
    obs = _observed(s)
    route, b = obs.route, obs.b
    _undecided_without_grant(obs, "the connect notice follows the grant")
    if obs.notice is None:
        raise ClauseFailed(f"after GCS {route.partner} was granted control, no MAV_CMD_REQUEST_OPERATOR_CONTROL "
                           f"(the connect notice) reached it within {NOTICE_WAIT * s.scale:g} s")
    b.decided_by_frame(obs.notice)
    if obs.notice.msg.param4 != route.partner:
        raise ClauseFailed(f"the connect notice to GCS {route.partner} had {_params(obs.notice)}; expected "
                           f"param4={route.partner} (the GCS now in control)")


@check("HO.SEQ.06")
def only_the_new_commander(s: Session) -> None:
    obs = _observed(s)
    route, a, b = obs.route, obs.a, obs.b
    _undecided_without_grant(obs, "after the handover")
    old, new = obs.old_command, obs.new_command
    if old is not None and old.msg.result == CommandResult.UNSUPPORTED and (
            new is None or new.msg.result == CommandResult.UNSUPPORTED):
        raise PreconditionFailed("the target answers MAV_CMD_DO_SET_MISSION_CURRENT UNSUPPORTED even from the GCS "
                                 "in control: the clause has no command of the target's to send")
    if old is None or old.msg.result != CommandResult.NOT_IN_CONTROL:
        if old is not None:
            a.decided_by_frame(old)
        raise ClauseFailed(f"after the handover to GCS {route.partner}, a command from the old commander, GCS "
                           f"{route.parent}, was answered {_result(old)}; expected MAV_RESULT_NOT_IN_CONTROL")
    if new is None or new.msg.result == CommandResult.NOT_IN_CONTROL:
        if new is not None:
            b.decided_by_frame(new)
        raise ClauseFailed(f"after the handover, the same command from the new commander, GCS {route.partner}, "
                           f"was answered {_result(new)}; expected an answer as to the GCS in control")
    a.decided_by_frame(old)


@check("HO.SEQ.08")
def one_handover_per_entry(s: Session) -> None:
    obs = _observed(s)
    route, a = obs.route, obs.a
    _undecided_without_grant(obs, "a handover first")
    since, until = obs.watch
    if obs.reinvitation is not None:
        a.decided_by_frame(obs.reinvitation)
        raise ClauseFailed(Measured(f"<after> s after the handover to GCS {route.partner} (the vehicle still in the "
                                    f"region), the vehicle sent GCS {route.parent} MAV_CMD_REQUEST_OPERATOR_CONTROL "
                                    f"({_params(obs.reinvitation)}): a new handover; expected one per entry "
                                    "into the region", after=f"{_arrival(a, obs.reinvitation) - since:.2f}"))
    outside = [p for _, p in _positions(a, since, until) if not route.inside(p)]
    if outside:
        raise PreconditionFailed(f"the vehicle left the handover region during the watch "
                                 f"({route.where(outside[0])}): the watch needs it inside")


# --- the silent commander (HO.SEQ.07) -------------------------------------------------------------

@dataclass
class _Silent:
    stop: BaseException | None = None
    route: Route | None = None
    invited_at: float = 0.0
    until: float = 0.0
    request_ack: Frame | None = None
    retries: list[Frame] = field(default_factory=list)   # B's requests on seeing takeover allowed: ACKs
    a: Tester | None = field(default=None, repr=False)
    b: Tester | None = field(default=None, repr=False)


def _silent(s: Session, route: Route) -> _Silent:
    obs = _Silent(route=route)
    hold = route.bound + route.dwell + BOUND_MARGIN * s.scale
    try:
        with _flight(s, route, round(hold, 1)) as flight:
            a = obs.a = flight.a
            obs.b = flight.b
            obs.invited_at, invitation = _await_invitation(s, flight)
            a.mark()
            obs.request_ack = _partner_asks(flight, invitation)
            if not _accepted(obs.request_ack):
                forward = a.poll_for(RELAYED, FORWARD_WAIT)
                if forward is not None:
                    _ack(a, forward)
                a.note(f"GCS {route.parent} (the commander) acknowledges the relayed request and never "
                       f"authorises; GCS {route.partner} asks again whenever CONTROL_STATUS shows takeover "
                       f"allowed; watched until {route.bound:g} s (the bound) + {BOUND_MARGIN * s.scale:g} s "
                       "after the invitation")
                obs.until = obs.invited_at + route.bound + BOUND_MARGIN * s.scale
                _watch_bound(s, obs, invitation)
    except (NotApplicable, PreconditionFailed, Skipped) as exc:
        obs.stop = exc
    return obs


def _watch_bound(s: Session, obs: _Silent, invitation: Frame) -> None:
    a, b = obs.a, obs.b
    reader = InboxReader(a, a.now())
    timeout = cm.clamp_timeout(invitation.msg.param3)
    for _ in range(1000):   # bounded: at most one request per CONTROL_STATUS, and the window ends
        left = obs.until - a.now()
        if left <= 0:
            return
        chance: list[Frame] = []

        def takeover_shown() -> bool:
            chance.extend(f for _, f in reader.new()
                          if f.msg._type == "CONTROL_STATUS" and f.msg.flags & TAKEOVER)
            return bool(chance)
        if a.wait_until(takeover_shown, left / s.scale):
            b.note(f"CONTROL_STATUS shows takeover allowed: GCS {_id(b)} asks again")
            obs.retries.append(_ask(b, cm.ACTION_REQUEST, timeout=timeout))


@check("HO.SEQ.07")
def silent_commander_keeps_control(s: Session) -> None:
    route = _applicable(s)
    obs = s.shared(_SILENT, lambda: _silent(s, route))
    a, b = _gcss(s, route)
    _reraise(obs.stop)
    if _accepted(obs.request_ack):
        raise PreconditionFailed(f"GCS {route.partner}'s request was granted at once, before the commander "
                                 "authorised (HO.SEQ.03 judges that)")
    statuses = _statuses(a, obs.invited_at, obs.until)
    for at, frame in statuses:
        if frame.msg.gcs_main != route.parent:
            _shown(a, frame)
            raise ClauseFailed(Measured(f"GCS {route.parent}, the commander, never authorised, yet <after> s after "
                                        f"the invitation {_status_text(frame)} came; expected GCS {route.parent} "
                                        f"to keep control and the handover to end within its {route.bound:g} s bound",
                                        after=f"{at - obs.invited_at:.2f}"))
    for frame in obs.retries:
        if _accepted(frame):
            b.decided_by_frame(frame)
            raise ClauseFailed(Measured(f"GCS {route.parent}, the commander, never authorised, yet <after> s after "
                                        f"the invitation GCS {route.partner}'s request was granted "
                                        f"(MAV_RESULT_ACCEPTED); expected GCS {route.parent} to keep control and "
                                        f"the handover to end within its {route.bound:g} s bound",
                                        after=f"{_arrival(b, frame) - obs.invited_at:.2f}"))
    late = [f for at, f in statuses if at > obs.invited_at + route.bound]
    if not late:
        raise PreconditionFailed(f"no CONTROL_STATUS came after the {route.bound:g} s bound to judge by "
                                 "(HO.CTL.01 judges the stream)")
    _shown(a, late[-1])
