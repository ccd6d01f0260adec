"""After every flight attempt, flown or failed: the vehicle on the ground and disarmed.

A conformance run must never leave a vehicle armed (on a bench, an armed aircraft is a
hazard). Whatever happened before (a finished mission, a refused start, a clause cut off),
`land_and_disarm` brings a vehicle that is still armed down, the way its autopilot lands
(its LAND mode; a fixed-wing flies its plan's own landing approach; a ground vehicle stops),
disarms it once it is on the ground and stopped, and confirms that from a HEARTBEAT sent
afterwards. It never raises: what it could not do is its result, which the run report
shows at the top (`Ending.disarmed` False), never a silent line. Every wait is bounded.
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult
from mavconform.reference_impl.vehicle_class import VehicleClass

from .flight_plan import FlightPlan
from .flight_styles import FlightStyle, Mode
from .match import msg
from .procedures import command_result_name
from .tester import Tester
from .vehicle_watch import VehicleWatch

LAND_WINDOW = {VehicleClass.FIXED_WING: 300.0, VehicleClass.VTOL: 180.0}
LAND_WINDOW_DEFAULT = 120.0     # s for a vehicle still flying to be on the ground
SETTLE = 3.0                    # s on the ground and stopped before it is disarmed
DISARM_TRIES = 3
HEARTBEAT_WAIT = 3.0            # s: HEARTBEATs come at 1 Hz
AUTO_DISARM_WAIT = 5.0          # s a landed vehicle may take to disarm by itself (PX4 COM_DISARM_LAND 2 s)
GOING = (CommandResult.ACCEPTED, CommandResult.IN_PROGRESS)


@dataclass
class Ending:
    """How a flight ended. `disarmed`: True, confirmed by a HEARTBEAT; False, the vehicle
    may still be armed; None, its HEARTBEAT never shows arming, so nobody can tell."""
    disarmed: bool | None
    detail: str

    def as_dict(self) -> dict:
        return {"disarmed": self.disarmed, "detail": self.detail}


def land_and_disarm(t: Tester, watch: VehicleWatch, style: FlightStyle, plan: FlightPlan | None) -> Ending:
    """Bring the vehicle down and disarmed (see the module docstring)."""
    done: list[str] = []
    try:
        return _land_and_disarm(t, watch, style, plan, done)
    except Exception as exc:   # a dead link, a bug: still a reported ending, never a traceback
        return Ending(False, "; ".join(done + [f"ending the flight failed: {type(exc).__name__}: {exc}"]))


def _land_and_disarm(t: Tester, watch: VehicleWatch, style: FlightStyle, plan: FlightPlan | None,
                     done: list[str]) -> Ending:
    asked = t.now()
    t.wait_until(lambda: watch.heartbeat_since(asked), HEARTBEAT_WAIT)
    if watch.armed is None:
        return Ending(False, "no HEARTBEAT came after the flight: whether the vehicle is disarmed is unknown")
    if not watch.armed:
        return _disarmed(t, watch, done, "its HEARTBEAT shows it disarmed")
    if style.vehicle is not VehicleClass.GROUND:
        if not _on_ground(watch):
            done.append(_bring_down(t, watch, style, plan))
            window = LAND_WINDOW.get(style.vehicle, LAND_WINDOW_DEFAULT)
            landed = t.wait_until(lambda: watch.armed is False or watch.still_for() >= SETTLE, window)
            if not landed:
                return Ending(False, "; ".join(done + [f"the vehicle was not on the ground within {window * t.scale:g} s "
                                                       f"({watch.describe()}): IT MAY STILL BE ARMED AND FLYING"]))
            if not watch.armed:
                return _disarmed(t, watch, done, "it landed and disarmed itself")
            done.append("it is on the ground")
        t.wait_until(lambda: watch.armed is False, AUTO_DISARM_WAIT)   # most aircraft disarm once landed
        if not watch.armed:
            return _disarmed(t, watch, done, "it disarmed itself on the ground")
    elif style.stop is not None:
        done.append(_set_mode(t, watch, style.stop))
    t.wait_until(lambda: watch.still_for() >= SETTLE, LAND_WINDOW_DEFAULT)
    for attempt in range(DISARM_TRIES):
        sent = t.now()
        reply = _command(t, Cmd.COMPONENT_ARM_DISARM, 0.0)
        t.wait_until(lambda: watch.heartbeat_since(sent + 0.01) and watch.armed is False, HEARTBEAT_WAIT)
        if watch.armed is False:
            return _disarmed(t, watch, done, f"disarmed by MAV_CMD_COMPONENT_ARM_DISARM 0 ({_said(reply)})")
        done.append(f"disarm {attempt + 1} answered {_said(reply)}, still armed")
    return Ending(False, "; ".join(done + [f"the vehicle would not disarm ({watch.describe()}): IT MAY STILL BE ARMED"]))


def _disarmed(t: Tester, watch: VehicleWatch, done: list[str], how: str) -> Ending:
    text = "; ".join(done + [how])
    if not watch.ever_armed:
        return Ending(None, text + "; its HEARTBEAT never showed it armed, so that says little: "
                      "check the vehicle")
    t.note(f"the flight is over: {text}")
    return Ending(True, text)


def _on_ground(watch: VehicleWatch) -> bool:
    height = watch.height_m
    return height is not None and watch.still_for() > 0 and height < 1.0


def _bring_down(t: Tester, watch: VehicleWatch, style: FlightStyle, plan: FlightPlan | None) -> str:
    """Start the landing; what was asked, for the ending's detail."""
    if style.fixed_wing_landing and plan is not None and plan.approach is not None:
        if style.arm_in is not None and watch.mode != style.arm_in.custom_mode:
            _set_mode(t, watch, style.arm_in)
        t.send(m.set_current_message(plan.approach, t.target))
        t.note(f"landing: MISSION_SET_CURRENT {plan.approach}, the plan's own landing approach")
        return f"sent it to its landing approach (item {plan.approach})"
    if style.land is not None:
        return _set_mode(t, watch, style.land)
    command, what = ((Cmd.NAV_RETURN_TO_LAUNCH, "MAV_CMD_NAV_RETURN_TO_LAUNCH")
                     if style.vehicle is VehicleClass.FIXED_WING else (Cmd.NAV_LAND, "MAV_CMD_NAV_LAND"))
    reply = _command(t, command)
    return f"{what} ({_said(reply)})"


def _set_mode(t: Tester, watch: VehicleWatch, mode: Mode) -> str:
    reply = _command(t, Cmd.DO_SET_MODE, *mode.params)
    shown = t.wait_until(lambda: watch.mode == mode.custom_mode, HEARTBEAT_WAIT)
    return f"mode {mode} ({_said(reply)}{'' if shown else ', not shown by the HEARTBEAT'})"


def _command(t: Tester, command: int, *params: float):
    t.mark()
    t.send(m.command_long_message(command, t.target, *params))
    return t.poll_for(msg("COMMAND_ACK", command=int(command)), t.timings.default_timeout)


def _said(reply) -> str:
    return "no COMMAND_ACK" if reply is None else command_result_name(reply.msg.result)
