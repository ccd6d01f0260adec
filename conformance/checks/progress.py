"""Mission progress in flight (seed 000, "Monitor Mission Progress"): MIS.PRG.*

Both clauses are decided from one flight of a realistic plan (take-off, waypoints with DO
commands between them, a loiter, a landing), laid out from the vehicle's home for its class
and started the way its autopilot and vehicle type accept (`harness.flight`). The flight
always ends with the vehicle landed and disarmed, or the run report saying loudly that it
could not be (`harness.landing`).

"Reached" is about the items with a position (the navigation items): a DO command completes
at once and may be reported or not, but a waypoint the vehicle flew past must have its own
MISSION_ITEM_REACHED, also when a DO command follows it at once (where a vehicle that keeps
one pending report per link loses it). The landing the flight ends with need not be
reported: the mission ends there.
"""

from __future__ import annotations

from mavconform.reference_impl.mission.items import MissionType

from ..harness import flight as flying
from ..harness import procedures
from ..harness.landing import land_and_disarm
from ..harness.vehicle_watch import VehicleWatch
from ..outcome import ClauseFailed, PreconditionFailed, Skipped
from ..session import Session
from . import check

MISSION = MissionType.MISSION


def flight(s: Session) -> flying.Flown:
    if not s.allow_flight:
        raise Skipped("needs --allow-flight: the check flies the vehicle")
    flown = s.shared("mission_flight", lambda: _attempt(s))
    if isinstance(flown, Exception):
        raise flown
    return flown


def _attempt(s: Session) -> flying.Flown | Exception:
    """One flight for both clauses: a flight that could not be flown (not-applicable, a
    refused start) is the same answer for both, and is not tried twice."""
    try:
        return _fly(s)
    except Exception as exc:
        return exc


def _fly(s: Session) -> flying.Flown:
    t = s.t
    style = flying.style_of(s.identity)
    plan = flying.plan_for(t, style)
    accepted = procedures.ensure_plan(t, plan.items, MISSION)
    procedures.await_plan_taken(t, accepted)
    first = plan.flown[0]
    if procedures.set_current(t, first)[0] is None:
        raise PreconditionFailed(f"flight: after MISSION_SET_CURRENT {first} no MISSION_CURRENT reported "
                                 f"item {first} current, so the flight would not start at the first item")
    watch = VehicleWatch(t)
    flown = flying.Flown(plan, style)
    try:
        flying.start(t, watch, style)
        flying.watch_progress(t, flown, watch)
    except PreconditionFailed as exc:
        _end(s, flown, watch)
        raise PreconditionFailed(f"{exc}; afterwards: {flown.ending.detail}") from None
    finally:
        if flown.ending is None:   # flown, or cut off by anything else (an interrupt too)
            _end(s, flown, watch)
    return flown


def _end(s: Session, flown: flying.Flown, watch: VehicleWatch) -> None:
    flown.ending = land_and_disarm(s.t, watch, flown.style, flown.plan)
    s.record_flight(flown.style.name, flown.plan.summary, flown.ending)


def _frontier(got: flying.Flown) -> int | None:
    """The furthest item the vehicle is known to have got to (None: no progress at all)."""
    seen = got.reached + got.currents + ([got.plan.last] if got.finished else [])
    return max(seen) if seen else None


def _no_progress(s: Session, got: flying.Flown) -> PreconditionFailed:
    return PreconditionFailed(f"the flight made no progress the vehicle reported (no MISSION_ITEM_REACHED, no "
                              f"MISSION_CURRENT) and did not land within {got.plan.window_s * s.scale:g} s")


@check("MIS.PRG.01")
def item_reached_broadcast(s: Session) -> None:
    got = flight(s)
    frontier = _frontier(got)
    if frontier is None:
        raise _no_progress(s, got)
    plan = got.plan
    want = [k for k in plan.navigation if k < frontier and k != plan.last]
    navigation = set(plan.navigation)
    firsts = [k for k in dict.fromkeys(got.reached) if k in navigation]   # repeats and DO items aside
    missing = [k for k in want if k not in firsts]
    flown = f"flying {len(plan.flown)} items ({plan.summary})"
    if missing:
        raise ClauseFailed(f"{flown}, the vehicle got past navigation item(s) {_seqs(want)}, but no "
                           f"MISSION_ITEM_REACHED came for {_seqs(missing)} (reports seen, in order: "
                           f"{_seqs(list(dict.fromkeys(got.reached)))})")
    reported = [k for k in firsts if k in want]
    if reported != sorted(reported):
        raise ClauseFailed(f"{flown}, MISSION_ITEM_REACHED came for {_seqs(reported)}: not in the order flown")


@check("MIS.PRG.02")
def current_broadcast_in_flight(s: Session) -> None:
    got = flight(s)
    frontier = _frontier(got)
    if frontier is None:
        raise _no_progress(s, got)
    plan = got.plan
    became = [k for k in plan.navigation if plan.flown[0] < k <= frontier]
    missing = [k for k in became if k not in got.currents]
    if missing:
        raise ClauseFailed(f"flying {len(plan.flown)} items ({plan.summary}), navigation item(s) {_seqs(became)} "
                           f"became current in turn, but no MISSION_CURRENT reported {_seqs(missing)} "
                           f"(MISSION_CURRENT seqs seen: {_seqs(list(dict.fromkeys(got.currents)))})")


def _seqs(seqs: list[int]) -> str:
    return ", ".join(map(str, seqs)) or "none"
