"""Mission progress in flight (seed 000, "Monitor Mission Progress"): MIS.PRG.*

Both clauses are decided from one short flight: a 3-waypoint plan a few metres from where
the vehicle is, started with MAV_CMD_MISSION_START.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from reference_impl.mission.constants import Cmd, CommandResult, MissionState
from reference_impl.mission.items import MissionType
from reference_impl.wire.dialect import mavlink as _d

from ..harness import plans, procedures
from ..harness.match import msg
from ..harness.tester import Tester
from ..outcome import ClauseFailed, PreconditionFailed, Skipped
from ..session import Session
from . import check

MISSION = MissionType.MISSION
PLAN_SIZE = 3
FLIGHT_WINDOW = 20.0     # s the whole flight may take (a real vehicle may have to climb first)
FLIGHT_ALT = 5.0         # m above home: a short climb (variant 1: the legs are under 1 m)
LATE_CURRENT = 1.5       # s after the last item for a MISSION_CURRENT still owed
REACHED = msg("MISSION_ITEM_REACHED")
CURRENT = msg("MISSION_CURRENT")
COMPLETE = msg("MISSION_CURRENT", seq=PLAN_SIZE - 1, mission_state=int(MissionState.COMPLETE))


@dataclass
class Flight:
    reached: list[int]       # seq of every MISSION_ITEM_REACHED, in arrival order
    currents: list[int]      # seq of every MISSION_CURRENT from the start on, in arrival order
    finished: bool           # the last item was reached (or the mission reported complete)


def _home(t: Tester) -> tuple[int, int]:
    """Where the vehicle is, from its latest GLOBAL_POSITION_INT; the default home if none."""
    for _, frame in reversed(t.node.inbox):
        if frame.msg._type == "GLOBAL_POSITION_INT" and (frame.msg.lat or frame.msg.lon):
            return frame.msg.lat, frame.msg.lon
    return plans.DEFAULT_HOME


def _mission_start(t: Tester, last: int):
    return _d.MAVLink_command_long_message(t.target[0], t.target[1], int(Cmd.MISSION_START), 0,
                                           0, float(last), 0, 0, 0, 0, 0)


def flight(s: Session) -> Flight:
    if not s.allow_flight:
        raise Skipped("needs --allow-flight: the check flies the vehicle")
    return s.shared("mission_flight", lambda: _fly(s.t))


def _fly(t: Tester) -> Flight:
    items = [replace(it, z=FLIGHT_ALT)
             for it in plans.mission(PLAN_SIZE, variant=1, home=_home(t))]
    procedures.ensure_plan(t, items, MISSION)
    t.mark()
    t.send(_mission_start(t, PLAN_SIZE - 1))
    reply = t.expect(msg("COMMAND_ACK", command=int(Cmd.MISSION_START)))
    if reply.msg.result not in (CommandResult.ACCEPTED, CommandResult.IN_PROGRESS):
        raise PreconditionFailed(f"MAV_CMD_MISSION_START was answered with MAV_RESULT "
                                 f"{reply.msg.result}; the vehicle would not fly the plan")
    last = msg("MISSION_ITEM_REACHED", seq=PLAN_SIZE - 1)
    seen = t.collect(REACHED | CURRENT, FLIGHT_WINDOW, stop=last | COMPLETE)
    reached = [f.msg.seq for _, f in seen if f.msg._type == "MISSION_ITEM_REACHED"]
    currents = [f.msg.seq for _, f in seen if f.msg._type == "MISSION_CURRENT"]
    finished = bool(seen) and (last(seen[-1][1]) or COMPLETE(seen[-1][1]))
    if finished and PLAN_SIZE - 1 not in currents:
        late = t.poll_for(msg("MISSION_CURRENT", seq=PLAN_SIZE - 1), LATE_CURRENT)
        if late is not None:
            currents.append(late.msg.seq)
    if not finished:
        t.note("the flight did not finish: a new upload of the plan should stop it")
        procedures.upload(t, items, MISSION)
    return Flight(reached, currents, finished)


@check("MIS.PRG.01")
def item_reached_broadcast(s: Session) -> None:
    got = flight(s)
    want = list(range(PLAN_SIZE))
    firsts = list(dict.fromkeys(got.reached))   # repeats of a report are harmless
    if firsts != want:
        raise ClauseFailed(f"flying a {PLAN_SIZE}-item plan, MISSION_ITEM_REACHED came for seq "
                           f"{firsts or 'none'}; expected {want}, in order"
                           + ("" if got.finished else
                              f" (the flight did not finish within {FLIGHT_WINDOW * s.scale:g} s)"))


@check("MIS.PRG.02")
def current_broadcast_in_flight(s: Session) -> None:
    got = flight(s)
    missing = [seq for seq in range(1, PLAN_SIZE) if seq not in got.currents]
    if missing:
        raise ClauseFailed(f"flying a {PLAN_SIZE}-item plan, the current item became "
                           f"{', '.join(map(str, range(1, PLAN_SIZE)))} in turn, but no MISSION_CURRENT "
                           f"reported seq {', '.join(map(str, missing))} (MISSION_CURRENT seqs seen: "
                           f"{got.currents or 'none'})")
