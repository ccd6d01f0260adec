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

from dataclasses import dataclass, field

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.mission.constants import CommandResult
from mavconform.reference_impl.wire.frame import Frame

from ..harness.vehicle_watch import InboxReader
from ..harness.match import msg
from ..harness.measured import Measured
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed, Skipped
from ..session import Session
from . import check
from .handover_flight import (NO_MISSION_COMPUTER, Flight, ack_command, arrival_of, ask_control, await_invitation,
                              command_from, flown, gcs_id, is_accepted, is_request_to, params_text, partner_asks,
                              positions_between, result_text, statuses_between, the_gcss)
from .handover_route import Route, route_for
from .control_exchange import STATUS_WAIT, TAKEOVER, shown, status_text, system_manager

RELAYED = msg(("COMMAND_LONG", "COMMAND_INT"), command=cm.REQUEST_CONTROL)   # 32100 from the vehicle
AUTH_HOLD = 1.5          # s the commander waits before it authorises (HO.SEQ.03's window)
FORWARD_WAIT = 3.0       # s for the relayed request: the first send and a resend at the manager's 1.5 s
NOTICE_WAIT = 3.0        # s for the connect notice after the grant
WATCH_EXTRA = 2.0        # s beyond the dwell that HO.SEQ.08 watches the vehicle inside the region
HOLD_SLACK = 3.0         # s of the cooperative flight's hold beyond what it watches
BOUND_MARGIN = 2.0       # s beyond the bound that HO.SEQ.07 watches
_COOPERATIVE, _SILENT = "ho.handover", "ho.silent_commander"


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
        return is_accepted(self.request_ack) or is_accepted(self.repeat_ack)

    @property
    def granted(self) -> bool:
        return self.early or is_accepted(self.grant_ack)


def _cooperative(s: Session, route: Route) -> _Cooperative:
    obs = _Cooperative(route=route)
    hold = route.dwell + route.dwell + (AUTH_HOLD + WATCH_EXTRA + HOLD_SLACK) * s.scale
    try:
        with flown(s, route, round(hold, 1)) as flight:
            a, b = obs.a, obs.b = flight.a, flight.b
            obs.started = flight.started
            obs.invited_at, obs.invitation = await_invitation(s, flight)
            obs.asked_at = a.now()
            a.mark()
            obs.request_ack = partner_asks(flight, obs.invitation)
            obs.forward = a.poll_for(RELAYED, FORWARD_WAIT)
            if obs.forward is not None:
                ack_command(a, obs.forward)
            if not obs.early:
                a.note(f"GCS {route.parent} (the commander) takes {AUTH_HOLD * s.scale:g} s before it authorises; "
                       f"GCS {route.partner} asks again meanwhile")
                obs.repeat_ack = ask_control(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(obs.invitation.msg.param3))
                a.wait_until(lambda: False, AUTH_HOLD)
            obs.held = statuses_between(a, obs.asked_at, a.now())
            if not obs.early:
                a.note(f"GCS {route.parent} authorises: it re-requests control with takeover allowed")
                obs.allow_ack = ask_control(a, cm.ACTION_REQUEST, allow=True)
                b.note(f"GCS {route.partner} asks again")
                obs.grant_ack = ask_control(b, cm.ACTION_REQUEST, timeout=cm.clamp_timeout(obs.invitation.msg.param3))
            if obs.granted:
                _after_grant(s, obs, flight)
    except (NotApplicable, PreconditionFailed, Skipped) as exc:
        obs.stop = exc
    return obs


def _after_grant(s: Session, obs: _Cooperative, flight: Flight) -> None:
    route, a, b = flight.route, flight.a, flight.b
    obs.named = a.poll_for(msg("CONTROL_STATUS", gcs_main=route.partner), STATUS_WAIT, forced=True)
    obs.notice = b.poll_for(RELAYED, NOTICE_WAIT)
    if obs.notice is not None:
        ack_command(b, obs.notice)
        b.note(f"GCS {route.partner} acknowledges the connect notice (step 5)")
    a.note(f"GCS {route.parent} lets go (step 6): it releases control")
    obs.release_ack = ask_control(a, cm.ACTION_RELEASE)
    watch_from = a.now()
    a.note(f"GCS {route.parent}, the old commander, sends MAV_CMD_DO_SET_MISSION_CURRENT -1 (the current item)")
    obs.old_command = command_from(a)
    b.note(f"GCS {route.partner}, the new commander, sends the same")
    obs.new_command = command_from(b)
    watch = (route.dwell + WATCH_EXTRA) * s.scale
    a.note(f"the vehicle holds in the region: watched {watch:g} s for a new handover")
    reader = InboxReader(a, watch_from)

    def reinvited() -> bool:
        for _, frame in reader.new():
            if is_request_to(frame, route.parent):
                obs.reinvitation = frame
                return True
        return False
    a.wait_until(reinvited, route.dwell + WATCH_EXTRA)
    obs.watch = (watch_from, a.now())


def _observed(s: Session) -> _Cooperative:
    route = _applicable(s)
    obs = s.shared(_COOPERATIVE, lambda: _cooperative(s, route))
    the_gcss(s, route)
    _reraise(obs.stop)
    return obs


def _applicable(s: Session) -> Route:
    system_manager(s)
    if NO_MISSION_COMPUTER in s.cache:
        raise NotApplicable(s.cache[NO_MISSION_COMPUTER])
    if not s.allow_flight:
        raise Skipped("needs --allow-flight: the handover clauses fly the vehicle into a handover region")
    return route_for(s)


def _reraise(stop: BaseException | None) -> None:
    if stop is not None:
        raise type(stop)(*stop.args)


def _undecided_without_grant(obs: _Cooperative, what: str) -> None:
    if obs.early:
        return
    if not is_accepted(obs.allow_ack):
        raise PreconditionFailed(f"{what}: the commander's re-request with takeover allowed got "
                                 f"{result_text(obs.allow_ack)}")
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
                           f"{params_text(inv)}) had {'; '.join(wrong)}")
    # the vehicle's position reports either side of it (1 Hz: the entry may fall between two)
    near = positions_between(obs.a, obs.started, obs.watch[1] or obs.a.now())
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
    if is_accepted(obs.request_ack):
        raise PreconditionFailed(f"GCS {route.partner}'s request was granted at once, so there was nothing to "
                                 "relay (HO.SEQ.03 judges that)")
    if obs.forward is None:
        raise ClauseFailed(f"GCS {route.partner}'s request for control (answered {result_text(obs.request_ack)}) did not "
                           f"reach the commander, GCS {route.parent}, within {FORWARD_WAIT * s.scale:g} s; expected "
                           "the same MAV_CMD_REQUEST_OPERATOR_CONTROL relayed to it (param4 = the partner)")
    a.decided_by_frame(obs.forward)
    msg = obs.forward.msg
    if msg.param1 != cm.ACTION_REQUEST or msg.param4 != route.partner:
        raise ClauseFailed(f"the request relayed to the commander, GCS {route.parent}, had {params_text(obs.forward)}; "
                           f"expected param1=1 (a request) and param4={route.partner} (the partner)")


@check("HO.SEQ.03")
def no_switch_before_authorisation(s: Session) -> None:
    obs = _observed(s)
    route, a, b = obs.route, obs.a, obs.b
    for frame, which in ((obs.request_ack, "request"), (obs.repeat_ack, "repeated request")):
        if is_accepted(frame):
            b.decided_by_frame(frame)
            raise ClauseFailed(f"GCS {route.partner}'s {which} for control was granted (MAV_RESULT_ACCEPTED) before "
                               f"the commander, GCS {route.parent}, authorised the handover; expected it refused "
                               "until then")
    for at, frame in obs.held:
        if frame.msg.gcs_main != route.parent:
            shown(a, frame)
            raise ClauseFailed(Measured(f"<after> s after GCS {route.partner} asked for control, before the "
                                        f"commander authorised, {status_text(frame)} came; expected "
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
    if not is_accepted(obs.allow_ack):
        raise PreconditionFailed(f"setup: the commander's re-request with takeover allowed got {result_text(obs.allow_ack)}")
    if not is_accepted(obs.grant_ack):
        if obs.grant_ack is not None:
            b.decided_by_frame(obs.grant_ack)
        raise ClauseFailed(f"after the commander, GCS {route.parent}, authorised (re-requested control with "
                           f"takeover allowed: MAV_RESULT_ACCEPTED), GCS {route.partner}'s request was answered "
                           f"{result_text(obs.grant_ack)}; expected MAV_RESULT_ACCEPTED")
    if obs.named is None:
        raise ClauseFailed(f"GCS {route.partner} was granted control, but no CONTROL_STATUS with "
                           f"gcs_main={route.partner} came within {STATUS_WAIT * s.scale:g} s")
    shown(a, obs.named)


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
        raise ClauseFailed(f"the connect notice to GCS {route.partner} had {params_text(obs.notice)}; expected "
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
                           f"{route.parent}, was answered {result_text(old)}; expected MAV_RESULT_NOT_IN_CONTROL")
    if new is None or new.msg.result == CommandResult.NOT_IN_CONTROL:
        if new is not None:
            b.decided_by_frame(new)
        raise ClauseFailed(f"after the handover, the same command from the new commander, GCS {route.partner}, "
                           f"was answered {result_text(new)}; expected an answer as to the GCS in control")
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
                                    f"({params_text(obs.reinvitation)}): a new handover; expected one per entry "
                                    "into the region", after=f"{arrival_of(a, obs.reinvitation) - since:.2f}"))
    outside = [p for _, p in positions_between(a, since, until) if not route.inside(p)]
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
        with flown(s, route, round(hold, 1)) as flight:
            a = obs.a = flight.a
            obs.b = flight.b
            obs.invited_at, invitation = await_invitation(s, flight)
            a.mark()
            obs.request_ack = partner_asks(flight, invitation)
            if not is_accepted(obs.request_ack):
                forward = a.poll_for(RELAYED, FORWARD_WAIT)
                if forward is not None:
                    ack_command(a, forward)
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
            b.note(f"CONTROL_STATUS shows takeover allowed: GCS {gcs_id(b)} asks again")
            obs.retries.append(ask_control(b, cm.ACTION_REQUEST, timeout=timeout))


@check("HO.SEQ.07")
def silent_commander_keeps_control(s: Session) -> None:
    route = _applicable(s)
    obs = s.shared(_SILENT, lambda: _silent(s, route))
    a, b = the_gcss(s, route)
    _reraise(obs.stop)
    if is_accepted(obs.request_ack):
        raise PreconditionFailed(f"GCS {route.partner}'s request was granted at once, before the commander "
                                 "authorised (HO.SEQ.03 judges that)")
    statuses = statuses_between(a, obs.invited_at, obs.until)
    for at, frame in statuses:
        if frame.msg.gcs_main != route.parent:
            shown(a, frame)
            raise ClauseFailed(Measured(f"GCS {route.parent}, the commander, never authorised, yet <after> s after "
                                        f"the invitation {status_text(frame)} came; expected GCS {route.parent} "
                                        f"to keep control and the handover to end within its {route.bound:g} s bound",
                                        after=f"{at - obs.invited_at:.2f}"))
    for frame in obs.retries:
        if is_accepted(frame):
            b.decided_by_frame(frame)
            raise ClauseFailed(Measured(f"GCS {route.parent}, the commander, never authorised, yet <after> s after "
                                        f"the invitation GCS {route.partner}'s request was granted "
                                        f"(MAV_RESULT_ACCEPTED); expected GCS {route.parent} to keep control and "
                                        f"the handover to end within its {route.bound:g} s bound",
                                        after=f"{arrival_of(b, frame) - obs.invited_at:.2f}"))
    late = [f for at, f in statuses if at > obs.invited_at + route.bound]
    if not late:
        raise PreconditionFailed(f"no CONTROL_STATUS came after the {route.bound:g} s bound to judge by "
                                 "(HO.CTL.01 judges the stream)")
    shown(a, late[-1])

