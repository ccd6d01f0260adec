"""Run MSP clauses against a flight controller and decide each one (conformance/runner.py's
counterpart for the MSP role).

Before the first clause the runner asks MSP_API_VERSION (a flight controller that does not
answer is reported, and no clause is run) and reads the mission the flight controller holds;
after the last it writes that mission back if the run changed it. MSP has no command that
empties the list (INAV clears it only from its CLI, `wp reset`, or MAVLink's
MISSION_CLEAR_ALL), so a flight controller that held no mission keeps the last one a clause
wrote, and the restore says so; it is not saved (only MSP.WP.09 saves, and puts back what
was saved). A clause that meets silence is followed by one MSP_API_VERSION: no answer to it
either, and the remaining clauses are marked `error` without being run. A clause that did
not pass while the host lagged is run again, as the vehicle suite does (host_lag.py).
"""

from __future__ import annotations

import time
from typing import Iterable

from mavconform.reference_impl.msp.commands import Waypoint

from ..clause import Clause
from ..harness.exchange import Exchange
from ..outcome import ClauseResult, Outcome, TargetUnresponsive
from ..clause_loop import ClauseLoop
from ..host_lag import judged_on_time
from ..runner import DecidedResult, InterruptGuard, OnResult, RunOutcome, _measured, call_check
from .checks import MSP_CHECKS
from .session import MspSession


def _mark(session: MspSession, label: str, level: str = "info") -> None:
    mark = getattr(session.capture, "mark", None)
    if mark is not None:
        mark(label, clock=session.driver.clock, level=level)


def discover(session: MspSession) -> dict:
    """Who answers: MSP_API_VERSION and the waypoint store's size (TargetUnresponsive if nothing)."""
    t = session.tester
    api = t.expect("MSP_API_VERSION")
    info = t.info()
    if len(api.payload) >= 3:
        version = {"msp_protocol": api.payload[0], "msp_api": f"{api.payload[1]}.{api.payload[2]}"}
    else:
        version = {"msp_api": f"unreadable ({api.payload.hex() or 'empty'})"}
    identity = {**version, "max_waypoints": info.max_waypoints, "waypoints": info.count,
                "mission_valid": info.valid}
    stream = session.stream
    identity["address"] = stream.peer if stream is not None else str(session.target)
    return identity


def run_msp_clauses(session: MspSession, clauses: Iterable[Clause], *, on_result: OnResult | None = None,
                    restore: bool = True, guard: InterruptGuard | None = None) -> RunOutcome:
    loop = ClauseLoop(clauses, on_result, guard)
    started = time.monotonic()
    snapshot: list[Waypoint] | None = None
    identity = None

    def dead_after(clause: Clause, result: ClauseResult) -> str | None:
        if result.outcome is Outcome.ERROR and result.detail.startswith("target unresponsive"):
            if session.tester.ask("MSP_API_VERSION") is None:
                return f"the flight controller stopped answering during {clause.id}"
        return None

    with loop.interruptible():
        try:
            try:
                identity = discover(session)
            except TargetUnresponsive as exc:
                loop.never_answered(str(exc))
                return RunOutcome(loop.results, None, {"status": "skipped",
                                                       "detail": "the flight controller never answered"},
                                  time.monotonic() - started, 0.0, unresponsive=str(exc), link=session.link_facts,
                                  link_events=session.link_events())
            if restore:
                loop.phase = "reading the flight controller's mission"
                snapshot = session.tester.stored()
            loop.run(lambda clause: judged_on_time(session, clause, run_one), dead_after)
        except TargetUnresponsive as exc:     # while reading the mission, before any clause
            loop.give_up(f"the flight controller stopped answering: {exc}")
    dead, interrupted, phase = loop.dead, loop.interrupted, loop.phase
    session.tester.exchange = None
    status = _restore(session, snapshot, restore=restore, dead=dead)
    return RunOutcome(loop.results, identity, status, time.monotonic() - started, session.tester.forced_wait,
                      unresponsive=dead, interrupted=interrupted, interrupted_at=phase if interrupted else None,
                      interrupted_by=loop.interrupted_by if interrupted else None,
                      link=session.link_facts, link_events=session.link_events())


def run_one(session: MspSession, clause: Clause) -> ClauseResult:
    fn = MSP_CHECKS.get(clause.id)
    if fn is None:
        return ClauseResult(clause.id, Outcome.ERROR, "no check is registered for this clause")
    t = session.tester
    begin = t.now()
    exchange = t.exchange = Exchange(begin)
    _mark(session, f"clause {clause.id}")
    outcome, detail, caught = call_check(fn, session)
    decided_by = exchange.decided_by if outcome in (Outcome.PASS, Outcome.FAIL) else None
    end = t.now()
    t.exchange = None
    _mark(session, f"clause {clause.id}: {outcome.value}", "info" if outcome is Outcome.PASS else "warning")
    return DecidedResult(clause.id, outcome, detail, round(end - begin, 6), exchange.finish(end),
                         decided_by=decided_by, measured=_measured(*caught))


def _restore(session: MspSession, snapshot: list[Waypoint] | None, *, restore: bool, dead: str | None) -> dict:
    if not restore:
        return {"status": "skipped", "detail": "not asked (--no-restore)"}
    if dead is not None:
        return {"status": "skipped", "detail": "the flight controller stopped answering"}
    if snapshot is None:
        return {"status": "failed", "detail": "could not read the flight controller's mission before the run"}
    t = session.tester
    try:
        now = t.stored()
        if now == snapshot:
            return {"status": "unchanged", "detail": "the flight controller holds the mission it held before the run"}
        if not snapshot:
            return {"status": "skipped", "detail": f"the flight controller held no mission and now holds {len(now)} "
                    "waypoints (not saved): MSP has no command that empties the list (INAV: the CLI's `wp reset`, "
                    "or a reboot)"}
        t.write(snapshot)
        back = t.stored()
    except TargetUnresponsive as exc:
        return {"status": "failed", "detail": f"the flight controller stopped answering while the mission was put back: {exc}"}
    if back == snapshot:
        return {"status": "restored", "detail": f"put back the {len(snapshot)}-waypoint mission it held before the run"}
    return {"status": "failed", "detail": f"wrote back the {len(snapshot)}-waypoint mission it held, and read back "
            f"{len(back)} waypoints that differ"}
