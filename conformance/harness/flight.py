"""Flying a target's mission for the progress clauses, the way its autopilot flies it.

A real vehicle flies only from where it is, once armed, in a mode that runs missions, and
reports an item reached only past its acceptance radius (VARIANTS.md L6, L9); how it is
started depends on the autopilot *and* the vehicle type (`flight_styles`). So:
1. the style comes from the HEARTBEAT (autopilot, MAV_TYPE); a type the suite does not fly
   makes the clauses not-applicable, with the reason;
2. the plan is laid out from the vehicle's HOME_POSITION (asked for with
   MAV_CMD_REQUEST_MESSAGE), sized from the radii it reports (PARAM_REQUEST_READ), for its
   class (`flight_plan`): no home, no flight (not-applicable), never a fixed place;
3. the first item is made current (ArduCopter's MISSION_START resumes from the current
   item, which an earlier set-current clause may have left anywhere);
4. the mode the style arms in is asked for and confirmed from the HEARTBEAT before the
   vehicle is armed (a mode number of the wrong vehicle type is another mode: ArduCopter's
   GUIDED 4 is ArduPlane's ACRO); arming is retried while the vehicle is not ready;
5. and whatever happens, the flight ends with `landing.land_and_disarm`, whose result is
   kept for the run report.
A step the vehicle answers MAV_RESULT_UNSUPPORTED is one it does not have (the generic
style's vehicles need no arming).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionState
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.vehicle_class import type_name, vehicle_class
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.wire.frame import Frame

from ..outcome import NotApplicable, PreconditionFailed
from . import procedures
from .flight_plan import FlightPlan, Home, layout, radius
from .flight_styles import FlightStyle, Mode, style_for
from .landing import Ending, land_and_disarm
from .match import msg
from .tester import Tester
from .vehicle_watch import VehicleWatch

POSITION_WAIT = 5.0      # s for a GLOBAL_POSITION_INT with a position, if none came yet
HOME_WAIT = 30.0         # s for a HOME_POSITION (ArduPilot sets home ~20 s after boot)
HOME_RETRY = 1.5         # s between requests
PARAM_WAIT = 1.0         # s for a PARAM_VALUE
MODE_WINDOW = 30.0       # s a mode change may be refused while the vehicle gets ready
ARM_WINDOW = 60.0        # s arming may be refused while the vehicle gets ready (ArduPilot: ~40 s after boot)
RETRY = 2.0              # s between attempts
HEARTBEAT_WAIT = 3.0     # s for the HEARTBEAT to show a change (HEARTBEATs are 1 Hz)
GOING = (CommandResult.ACCEPTED, CommandResult.IN_PROGRESS)
UNSUPPORTED = CommandResult.UNSUPPORTED
HOME_POSITION_ID = 242
POSITION = msg("GLOBAL_POSITION_INT", where=lambda f: bool(f.msg.lat or f.msg.lon),
               label="GLOBAL_POSITION_INT with a position")
PROGRESS = ("MISSION_ITEM_REACHED", "MISSION_CURRENT")


@dataclass
class Flown:
    """What one flight showed: the progress messages from the start on, in arrival order."""
    plan: FlightPlan
    style: FlightStyle
    reached: list[int] = field(default_factory=list)     # seq of every MISSION_ITEM_REACHED
    currents: list[int] = field(default_factory=list)    # seq of every MISSION_CURRENT
    finished: bool = False                                # it reached its end (or landed, disarmed)
    ending: Ending | None = None


def style_of(identity: dict[str, Any] | None) -> FlightStyle:
    """The flight style for a discovered target; NotApplicable for a type not flown."""
    identity = identity or {}
    mav_type, autopilot = identity.get("type"), identity.get("autopilot")
    style = style_for(autopilot, vehicle_class(mav_type))
    if style is None:
        raise NotApplicable(f"the vehicle is a {type_name(mav_type)} (MAV_TYPE {mav_type}): the suite flies "
                            "multicopters, fixed-wings, VTOLs and ground vehicles only, so there is no flight "
                            "to judge progress from")
    return style


def where(t: Tester) -> tuple[int, int]:
    """(lat, lon) in degE7 from the vehicle's latest GLOBAL_POSITION_INT, waiting a little
    for one; NotApplicable if the vehicle reports no position (the handover clauses lay
    their route out from where the vehicle is)."""
    for _, frame in reversed(t.node.inbox):
        if POSITION(frame):
            return frame.msg.lat, frame.msg.lon
    frame = t.poll_for(POSITION, POSITION_WAIT, forced=True)
    if frame is None:
        raise NotApplicable("the vehicle reports no position (no GLOBAL_POSITION_INT with a fix, even "
                            "when asked for it), so there is nowhere to lay a flight out from; a plan "
                            "at a fixed place is never flown")
    return frame.msg.lat, frame.msg.lon


def home_position(t: Tester) -> Home:
    """The vehicle's home (HOME_POSITION, asked for with MAV_CMD_REQUEST_MESSAGE 242);
    NotApplicable if it has none: a vehicle without home has no position fix to fly from."""
    found = None
    opened = t.now()
    for _ in range(int(HOME_WAIT / HOME_RETRY) + 1):
        t.mark()
        t.send(m.command_long_message(Cmd.REQUEST_MESSAGE, t.target, HOME_POSITION_ID))
        found = t.poll_for(msg("HOME_POSITION"), HOME_RETRY, forced=True)
        if found is not None or t.now() - opened > HOME_WAIT * t.scale:
            break
    if found is None or not (found.msg.latitude or found.msg.longitude):
        raise NotApplicable(f"the vehicle sent no HOME_POSITION within {HOME_WAIT * t.scale:g} s (asked for with "
                            "MAV_CMD_REQUEST_MESSAGE 242): without a home there is no position fix to lay a flight "
                            "out from; a plan at a fixed place is never flown")
    return Home(found.msg.latitude, found.msg.longitude, found.msg.altitude / 1000.0)


def read_param(t: Tester, names: tuple[tuple[str, float], ...]) -> tuple[float | None, str]:
    """The first of `names` the vehicle answers PARAM_REQUEST_READ for, in metres."""
    for name, scale in names:
        t.mark()
        t.send(_d.MAVLink_param_request_read_message(t.target[0], t.target[1], name.encode(), -1))
        reply = t.poll_for(msg("PARAM_VALUE", where=lambda f, n=name: _param_id(f.msg) == n), PARAM_WAIT)
        if reply is not None:
            return reply.msg.param_value * scale, f"{name} {reply.msg.param_value:g}"
    return None, ""


def plan_for(t: Tester, style: FlightStyle) -> FlightPlan:
    """Lay the flight out from home, legs sized from the radii the vehicle reports."""
    home = home_position(t)
    acceptance, said_a = read_param(t, style.acceptance_params)
    loiter, said_l = read_param(t, style.loiter_params)
    r = radius(style.vehicle, acceptance, loiter)
    plan = layout(style.vehicle, home, r, home_slot=t.form.home_slot_of(MissionType.MISSION))
    said = ", ".join(s for s in (said_a, said_l) if s) or "no radius parameter answered"
    t.note(f"flight ({style.name}): {plan.summary}; legs from R = {r:g} m ({said}); "
           f"{plan.path_m:g} m, bounded at {plan.window_s:g} s")
    return plan


def start(t: Tester, watch: VehicleWatch, style: FlightStyle) -> None:
    """Get the vehicle flying its mission from the current item; PreconditionFailed if it
    will not (the caller still lands and disarms it)."""
    if style.arm_in is None:
        _command(t, Cmd.MISSION_START, "start the mission", 0.0, 0.0)
        return
    set_mode(t, watch, style.arm_in)
    if _arm(t, watch):
        if style.start_after_arming:
            _command(t, Cmd.MISSION_START, "start the mission", 0.0, 0.0)
    else:
        _command(t, Cmd.MISSION_START, "start the mission", 0.0, 0.0)


def set_mode(t: Tester, watch: VehicleWatch, mode: Mode) -> None:
    """MAV_CMD_DO_SET_MODE, retried while refused (bounded), then confirmed from the
    HEARTBEAT: nothing is armed in a mode the suite did not see."""
    opened = t.now()
    for _ in range(int(MODE_WINDOW / RETRY) + 1):
        result = _command(t, Cmd.DO_SET_MODE, f"set mode {mode}", *mode.params, refusal_ok=True)
        if result in GOING:
            break
        if t.now() - opened > MODE_WINDOW * t.scale:
            raise PreconditionFailed(f"flight: mode {mode} was refused for {MODE_WINDOW * t.scale:g} s "
                                     f"(last: {procedures.command_result_name(result)})")
        t.wait_until(lambda: False, RETRY)
    if not t.wait_until(lambda: watch.mode == mode.custom_mode, HEARTBEAT_WAIT):
        raise PreconditionFailed(f"flight: mode {mode} was accepted but the HEARTBEAT shows custom_mode "
                                 f"{watch.mode}, not {mode.custom_mode}: not arming in a mode not seen")
    t.note(f"flight: the HEARTBEAT shows mode {mode}")


def _arm(t: Tester, watch: VehicleWatch) -> bool:
    """Arm, retrying while the vehicle is not ready yet; confirmed from the HEARTBEAT.
    False if it has no arming step (UNSUPPORTED)."""
    opened = t.now()
    said: list[str] = []
    for _ in range(int(ARM_WINDOW / RETRY) + 1):
        t.mark()
        t.send(m.command_long_message(Cmd.COMPONENT_ARM_DISARM, t.target, 1.0))
        reply = t.poll_for(msg("COMMAND_ACK", command=Cmd.COMPONENT_ARM_DISARM), t.timings.default_timeout)
        if reply is not None and reply.msg.result == UNSUPPORTED:
            return False
        if reply is not None and reply.msg.result in GOING:
            if t.wait_until(lambda: watch.armed is True, HEARTBEAT_WAIT):
                t.note("flight: the HEARTBEAT shows the vehicle armed")
                return True
            said += _statustexts(t)   # it disarmed at once (a pre-arm check): try again, as for a refusal
            t.note(f"flight: arming was accepted but the HEARTBEAT does not show it armed ({watch.describe()})")
        else:
            said += _statustexts(t)
        if t.now() - opened > ARM_WINDOW * t.scale:
            break
        t.wait_until(lambda: False, RETRY)   # the vehicle's own readiness: a forced wait
    why = f" (it said: {said[-1]})" if said else ""
    raise PreconditionFailed(f"flight: the vehicle refused to arm for {ARM_WINDOW * t.scale:g} s{why}")


def watch_progress(t: Tester, flown: Flown, watch: VehicleWatch) -> None:
    """Collect MISSION_ITEM_REACHED / MISSION_CURRENT until the flight is over: the vehicle
    disarmed after flying (landed), or its last item reached or the mission reported
    complete (for a plan that ends with a landing, only once a vehicle that shows arming
    has disarmed); bounded by the plan's window."""
    last = flown.plan.last

    def on_frame(_at: float, frame: Frame) -> None:
        name = frame.msg._type
        if name == "MISSION_ITEM_REACHED":
            flown.reached.append(frame.msg.seq)
            flown.finished |= frame.msg.seq == last
        elif name == "MISSION_CURRENT":
            flown.currents.append(frame.msg.seq)
            flown.finished |= (frame.msg.seq == last
                               and getattr(frame.msg, "mission_state", 0) == MissionState.COMPLETE)

    watch.on_frame = on_frame

    lands = flown.plan.lands

    def over() -> bool:
        watch.update()
        if watch.ever_armed and watch.armed is False:   # landed (or stopped) and disarmed
            return True
        # a plan that ends with a landing is over once the vehicle is down: a report for the
        # landing item may come as it starts to descend
        return flown.finished and not (lands and watch.ever_armed)

    t.wait_until(over, flown.plan.window_s)
    watch.on_frame = None
    flown.finished |= watch.ever_armed and watch.armed is False


def _command(t: Tester, command: int, what: str, *params: float, refusal_ok: bool = False) -> int | None:
    """Send one COMMAND_LONG; its result. UNSUPPORTED is a step the vehicle does not have
    (noted, None); another refusal raises PreconditionFailed unless `refusal_ok`."""
    t.mark()
    t.send(m.command_long_message(command, t.target, *params))
    reply = t.poll_for(msg("COMMAND_ACK", command=int(command)), t.timings.default_timeout)
    if reply is None:
        raise PreconditionFailed(f"flight: {what}: no COMMAND_ACK within {t.reply_timeout:g} s")
    result = reply.msg.result
    if result == UNSUPPORTED:
        t.note(f"flight: {what}: the vehicle has no such step (MAV_RESULT_UNSUPPORTED); going on")
        return None
    if result not in GOING and not refusal_ok:
        said = _statustexts(t)
        raise PreconditionFailed(f"flight: {what} was refused with {procedures.command_result_name(result)}"
                                 + (f" (it said: {said[-1]})" if said else ""))
    return result


def _statustexts(t: Tester) -> list[str]:
    """The STATUSTEXTs since the last mark (a refusal's reason, as the vehicle said it)."""
    return [_text(f.msg) for f in t.since_mark() if f.msg._type == "STATUSTEXT"]


def _text(message: Any) -> str:
    text = message.text
    return text.decode(errors="replace").rstrip("\0") if isinstance(text, bytes) else str(text).rstrip("\0")


def _param_id(message: Any) -> str:
    pid = message.param_id
    return (pid.decode(errors="replace") if isinstance(pid, bytes) else str(pid)).rstrip("\0")
