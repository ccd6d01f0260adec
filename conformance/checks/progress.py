"""Mission progress in flight (seed 000, "Monitor Mission Progress"): MIS.PRG.*

Both clauses are decided from one short flight: a 3-waypoint plan laid out from where the
vehicle is, legs longer than its acceptance radius, started the way its autopilot accepts
(`harness.flight`).
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.mission.constants import MissionState
from mavconform.reference_impl.mission.items import MissionType

from ..harness import flight as flying
from ..harness import procedures
from ..harness.match import msg
from ..outcome import ClauseFailed, Skipped
from ..session import Session
from . import check

MISSION = MissionType.MISSION
PLAN_SIZE = 3
FLIGHT_WINDOW = 90.0     # s the whole flight may take (ends at the last item: 75 m at a few m/s)
LATE_CURRENT = 1.5       # s after the last item for a MISSION_CURRENT still owed
REACHED = msg("MISSION_ITEM_REACHED")
CURRENT = msg("MISSION_CURRENT")
COMPLETE = msg("MISSION_CURRENT", seq=PLAN_SIZE - 1, mission_state=int(MissionState.COMPLETE))


@dataclass
class Flight:
    reached: list[int]       # seq of every MISSION_ITEM_REACHED, in arrival order
    currents: list[int]      # seq of every MISSION_CURRENT from the start on, in arrival order
    finished: bool           # the last item was reached (or the mission reported complete)


def flight(s: Session) -> Flight:
    if not s.allow_flight:
        raise Skipped("needs --allow-flight: the check flies the vehicle")
    return s.shared("mission_flight", lambda: _fly(s))


def _fly(s: Session) -> Flight:
    t = s.t
    items = flying.flight_plan(t, PLAN_SIZE)
    accepted = procedures.ensure_plan(t, items, MISSION)
    procedures.await_plan_taken(t, accepted)
    t.mark()
    flying.start(t, (s.identity or {}).get("autopilot"))
    last = msg("MISSION_ITEM_REACHED", seq=PLAN_SIZE - 1)
    seen = t.collect(REACHED | CURRENT, FLIGHT_WINDOW, stop=last | COMPLETE)
    reached = [f.msg.seq for _, f in seen if f.msg._type == "MISSION_ITEM_REACHED"]
    currents = [f.msg.seq for _, f in seen if f.msg._type == "MISSION_CURRENT"]
    finished = bool(seen) and (last(seen[-1][1]) or COMPLETE(seen[-1][1]))
    if finished and PLAN_SIZE - 1 not in currents:
        late = t.poll_for(msg("MISSION_CURRENT", seq=PLAN_SIZE - 1), LATE_CURRENT)
        if late is not None:
            currents.append(late.msg.seq)
    flying.end(t)
    return Flight(reached, currents, finished)


@check("MIS.PRG.01")
def item_reached_broadcast(s: Session) -> None:
    got = flight(s)
    want = list(range(s.t.form.first_flown(), PLAN_SIZE))   # slot 0 may be home: not flown
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
