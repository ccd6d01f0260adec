"""The conformance suite as pytest tests: `pytest --pyargs mavconform.conformance --mavlink-target URI`.

Registered as a pytest11 entry point, so it loads in every pytest run of an environment
where mavconform is installed; it only adds options until `--mavlink-target` is given, and
imports the suite lazily. Each clause is one test named by its id; pass/fail map to pytest's,
not-applicable and skipped to skips, known deviations to xfail, and an undecided clause
(target unresponsive, precondition) to a failure saying so. `--mavlink-report-dir` writes
the same reports as `mavconform run`. A usage mistake is pytest's usage error (exit 4),
one line naming the option, as `mavconform run` names it.
"""

from __future__ import annotations

from typing import Any

import pytest

_STATE: dict[str, Any] = {}


def pytest_addoption(parser: pytest.Parser) -> None:
    g = parser.getgroup("mavconform", "MAVLink mission conformance (mavconform)")
    g.addoption("--mavlink-target", metavar="URI",
                help="run the conformance clauses against URI (builtin:PROFILE: spec, px4, ardupilot, ... "
                     "(`mavconform profiles`); mutant:NAME, udp:HOST:PORT, udpin:[HOST:]PORT, "
                     "tcp:HOST:PORT, tcpin:[HOST:]PORT or serial:DEVICE[:BAUD])")
    g.addoption("--mavlink-clauses", default="*", metavar="GLOB", help="clause id globs (default all)")
    g.addoption("--mavlink-strict", action="store_true", help="SHOULD failures fail too")
    g.addoption("--mavlink-expect", metavar="NAME|FILE", help="expectations file of known deviations")
    g.addoption("--mavlink-profile", metavar="NAME|FILE",
                help="what an external target is when its HEARTBEAT cannot say (e.g. inav)")
    g.addoption("--mavlink-time-scale", type=float, default=1.0, metavar="X", help="stretch waits by X")
    g.addoption("--mavlink-allow-flight", action="store_true", help="let progress clauses fly")
    g.addoption("--mavlink-report-dir", metavar="DIR", help="write run.json/junit/md/html/mcap here")
    g.addoption("--mavlink-handover-scenario", metavar="FILE",
                help="the handover scenario the target's mission computer runs (HO.SEQ clauses; default: "
                     "the shipped conformance scenario)")


def pytest_configure(config: pytest.Config) -> None:
    if config.getoption("--mavlink-target", default=None):
        _prepared(config)   # check every option before collection: a mistake is a usage error
        _catch_sigterm()


def _catch_sigterm() -> None:
    """SIGTERM (CI cancel, `timeout`) as Ctrl-C: pytest then stops and tears the session
    down, so the target's plans are put back and the reports written, marked interrupted."""
    import signal
    import threading
    if threading.current_thread() is not threading.main_thread():
        return

    def interrupt(signum: int, frame: object) -> None:
        _STATE["signal"] = "SIGTERM"
        raise KeyboardInterrupt
    _STATE["previous_sigterm"] = signal.signal(signal.SIGTERM, interrupt)


def pytest_unconfigure(config: pytest.Config) -> None:
    if "previous_sigterm" in _STATE:
        import signal
        signal.signal(signal.SIGTERM, _STATE.pop("previous_sigterm"))


@pytest.hookimpl(tryfirst=True)
def pytest_keyboard_interrupt(excinfo: pytest.ExceptionInfo) -> None:
    if "prepared" in _STATE:
        _STATE["interrupted_by"] = _STATE.get("signal", "SIGINT")
        _give_every_entry_a_line(excinfo)


def _give_every_entry_a_line(excinfo: pytest.ExceptionInfo) -> None:
    """An interrupt lands between any two bytecodes; on CPython 3.11 some have no line
    number, so a traceback entry's tb_lineno is None and pytest's terminal reporter, which
    subtracts 1 from it, dies with a TypeError instead of reporting the interrupt (exit 1,
    not 2). Runs before that reporter: each such entry gets its function's first line."""
    exc: BaseException | None = excinfo.value
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if exc.__traceback__ is not None:
            exc.__traceback__ = _numbered(exc.__traceback__)
        exc = exc.__cause__ or exc.__context__
    excinfo.traceback = type(excinfo.traceback)(_numbered(excinfo.tb))


def _numbered(tb):
    import types
    entries = []
    while tb is not None and len(entries) < 10_000:
        entries.append(tb)
        tb = tb.tb_next
    rebuilt = None
    for entry in reversed(entries):
        line = entry.tb_lineno if entry.tb_lineno is not None else entry.tb_frame.f_code.co_firstlineno
        rebuilt = types.TracebackType(rebuilt, entry.tb_frame, entry.tb_lasti, line)
    return rebuilt


def _prepared(config: pytest.Config):
    if "prepared" not in _STATE:
        from mavconform.reference_impl.errors import UsageError

        from . import document, suite
        from .target_uri import parse_target
        try:   # first, alone, so its line names the option
            parse_target(config.getoption("--mavlink-target"))
        except UsageError as exc:
            raise pytest.UsageError(f"--mavlink-target: {exc}") from None
        if config.getoption("--mavlink-handover-scenario"):
            from .target_uri import load_handover_scenario
            try:
                load_handover_scenario(config.getoption("--mavlink-handover-scenario"),
                                       option="--mavlink-handover-scenario")
            except UsageError as exc:
                raise pytest.UsageError(str(exc)) from None
        options = document.RunOptions(
            target=config.getoption("--mavlink-target"), clauses=config.getoption("--mavlink-clauses"),
            strict=config.getoption("--mavlink-strict"), time_scale=config.getoption("--mavlink-time-scale"),
            expectations=config.getoption("--mavlink-expect"),
            handover_scenario=config.getoption("--mavlink-handover-scenario"),
            profile=config.getoption("--mavlink-profile"))
        try:
            _STATE["prepared"] = suite.prepare(options, report_dir=config.getoption("--mavlink-report-dir"))
        except UsageError as exc:
            raise pytest.UsageError(str(exc)) from None
    return _STATE["prepared"]


NO_TARGET = "no-target"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """A CI job that collects the conformance suite but forgot --mavlink-target must not be
    green with "1 skipped": it is a usage error (exit 4), said in one line."""
    if not config.getoption("--mavlink-target") and any(
            getattr(getattr(item, "callspec", None), "id", None) == NO_TARGET for item in items):
        raise pytest.UsageError("the conformance suite needs --mavlink-target URI "
                                "(e.g. builtin:spec, udp:HOST:PORT or udpin:PORT)")


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    if "mavlink_clause" not in metafunc.fixturenames:
        return
    if not metafunc.config.getoption("--mavlink-target"):
        metafunc.parametrize("mavlink_clause", [None], ids=[NO_TARGET])   # refused once collected
        return
    clauses = _prepared(metafunc.config).clauses
    metafunc.parametrize("mavlink_clause", clauses, ids=[c.id for c in clauses])


@pytest.fixture(scope="session")
def mavlink_session(request: pytest.FixtureRequest):
    """The open target: discovered, its plans read; restored and reported at the end."""
    import datetime as dt

    from .outcome import TargetUnresponsive
    from .runner import _restore, _snapshot
    from .session import Session
    from mavconform.reference_impl.net.capture import McapCapture
    from mavconform.reference_impl.errors import UsageError
    p = _prepared(request.config)
    capture = McapCapture(p.report_dir / "run.mcap") if p.report_dir is not None else None
    try:
        session = Session(p.uri, scale=p.options.time_scale, capture=capture,
                          allow_flight=True if request.config.getoption("--mavlink-allow-flight") else None)
    except UsageError as exc:   # e.g. udpin: on an address we cannot bind
        if capture is not None:
            capture.close()
        pytest.exit(f"--mavlink-target: {exc}", returncode=pytest.ExitCode.USAGE_ERROR)
    started = dt.datetime.now(dt.timezone.utc)
    results: list = []
    _STATE["results"] = results
    try:
        try:
            p.expected.identify(session.discover())
        except TargetUnresponsive as exc:
            _STATE["dead"] = f"target unresponsive: {exc}"
            from .outcome import ClauseResult, Outcome
            results += [ClauseResult(c.id, Outcome.ERROR, f"target unresponsive: {exc}") for c in p.clauses]
            if p.report_dir is not None:
                _write(p, session, results, {"status": "skipped", "detail": "the target never answered"},
                       started, capture)
            pytest.fail(f"target unresponsive: {exc}", pytrace=False)
        snapshot = _snapshot(session)
        from . import readiness   # as `mavconform run` does: streams, forms, a target done booting
        session.identity["prepared"] = readiness.prepare(session.t).line()
        yield session
        from .runner import run_guard
        with run_guard() as guard:   # a second signal must not cut the restore short
            guard.hold()
            restore = _restore(session, snapshot) if snapshot is not None else {
                "status": "skipped", "detail": "could not read the plans before the run"}
            if p.report_dir is not None:
                _write(p, session, results, restore, started, capture)
    finally:
        if capture is not None:
            capture.close()
        session.close()


def _write(p, session, results, restore, started, capture) -> None:
    import datetime as dt

    from mavconform.reports.write import write_reports

    from . import document, gating
    from .outcome import ClauseResult, Outcome
    from .runner import RunOutcome
    interrupted_by = _STATE.get("interrupted_by")
    decided = {r.clause_id for r in results}
    not_run = [c.id for c in p.clauses if c.id not in decided]
    if interrupted_by is not None:   # the clauses pytest never reached
        results = results + [ClauseResult(cid, Outcome.SKIPPED, "not run: interrupted") for cid in not_run]
    run = RunOutcome(results, session.identity, restore,
                     (dt.datetime.now(dt.timezone.utc) - started).total_seconds(),
                     sum(t.forced_wait for t in session.testers()),
                     interrupted=interrupted_by is not None,
                     interrupted_at=(not_run[0] if not_run else "restore") if interrupted_by else None,
                     interrupted_by=interrupted_by, receive_queue=session.receive_facts(),
                     link=session.link_facts, link_events=session.link_events(),
                     flights=list(session.flights))
    gating.apply_expectations(run.results, p.expected)
    flags, summary = gating.gate(run.results, strict=p.options.strict, baseline=p.baseline)
    doc = document.build(p.options, run, started=started, gating_flags=flags, gating=summary,
                         capture="run.mcap" if capture is not None else None)
    write_reports(doc, p.report_dir)


def decide(session, clause, expected: dict, strict: bool) -> Any:
    """Run one clause and turn its outcome into pytest's vocabulary."""
    from .clause import Level
    from .gating import apply_expectations
    from .host_lag import judged_on_time
    from .outcome import ClauseResult, Outcome
    from .runner import _still_alive, run_one
    dead = _STATE.get("dead")
    if dead is not None:   # as the CLI does: a dead target is not waited on clause after clause
        _STATE.setdefault("results", []).append(ClauseResult(clause.id, Outcome.ERROR, f"not run: {dead}"))
        pytest.fail(f"error: {clause.id} not run: {dead}", pytrace=False)
    result = judged_on_time(session, clause, run_one)   # as the CLI does: a host that lagged gets a second try
    if result.outcome is Outcome.ERROR and result.detail.startswith("target unresponsive") \
            and not _still_alive(session):
        _STATE["dead"] = f"the target stopped answering during {clause.id}"
    apply_expectations([result], expected)
    _STATE.setdefault("results", []).append(result)
    text = f"{clause.id} ({clause.level.value}) {clause.title}: {result.detail}".rstrip(": ")
    if result.outcome is Outcome.PASS:
        return result
    if result.outcome is Outcome.KNOWN_DEVIATION:
        pytest.xfail(f"known deviation ({result.expectation}): {result.detail}")
    if result.outcome in (Outcome.NOT_APPLICABLE, Outcome.SKIPPED):
        pytest.skip(f"{result.outcome.value}: {result.detail}")
    if result.outcome is Outcome.FAIL and clause.level is Level.SHOULD and not strict:
        pytest.skip(f"SHOULD clause failed (not gating without --mavlink-strict): {text}")
    pytest.fail(f"{result.outcome.value}: {text}\n  requirement: {clause.requirement} [{clause.source}]",
                pytrace=False)
