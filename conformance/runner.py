"""Run clauses against a target and decide each one.

Between clauses the runner puts the target back to rest: every tester sends
OPERATION_CANCELLED for each plan type (a spec vehicle in idle ignores it; one left
mid-transfer by the last check drops it), and the next check only looks at frames that
arrive after it starts. Before the first clause the runner reads every plan the target
holds; after the last it puts back any that changed, and says whether it could.
A target that falls silent is reported, never waited on: once it has been silent past the
liveness bound, the remaining clauses are marked `error` without being run.

An interrupt (Ctrl-C, or SIGTERM under an `InterruptGuard`) stops the run where it is: the
clause it cut short and every later one are `skipped`, the target is settled and its plans
put back, and the outcome says where the run stopped. Under a guard, a second signal cannot
cut the restore short: it is noted and honoured once the reports are written.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

from mavconform.reference_impl.interrupts import INTERRUPT_SIGNALS, InterruptGuard
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionItem, MissionType

from . import readiness
from .checks import CHECKS
from .clause import Clause
from .clause_loop import ClauseLoop, OnResult
from .harness import procedures
from .harness.exchange import Exchange
from .harness.float_forms import JUDGES_INT_FORMS
from .harness.measured import Measured
from .host_lag import judged_on_time
from .outcome import (ClauseFailed, ClauseResult, NotApplicable, Outcome, PreconditionFailed,
                      Skipped, TargetUnresponsive)
from .session import Session


@dataclass
class RunOutcome:
    results: list[ClauseResult]
    identity: dict | None
    restore: dict
    duration_s: float
    forced_wait_s: float
    unresponsive: str | None = None     # why the target was given up on, if it was
    discovery_s: float = 0.0            # waiting for the first HEARTBEAT (the target's period)
    interrupted: bool = False           # a signal stopped it: the clauses not decided are skipped
    interrupted_at: str | None = None   # the clause (or phase, e.g. "discovery") it stopped in
    interrupted_by: str | None = None   # "SIGINT", "SIGTERM"
    late_signal: str | None = None      # a signal that came while restoring or reporting, held back
    snapshot: dict[str, int] = field(default_factory=dict)
    # our sockets' receive queues (Session.receive_facts): datagrams dropped, buffer granted
    receive_queue: dict[str, int | None] | None = None
    # the link to the target and the timing the suite used (Session.link_facts), and what
    # happened to a stream link during the run (Session.link_events: volatile)
    link: dict | None = None
    link_events: dict | None = None
    # how each flight ended (Session.flights): a vehicle left armed fails the run
    flights: list[dict] = field(default_factory=list)


@dataclass
class DecidedResult(ClauseResult):
    """A clause's result as `run_one` decided it, with the `Measured` texts its detail was
    made from: the run document keeps their numbers apart from the detail's stable text
    (conformance/document.py), even once an expectation has reworded the detail."""
    measured: list[Measured] = field(default_factory=list)
    # host_lag.py: how far behind its clock the tester ran while this was judged, when that
    # was more than the tolerance; and the attempt run again because it did not pass then
    host_lag_s: float | None = None
    first_attempt: dict[str, Any] | None = None


def _measured(*raised: BaseException | str | None) -> list[Measured]:
    """The Measured texts in what a check returned or raised, and in what that wrapped."""
    found: list[Measured] = []
    seen: set[int] = set()
    todo = list(raised)
    while todo:
        item = todo.pop(0)
        if isinstance(item, Measured):
            found.append(item)
        elif isinstance(item, BaseException) and id(item) not in seen:
            seen.add(id(item))
            todo += [*item.args, item.__cause__, item.__context__]
    return found


def _text(exc: BaseException) -> str:
    """The exception's message; a Measured one as it is, so it keeps its stable form."""
    return exc.args[0] if len(exc.args) == 1 and isinstance(exc.args[0], Measured) else str(exc)


RESTORING_NOTE = ("mavconform: putting the target's plans back and writing the reports first; "
                  "stopping after that")


def run_guard(signals: tuple[int, ...] = INTERRUPT_SIGNALS) -> InterruptGuard:
    """The guard of a run (reference_impl/interrupts.py): the first signal stops it at the
    current clause; a later one waits for the restore and the reports, and says so."""
    return InterruptGuard(signals, held_note=RESTORING_NOTE)


def _mark(session: Session, label: str, level: str = "info") -> None:
    """A marker in the run's capture (a Foxglove Log line), at the session clock's time."""
    mark = getattr(session.capture, "mark", None)
    if mark is not None:
        mark(label, clock=session.driver.clock, level=level)


def run_clauses(session: Session, clauses: Iterable[Clause], *, on_result: OnResult | None = None,
                restore: bool = True, guard: InterruptGuard | None = None) -> RunOutcome:
    loop = ClauseLoop(clauses, on_result, guard)
    started = time.monotonic()
    identity: dict | None = None
    discovered = 0.0
    snapshot: dict[MissionType, list[MissionItem]] | None = None
    changed = False            # the run may have changed the target's plans

    def dead_after(clause: Clause, result: ClauseResult) -> str | None:
        if result.outcome is Outcome.ERROR and result.detail.startswith("target unresponsive"):
            if not _still_alive(session):
                return f"the target stopped answering during {clause.id}"
        return None

    with loop.interruptible():   # an interrupt: stop, but still put the target back and report
        try:
            identity = session.discover()
            discovered = time.monotonic() - started
        except TargetUnresponsive as exc:
            loop.never_answered(str(exc))
            return RunOutcome(loop.results, None, {"status": "skipped", "detail": "the target never answered"},
                              time.monotonic() - started, 0.0, unresponsive=str(exc),
                              receive_queue=session.receive_facts(), link=session.link_facts,
                              link_events=session.link_events())
        if restore:
            loop.phase = "reading the target's plans"
            snapshot = _snapshot(session)
        loop.phase, changed = "preparing the target", True
        identity["prepared"] = readiness.prepare(session.t).line()
        loop.run(lambda clause: judged_on_time(session, clause, run_one), dead_after)
    results, phase, dead, interrupted, how = loop.results, loop.phase, loop.dead, loop.interrupted, loop.interrupted_by
    if interrupted and identity is not None:
        _after_interrupt(session)
    if not restore:
        restore_status = {"status": "skipped", "detail": "not asked (--no-restore)"}
    elif dead is not None:
        restore_status = {"status": "skipped", "detail": "target unresponsive"}
    elif not changed:
        restore_status = {"status": "unchanged" if identity is not None else "skipped",
                          "detail": f"interrupted during {phase}, before the run changed anything"}
    elif snapshot is None:
        restore_status = {"status": "failed", "detail": "could not read the target's mission before "
                          "the run, so what the run changed could not be put back"}
    else:
        restore_status = _restore(session, snapshot)
    forced = sum(t.forced_wait for t in session.testers())
    return RunOutcome(results, identity, restore_status, time.monotonic() - started, forced,
                      unresponsive=dead, discovery_s=discovered, interrupted=interrupted,
                      interrupted_at=phase if interrupted else None,
                      interrupted_by=how if interrupted else None,
                      receive_queue=session.receive_facts(), flights=list(session.flights),
                      link=session.link_facts, link_events=session.link_events())


def interrupted_before_start(clauses: Iterable[Clause], how: str | None,
                             on_result: OnResult | None = None) -> RunOutcome:
    """The outcome of a run stopped before its first datagram: every clause skipped."""
    results = []
    by = f" ({how})" if how else ""
    for clause in clauses:
        result = ClauseResult(clause.id, Outcome.SKIPPED,
                              f"not run: the run was interrupted{by} before the target was contacted")
        results.append(result)
        if on_result:
            on_result(clause, result)
    return RunOutcome(results, None, {"status": "skipped", "detail": "interrupted before the target "
                                      "was contacted"}, 0.0, 0.0, interrupted=True,
                      interrupted_at="connecting", interrupted_by=how)


def _after_interrupt(session: Session) -> None:
    """Leave the target idle after a check (or a setup step) that was cut off mid-exchange:
    stop recording into its exchange and cancel whatever it left open, as between clauses."""
    for t in session.testers():
        t.exchange = None
    _settle(session, 0)


def call_check(fn: Callable[[Any], Any], arg: Any) -> tuple[Outcome, Any, list[BaseException | str]]:
    """Run a check and say how its clause came out, with the detail and what it was made from
    (a Measured text keeps its numbers apart, see DecidedResult). Whatever else it raises is
    a bug in the check: ours, never the target's failure."""
    caught: list[BaseException | str] = []
    try:
        outcome, detail = Outcome.PASS, fn(arg) or ""
        caught.append(detail)
    except ClauseFailed as exc:
        outcome, detail = Outcome.FAIL, _text(exc)
        caught.append(exc)
    except NotApplicable as exc:
        outcome, detail = Outcome.NOT_APPLICABLE, _text(exc)
        caught.append(exc)
    except Skipped as exc:
        outcome, detail = Outcome.SKIPPED, _text(exc)
        caught.append(exc)
    except PreconditionFailed as exc:
        outcome, detail = Outcome.ERROR, f"precondition: {exc}"
        caught.append(exc)
    except TargetUnresponsive as exc:
        outcome, detail = Outcome.ERROR, f"target unresponsive: {exc}"
        caught.append(exc)
    except Exception as exc:
        where = traceback.extract_tb(exc.__traceback__)[-1]
        outcome, detail = Outcome.ERROR, (f"internal error in check {fn.__name__}: "
                                          f"{type(exc).__name__}: {exc} ({where.filename}:{where.lineno})")
    return outcome, detail, caught


def run_one(session: Session, clause: Clause) -> ClauseResult:
    fn = CHECKS.get(clause.id)
    if fn is None:
        return ClauseResult(clause.id, Outcome.ERROR, "no check is registered for this clause")
    testers = session.testers()
    exchange = Exchange(session.t.now())
    for t in testers:
        t.mark()
        t.translate = clause.id not in JUDGES_INT_FORMS   # float-only targets (harness/float_forms.py)
    session.t.exchange = exchange
    if session._second is not None:
        session._second.exchange = exchange
    begin = session.t.now()
    began_at = len(session.t.node.inbox)
    session.current_clause = clause.id
    _mark(session, f"clause {clause.id}")
    outcome, detail, caught = call_check(fn, session)
    if caught and isinstance(caught[-1], PreconditionFailed):
        try:
            session.t.check_alive()   # a setup step that got nothing from a dead target
        except TargetUnresponsive as dead:
            detail = f"target unresponsive: {dead}"
            caught.append(dead)
    # the event the check last judged (see Tester); not for a verdict no message decided:
    # a skip, a bug in the check, a crash
    decided_by = exchange.decided_by if outcome is not Outcome.SKIPPED else None
    if outcome is Outcome.ERROR and detail.startswith("internal error"):
        decided_by = None
    crash = session.guard.crash if session.guard is not None else None
    if crash is not None and outcome is not Outcome.PASS and "crashed" not in detail:
        outcome, detail = Outcome.ERROR, f"target unresponsive: the in-process vehicle crashed: {crash}"
        decided_by = None
    end = session.t.now()
    events = exchange.finish(end)
    for t in session.testers():
        t.exchange = None
    _settle(session, began_at)
    _mark(session, f"clause {clause.id}: {outcome.value}", "info" if outcome is Outcome.PASS else "warning")
    return DecidedResult(clause.id, outcome, detail, round(end - begin, 6), events,
                         decided_by=decided_by, measured=_measured(*caught))


SETTLE_QUIET = 0.005   # s without a frame that counts as "the target has finished replying"
SETTLE_ROUNDS = 40
LET_GO_QUIET = 1.5     # s without an item request: the target has let its upload go
LET_GO_MAX = 12.0      # s at most (the longest vehicle-side upload timeout seen: ArduPilot's 8 s)
REQUESTS = ("MISSION_REQUEST", "MISSION_REQUEST_INT")


def _settle(session: Session, clause_began: int) -> None:
    """Leave the target idle for the next clause: cancel whatever may be open, for every
    plan type a tester has used (an invalid one too: a target may have opened a transfer
    for it), then let its last replies arrive (a few ms on loopback), so none is taken for
    the next clause's. If the clause left an upload open (the last transfer message the
    target sent it was an item request), a target that ignores the cancel and goes on
    requesting (ArduPilot, MAVSDK) is waited for, bounded, until it lets the upload go:
    otherwise its requests meet the next clause, which a busy vehicle refuses or drops."""
    for t in session.testers():
        for mt in sorted(set(map(int, PLAN_TYPES)) | t.touched_types):
            t.node.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mt, t.target))
        t.touched_types.clear()
    inbox = session.t.node.inbox
    for _ in range(SETTLE_ROUNDS):   # bounded: at most SETTLE_ROUNDS quiet periods
        seen = len(inbox)
        session.driver.run_until(lambda: len(inbox) > seen, timeout=SETTLE_QUIET * session.scale)
        if len(inbox) == seen:
            break
    if _left_an_upload_open(session, clause_began):
        _await_let_go(session)


def _ours(session: Session) -> set[int]:
    return {t.node.endpoint.system for t in session.testers()}


def _left_an_upload_open(session: Session, since: int) -> bool:
    ours = _ours(session)
    for _, frame in reversed(session.t.node.inbox[since:]):
        name = frame.msg._type
        if (name in REQUESTS or name == "MISSION_ACK") and frame.msg.target_system in ours:
            return name in REQUESTS
    return False


def _requests_since(session: Session, index: int) -> list:
    ours = _ours(session)
    return [f for _, f in session.t.node.inbox[index:]
            if f.msg._type in REQUESTS and f.msg.target_system in ours]


def _await_let_go(session: Session) -> None:
    """Until no item request has come for a while: half as long again as the target's own
    retry interval where it has been measured (MIS.UP.07), LET_GO_QUIET before; at most
    LET_GO_MAX. Each request that still comes gets a cancel of its own."""
    measured = session.cache.get("silent_upload")
    quiet = LET_GO_QUIET
    gaps = measured[0].gaps if measured is not None else []
    if gaps:
        quiet = min(LET_GO_QUIET, 1.5 * gaps[-1] / session.scale)
    inbox = session.t.node.inbox
    clock = session.driver.clock
    opened = clock.now()
    for _ in range(int(LET_GO_MAX / min(quiet, LET_GO_QUIET)) + 2):   # each round: quiet, or a request
        if clock.now() - opened >= LET_GO_MAX * session.scale:
            return
        seen = len(inbox)
        session.driver.run_until(lambda: bool(_requests_since(session, seen)), timeout=quiet * session.scale)
        late = _requests_since(session, seen)
        if not late:
            return
        for frame in late:   # a cancel for each: a vehicle that does honour one stops now
            t = next(t for t in session.testers() if t.node.endpoint.system == frame.msg.target_system)
            t.node.send(m.ack_message(MissionResult.OPERATION_CANCELLED, frame.msg.mission_type, t.target))


def _still_alive(session: Session) -> bool:
    node = session.t.node
    heard = node.last_heard
    session.driver.run_until(lambda: node.last_heard != heard, timeout=2.5 * session.scale)
    return node.last_heard != heard


def _snapshot(session: Session) -> dict[MissionType, list[MissionItem]] | None:
    plans = {}
    for mt in PLAN_TYPES:
        got = procedures.download(session.t, mt)
        if got is None:
            return None if mt is MissionType.MISSION else plans   # types it lacks: not ours to restore
        plans[mt] = got.items
    return plans


def _restore(session: Session, snapshot: dict[MissionType, list[MissionItem]]) -> dict:
    t = session.t
    restored, failed = [], []
    for mt, items in snapshot.items():
        now = procedures.download(t, mt)
        if now is not None and procedures.same_plan(now.items, items, t.form):
            continue
        frame = procedures.upload(t, items, mt) if items else procedures.clear(t, mt)
        ok = frame is not None and frame.msg.type == MissionResult.ACCEPTED
        (restored if ok else failed).append(f"{mt.label} ({len(items)} items)" if items
                                            else f"{mt.label} (emptied again)")
    if failed:
        return {"status": "failed", "detail": "could not put back: " + ", ".join(failed)}
    if restored:
        return {"status": "restored", "detail": "put back what the target held before the run: "
                + ", ".join(restored)}
    return {"status": "unchanged", "detail": "the target holds the plans it held before the run"}
