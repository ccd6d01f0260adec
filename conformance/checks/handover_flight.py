"""One HO.SEQ flight and what the testers read during it (conformance/checks/handover_sequence.py
says what the flights are for): the GCSs' steps (operator-control requests and their acks), the
mission A uploads (from where the vehicle is, via a waypoint just inside the handover region, to
the hold point and back), the flight started as the target's autopilot wants it, waited out and
always cleaned up (plan put back, vehicle home and disarmed, control released), and the
invitation the partner waits for."""

from __future__ import annotations

import bisect
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any, Callable, Iterator

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
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
from ..harness.tester import Tester
from ..outcome import NotApplicable, PreconditionFailed
from ..session import Session
from .handover_route import Route, sampled_path
from .control_exchange import REQUEST_ACK, REQUEST_TIMEOUT, gcs_id, latest_status, refuse_if_unsupported, release_if_ours, result_text

MISSION = MissionType.MISSION
FRAME_GLOBAL_RELATIVE_ALT = _d.MAV_FRAME_GLOBAL_RELATIVE_ALT   # the path's altitudes are metres above home
INVITE_GRACE = 3.0       # s after the dwell, counted from the first position report inside the region
MIN_SPEED = 2.0          # m/s: the slowest flight the bounds allow for
FLIGHT_MARGIN = 20.0     # s on top of a flight's bound
ENTRY_DEPTH = 6.0        # m inside the region the flight's entry waypoint lies
POSITION = "GLOBAL_POSITION_INT"
NO_MISSION_COMPUTER = "ho.no_mission_computer"


# --- reading what came ---------------------------------------------------------------------------

def frames_since(t: Tester, when: float) -> list[tuple[float, Frame]]:
    """What `t` received from `when` on (the inbox is in arrival order)."""
    inbox = t.node.inbox
    start = bisect.bisect_left(inbox, when, key=lambda entry: entry[0])
    return inbox[start:]


def position_of(frame: Frame) -> GeoPoint | None:
    msg = frame.msg
    if msg._type != POSITION or not (msg.lat or msg.lon):
        return None
    return GeoPoint.from_e7(msg.lat, msg.lon)


def positions_between(t: Tester, since: float, until: float) -> list[tuple[float, GeoPoint]]:
    out = []
    for at, frame in frames_since(t, since):
        if at > until:
            break
        p = position_of(frame)
        if p is not None:
            out.append((at, p))
    return out


def statuses_between(t: Tester, since: float, until: float) -> list[tuple[float, Frame]]:
    return [(at, f) for at, f in frames_since(t, since) if at <= until and f.msg._type == "CONTROL_STATUS"]


def is_request_to(frame: Frame, gcs: int) -> bool:
    """MAV_CMD_REQUEST_OPERATOR_CONTROL (a request, param1 1) from the vehicle to `gcs`: an
    invitation or a connect notice to the partner, a relayed request to the commander."""
    msg = frame.msg
    return (cm.is_request_control(msg) and getattr(msg, "target_system", 0) == gcs
            and msg.param1 == cm.ACTION_REQUEST)


def arrival_of(t: Tester, frame: Frame) -> float:
    return next((at for at, f in reversed(t.node.inbox) if f is frame), t.now())


def is_accepted(frame: Frame | None) -> bool:
    return frame is not None and frame.msg.result == CommandResult.ACCEPTED


def params_text(frame: Frame) -> str:
    msg = frame.msg
    return ", ".join(f"param{i}={getattr(msg, f'param{i}'):g}" for i in (1, 2, 3, 4))


# --- the GCSs' steps ---------------------------------------------------------------------------

def ask_control(t: Tester, action: float, allow: bool = False, timeout: float = REQUEST_TIMEOUT) -> Frame | None:
    """32100 from `t` for itself; the COMMAND_ACK to it (None after the reply timeout)."""
    t.mark()
    t.send(cm.request_command(t.target, action, allow, timeout, gcs_id(t)))
    return t.poll_for(REQUEST_ACK, t.timings.default_timeout)


def ack_command(t: Tester, frame: Frame) -> None:
    """COMMAND_ACK ACCEPTED of a 32100 the vehicle sent `t` ("That owning GCS must ACK")."""
    t.send(cm.command_ack(cm.REQUEST_CONTROL, CommandResult.ACCEPTED, (frame.src_system, frame.src_component)))


def command_from(t: Tester) -> Frame | None:
    """MAV_CMD_DO_SET_MISSION_CURRENT -1 0 (the current item, no reset), as HO.CTL.10 sends it."""
    t.mark()
    t.send(m.command_long_message(Cmd.DO_SET_MISSION_CURRENT, t.target, -1.0, 0.0))
    return t.poll_for(msg("COMMAND_ACK", command=int(Cmd.DO_SET_MISSION_CURRENT)), t.timings.default_timeout)


def the_gcss(s: Session, route: Route) -> tuple[Tester, Tester]:
    """The commander A and the partner B, with this clause's exchange."""
    a, b = s.gcs(route.parent), s.gcs(route.partner)
    for x in (a, b):
        x.exchange = s.t.exchange
    return a, b


def ensure_uncontrolled(s: Session, route: Route) -> None:
    """A GCS of ours in control releases; another operator's control leaves it undecided."""
    release_if_ours(s.t, [*s.testers(), *the_gcss(s, route)])


# --- a flight --------------------------------------------------------------------------------

@dataclass
class Flight:
    route: Route
    a: Tester
    b: Tester
    here: GeoPoint
    hold_s: float
    started: float
    last_seq: int


def flight_mission(route: Route, here: GeoPoint, hold_s: float, vehicle: VehicleClass) -> list[MissionItem]:
    """Take off where the vehicle is, fly straight to the hold point, hold there (NAV_WAYPOINT
    param1, the hold time), fly straight back and land, at the path's altitude there; with a
    waypoint where that leg has just entered the region, so however a flight model spends a
    hold (at the waypoint, or as a slower leg to it: our FlightSim) it is spent inside the
    region. The take-off and landing are the vehicle class's (harness.flight_plan): an
    autopilot may refuse a mission without them (ArduCopter armed on the ground: a take-off
    first; PX4 fixed-wing and VTOL: a landing)."""
    entry = entry_point(route, here)
    points = [*([(entry, 0.0)] if entry is not None else []), (route.hold, hold_s), (here, 0.0)]
    x, y = round(float(here.lat) * 1e7), round(float(here.lon) * 1e7)
    body = [takeoff_item(vehicle, x, y, route.alt)]
    body += [MissionItem(0, FRAME_GLOBAL_RELATIVE_ALT, int(Cmd.NAV_WAYPOINT), param1=hold,
                         x=round(float(p.lat) * 1e7), y=round(float(p.lon) * 1e7), z=route.alt, mission_type=MISSION)
             for p, hold in points]
    body.append(landing_item(vehicle, x, y))
    return [replace(item, seq=seq) for seq, item in enumerate(body)]


def entry_point(route: Route, here: GeoPoint) -> GeoPoint | None:
    """ENTRY_DEPTH past where the straight leg from `here` to the hold point enters the
    region (None when that is at the hold point itself)."""
    points = list(sampled_path([here, route.hold]))
    for i, point in enumerate(points):
        if route.inside(point):
            travelled = 0.0
            for a, b in zip(points[i:], points[i + 1:]):
                travelled += haversine_m(a, b)
                if travelled >= ENTRY_DEPTH:
                    return b if haversine_m(b, route.hold) >= ENTRY_DEPTH else None
            return None
    return None


def position_now(a: Tester) -> GeoPoint:
    """Where the vehicle is now: a GLOBAL_POSITION_INT sent from now on (one sent before may
    be a second old, from the last flight's last leg), else the latest (`harness.flight`)."""
    a.mark()
    frame = a.poll_for(flying.POSITION, flying.POSITION_WAIT, forced=True)
    lat, lon = (frame.msg.lat, frame.msg.lon) if frame is not None else flying.where(a)
    return GeoPoint.from_e7(lat, lon)


def check_start(route: Route, here: GeoPoint) -> None:
    """The flight must start in A's coverage, in no handover region, and enter A and B's first."""
    if not route.parent_coverage.contains(here) or any(r.contains(here) for _, r in route.regions):
        raise PreconditionFailed(f"the vehicle is at {float(here.lat):.6f}, {float(here.lon):.6f}: not in GCS "
                                 f"{route.parent}'s coverage alone (scenario {route.scenario!r}), so a flight from "
                                 "there would not enter the handover region from the commander's side; bring it "
                                 "into the parent GCS's coverage, outside every handover region")
    for point in sampled_path([here, route.hold]):
        entered = [sysid for sysid, region in route.regions if region.contains(point)]
        if entered:
            if entered[0] != route.partner:
                raise PreconditionFailed(f"the straight leg from the vehicle to the hold point enters GCS "
                                         f"{entered[0]}'s handover region first, not GCS {route.partner}'s")
            return


@contextmanager
def flown(s: Session, route: Route, hold_s: float) -> Iterator[Flight]:
    """Take control as A, upload and start the flight; afterwards wait it out, put the plan
    back and release (see the module docstring)."""
    a, b = the_gcss(s, route)
    ensure_uncontrolled(s, route)
    before = procedures.stored(a, MISSION)
    a.note(f"GCS {route.parent} (the commander) takes control for the flight")
    frame = ask_control(a, cm.ACTION_REQUEST)
    refuse_if_unsupported(frame)
    if not is_accepted(frame):
        raise PreconditionFailed(f"setup: GCS {route.parent}'s request for control got {result_text(frame)} "
                                 "(HO.CTL.02 judges that)")
    flight = None
    style = watch = None   # set once the vehicle may be started: from then on it is landed and disarmed
    try:
        here = position_now(a)
        check_start(route, here)
        vehicle_style = flying.style_of(s.identity)
        items = flight_mission(route, here, hold_s, vehicle_style.vehicle)
        accepted = procedures.ensure_plan(a, items, MISSION)
        procedures.await_plan_taken(a, accepted)
        a.note(f"the flight: take off, straight to the hold point {route.where(route.hold)} the handover region "
               f"of {route.pair}, held {hold_s:g} s, back and land")
        started = a.now()
        style, watch = vehicle_style, VehicleWatch(a, since=started)
        flying.start(a, watch, style)
        flight = Flight(route, a, b, here, hold_s, started, len(items) - 1)
        yield flight
    finally:
        land_flight(s, route, a, b, flight, before, (style, watch))


def flight_wait(flight: Flight) -> float:
    """Unscaled bound on the whole flight, at the slowest speed allowed for."""
    leg = haversine_m(flight.here, flight.route.hold)
    return 2 * leg / MIN_SPEED + flight.hold_s + FLIGHT_MARGIN


def flight_ended(flight: Flight) -> Callable[[], bool]:
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


def land_flight(s: Session, route: Route, a: Tester, b: Tester, flight: Flight | None, before: list[MissionItem],
          started: tuple[FlightStyle | None, VehicleWatch | None]) -> None:
    keep = a.decided_by
    if flight is not None:
        a.note("afterwards: the flight is waited out")
        if not a.wait_until(flight_ended(flight), flight_wait(flight)):
            a.note(f"the flight did not end within {flight_wait(flight) * s.scale:g} s; going on")
    last = latest_status(a)
    owner = last.msg.gcs_main if last is not None else 0
    holder = {route.parent: a, route.partner: b}.get(owner, a)
    style, watch = started
    if style is not None and watch is not None:   # whether the flight flew or its start failed
        if holder is not a:
            watch = VehicleWatch(holder, since=watch.since)
        s.record_flight(style.name, "the handover flight", land_and_disarm(holder, watch, style, None))
    holder.note(f"afterwards: GCS {gcs_id(holder)} puts back the mission plan it found, and every GCS releases control")
    reply = procedures.upload(holder, before, MISSION) if before else procedures.clear(holder, MISSION)
    if reply is None or reply.msg.type != MissionResult.ACCEPTED:
        holder.note("the plan could not be put back from here (the run puts back what it can at its end)")
    for tester in {id(x): x for x in (*s.testers(), a, b)}.values():
        tester.node.heartbeats = True
        ask_control(tester, cm.ACTION_RELEASE)
    a.decided_by = keep


def await_invitation(s: Session, flight: Flight) -> tuple[float, Frame]:
    """The invitation to B (when it came, and the frame). None when the vehicle has been
    inside the region for the dwell and INVITE_GRACE: it has no mission computer, and every
    HO.SEQ clause is not-applicable (remembered for the run)."""
    route, a, b = flight.route, flight.a, flight.b
    positions, inbox_b = InboxReader(a, flight.started), InboxReader(b, flight.started)
    ended = flight_ended(flight)
    state: dict[str, Any] = {"inside": None, "invitation": None}
    grace = (route.dwell + INVITE_GRACE) * s.scale

    def done() -> bool:
        for at, frame in inbox_b.new():
            if is_request_to(frame, route.partner):
                state["invitation"] = (at, frame)
                return True
        for at, frame in positions.new():
            p = position_of(frame)
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
    s.cache[NO_MISSION_COMPUTER] = reason
    raise NotApplicable(reason)


def partner_asks(flight: Flight, invitation: Frame) -> Frame | None:
    """B acknowledges the invitation and requests control, takeover not allowed, with the
    invitation's timeout (docs/handover.md step 2)."""
    b = flight.b
    ack_command(b, invitation)
    b.note(f"GCS {gcs_id(b)} (the partner) acknowledges the invitation and asks for control")
    return ask_control(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(invitation.msg.param3))


