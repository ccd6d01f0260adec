"""Flying a target's mission for the progress clauses, the way its autopilot accepts.

A real vehicle flies only from where it is, once armed, in a mode that runs missions, and
reports an item reached only past its acceptance radius (VARIANTS.md L6, L9). So the plan
is laid out from the position the vehicle reports (never a fixed place: with no position
the flight is refused and the report says why), its legs are longer than any stock
acceptance radius (PX4 NAV_ACC_RAD 10 m, ArduCopter WPNAV_RADIUS 2 m), and the start
follows the autopilot family from the HEARTBEAT:
- ArduPilot (3): GUIDED, arm, take off, then MAV_CMD_MISSION_START with params 0, 0
  (ArduCopter's `GCS_MAVLINK_Copter::handle_command_mission_start` needs them so);
- every other target, PX4 (12) included: MAV_CMD_MISSION_START 0, 0 (PX4's commander
  switches to AUTO_MISSION and arms on it).
Before the start the first item is made current (MISSION_SET_CURRENT): ArduCopter's
MISSION_START resumes from the current item (`AP_Mission::start_or_resume`, MIS_RESTART 0),
which an earlier set-current clause may have left anywhere.
A step the vehicle answers MAV_RESULT_UNSUPPORTED is one it does not have (our reference
vehicle needs no arming); a refusal of arming is retried until the vehicle is ready, within
a bound. After the flight the vehicle is sent home (MAV_CMD_NAV_RETURN_TO_LAUNCH), so the
plans later clauses upload are not flown.
"""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult
from mavconform.reference_impl.mission.items import MissionItem
from mavconform.reference_impl.wire.dialect import mavlink as _d

from ..outcome import NotApplicable, PreconditionFailed
from . import plans, procedures
from .match import msg
from .tester import Tester

LEG_M = 25.0             # m between waypoints: longer than any stock acceptance radius
ALTITUDE_M = 10.0        # m above home
POSITION_WAIT = 5.0      # s for a GLOBAL_POSITION_INT with a position, if none came yet
ARM_WINDOW = 60.0        # s arming may be refused while the vehicle gets ready (ArduPilot: ~40 s after boot)
ARM_RETRY = 2.0          # s between arming attempts
CLIMB_WAIT = 30.0        # s for the take-off to reach most of its altitude
METRES_PER_DEGREE = 111_320.0

COPTER_GUIDED = 4        # ArduCopter custom mode (ArduCopter mode.h Mode::Number::GUIDED)
GOING = (CommandResult.ACCEPTED, CommandResult.IN_PROGRESS)
UNSUPPORTED = CommandResult.UNSUPPORTED
POSITION = msg("GLOBAL_POSITION_INT", where=lambda f: bool(f.msg.lat or f.msg.lon), label="GLOBAL_POSITION_INT with a position")


def where(t: Tester) -> tuple[int, int]:
    """(lat, lon) in degE7 from the vehicle's latest GLOBAL_POSITION_INT, waiting a little
    for one; NotApplicable if the vehicle reports no position to fly from."""
    for _, frame in reversed(t.node.inbox):
        if POSITION(frame):
            return frame.msg.lat, frame.msg.lon
    frame = t.poll_for(POSITION, POSITION_WAIT, forced=True)
    if frame is None:
        raise NotApplicable("the vehicle reports no position (no GLOBAL_POSITION_INT with a fix, even "
                            "when asked for it), so there is nowhere to lay a flight out from; a plan "
                            "at a fixed place is never flown")
    return frame.msg.lat, frame.msg.lon


def flight_plan(t: Tester, n: int) -> list[MissionItem]:
    """`n` waypoints LEG_M apart, due north of where the vehicle is, ALTITUDE_M up."""
    lat, lon = where(t)
    step = round(LEG_M / METRES_PER_DEGREE * 1e7)
    return [replace(it, x=lat + step * (it.seq + 1), y=lon, z=ALTITUDE_M)
            for it in plans.mission(n, variant=1, home=(lat, lon))]


def start(t: Tester, autopilot: int | None) -> None:
    """Get the vehicle flying its mission from the first item; PreconditionFailed if it will not."""
    first = t.form.first_flown()
    if procedures.set_current(t, first)[0] is None:
        raise PreconditionFailed(f"flight: after MISSION_SET_CURRENT {first} no MISSION_CURRENT reported "
                                 f"item {first} current, so the flight would not start at the first item")
    if autopilot == _d.MAV_AUTOPILOT_ARDUPILOTMEGA:
        _command(t, Cmd.DO_SET_MODE, "set mode GUIDED", _d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, COPTER_GUIDED)
        if _arm(t):
            _command(t, Cmd.NAV_TAKEOFF, f"take off to {ALTITUDE_M:g} m", *([0.0] * 6), ALTITUDE_M)
            _climb(t)
    _command(t, int(Cmd.MISSION_START), "start the mission", 0.0, 0.0)


def end(t: Tester) -> None:
    """Send the vehicle home, so the plans later clauses upload are not flown."""
    t.note("the flight is over: MAV_CMD_NAV_RETURN_TO_LAUNCH")
    t.send(m.command_long_message(Cmd.NAV_RETURN_TO_LAUNCH, t.target))


def _command(t: Tester, command: int, what: str, *params: float) -> int | None:
    """Send one COMMAND_LONG; its result (None: the vehicle does not have the step)."""
    t.mark()
    t.send(m.command_long_message(command, t.target, *params))
    reply = t.poll_for(msg("COMMAND_ACK", command=command), t.timings.default_timeout)
    if reply is None:
        raise PreconditionFailed(f"flight: {what}: no COMMAND_ACK within {t.reply_timeout:g} s")
    result = reply.msg.result
    if result == UNSUPPORTED:
        t.note(f"flight: {what}: the vehicle has no such step (MAV_RESULT_UNSUPPORTED); going on")
        return None
    if result not in GOING:
        raise PreconditionFailed(f"flight: {what} was refused with {procedures.command_result_name(result)}")
    return result


def _arm(t: Tester) -> bool:
    """Arm, retrying while the vehicle is not ready yet; False if it has no arming step."""
    opened = t.now()
    for _ in range(int(ARM_WINDOW / ARM_RETRY) + 1):
        t.mark()
        t.send(m.command_long_message(Cmd.COMPONENT_ARM_DISARM, t.target, 1.0))
        reply = t.poll_for(msg("COMMAND_ACK", command=Cmd.COMPONENT_ARM_DISARM), t.timings.default_timeout)
        if reply is not None and reply.msg.result in GOING:
            return True
        if reply is not None and reply.msg.result == UNSUPPORTED:
            return False
        if t.now() - opened > ARM_WINDOW * t.scale:
            break
        t.wait_until(lambda: False, ARM_RETRY)   # the vehicle's own readiness: a forced wait
    raise PreconditionFailed(f"flight: the vehicle refused to arm for {ARM_WINDOW * t.scale:g} s "
                             "(is it ready to fly: GPS, EKF, pre-arm checks?)")


def _climb(t: Tester) -> None:
    enough = ALTITUDE_M * 0.8 * 1000   # GLOBAL_POSITION_INT.relative_alt is in mm
    if t.poll_for(msg("GLOBAL_POSITION_INT", relative_alt=lambda alt: alt >= enough), CLIMB_WAIT,
                  forced=True) is None:
        raise PreconditionFailed(f"flight: the vehicle did not climb to {ALTITUDE_M * 0.8:g} m within "
                                 f"{CLIMB_WAIT * t.scale:g} s of taking off")


