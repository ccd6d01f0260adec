"""`search` and `replay` for the protocol mode (the contract in fuzz/__init__ users rely on).

Seeding: Hypothesis draws from a `Random` seeded by the campaign seed (and the chunk
number), so the same seed and `max_examples` run the same examples, finding for finding.
The example database, when given, is keyed by the target and the knobs, not the seed, so
an example that failed in one shard is tried first by every later run on that target.

Wall-time budget: Hypothesis has none, and an exception thrown out of a running test
confuses its shrinker, so a budgeted search runs in chunks (each a complete Hypothesis run
of a few examples, seeded from the campaign seed and the chunk number) and draws no new
chunk once the budget is spent. A finding ends the search: its chunk has shrunk it.

UDP targets: one connection (socket, discovered target, HEARTBEAT watch) serves the whole
campaign, and findings reach the search through the `CampaignState`, not as exceptions
(machine.py says why). A target that never says HEARTBEAT raises `TargetUnresponsive`; an
exception of our own raises `ToolError` with the steps that led to it.

Operator control (`Knobs.handover`, `--operator-control`): the case records it (`found_by.handover:
true`) so `replay` builds the same world; a case without the key replays as before, and a
control step in one is a usage error. Over UDP the target must send CONTROL_STATUS within
CONTROL_STATUS_WAIT, else `UsageError` (exit 2): a vehicle with no system manager has no
operator control to fuzz.

Interrupts: Ctrl-C (or SIGTERM, made one by the CLI) raises `SearchInterrupted` with the
findings seen so far: Hypothesis lets a KeyboardInterrupt through at once, even while it
shrinks, so every failing example is noted as it happens and the smallest per invariant
is handed over, shrunk as far as Hypothesis got.
"""

from __future__ import annotations

import hashlib
import time
from typing import Any, Callable

from hypothesis import HealthCheck, Phase, Verbosity, settings
from hypothesis.database import ExampleDatabase
from hypothesis.stateful import get_state_machine_test

from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.sim import CaptureHook, stable_seed

from ..case import LINK_LATENCY, Case, Violation, case_latency
from ..outcomes import SearchInterrupted, ToolError, caused_by_interrupt, raised_while_handling
from ..seeded import seeded_hypothesis
from .connection import TargetConnection
from .machine import CampaignOver, CampaignState, Finding, Knobs, machine_class
from .steps import Runner

MODE = "protocol"
DEFAULT_EXAMPLES = 100
FIRST_CHUNK = 8             # examples in the first chunk of a budgeted search (in-process)
FIRST_CHUNK_UDP = 1         # ... over UDP, where one example can take half a minute
MAX_CHUNK = 500
_OPS = {"upload": ("type", "items"), "download": ("type",), "clear": ("type",),
        "set_current": ("seq",), "cancel": ("of", "after"), "second_gcs": ("first", "second", "after"),
        "stray": ("messages", "after"), "faults": (), "wait": ("seconds",),
        "control": ("gcs", "action"), "gcs_loss": ("gcs", "seconds")}
_HANDOVER_OPS = ("control", "gcs_loss")
CONTROL_STATUS_WAIT = 3.0   # s a UDP target has to send CONTROL_STATUS under --operator-control (as `run`'s HO clauses)


UDP_MAX_WAIT = 2.0          # s: the longest wait step over real sockets (in-process: 20 s of virtual time)
UDP_MAX_BURST = 3.0         # s: the longest link outage over real sockets (in-process: 30 s)


def udp_knobs(target: str) -> Knobs:
    """A campaign's knobs over real sockets, where time is real: waits and link outages
    short enough that a step costs about what the protocol forces, not what a virtual
    clock would skip for free."""
    return Knobs(target=target, max_wait=UDP_MAX_WAIT, max_burst=UDP_MAX_BURST)


MAX_STEP_WAIT = 600.0   # s of virtual time one step of a case may wait (a bound for edited files)


def search(target: str, *, seed: int, max_examples: int | None = None,
           stop_after: float | None = None, database: ExampleDatabase | None = None,
           on_example: Callable[[int], None] | None = None,
           knobs: Knobs | None = None, profile: str | None = None,
           capture: CaptureHook | None = None, handover: bool | None = None,
           on_finding: Callable[[Finding], None] | None = None) -> list[Case]:
    """Run the protocol state machine against `target`; return the shrunk findings.
    `on_finding` is told of each failing example as Hypothesis meets it, before shrinking
    (bench/protocol_fuzz.py --find-planted times how soon the first comes; a KeyboardInterrupt
    from it ends the campaign there, as one from the user does: `SearchInterrupted`).
    `profile` (UDP targets) names the vehicle profile whose rules the oracles apply;
    `capture` sees the live traffic of a UDP campaign (the campaign keeps the last of it);
    `handover` (else the knobs') turns operator control on: the control steps and invariants.
    A UDP target that sends no CONTROL_STATUS has no operator control to fuzz: `UsageError`."""
    from dataclasses import replace
    if knobs is None:
        knobs = Knobs(target=target) if parse_target(target).in_process else udp_knobs(target)
    else:
        knobs = _with_target(knobs, target)
    if profile is not None:
        knobs = replace(knobs, profile=profile)
    if handover is not None:
        knobs = replace(knobs, handover=handover)
    if max_examples is None and stop_after is None:
        max_examples = DEFAULT_EXAMPLES
    deadline = None if stop_after is None else time.monotonic() + stop_after
    uri = parse_target(knobs.target)
    state = CampaignState()
    if not uri.in_process:   # TargetUnresponsive if it never says HEARTBEAT
        state.connection = TargetConnection(uri, seed=seed, capture=capture)
    try:
        if knobs.handover and state.connection is not None:
            _require_control_status(state.connection)
        return _search(knobs, seed, max_examples, deadline, database, on_example, state, on_finding)
    finally:
        if state.connection is not None:
            state.connection.close()


def _search(knobs: Knobs, seed: int, max_examples: int | None, deadline: float | None,
            database: ExampleDatabase | None, on_example: Callable[[int], None] | None,
            state: CampaignState, on_finding: Callable[[Finding], None] | None = None) -> list[Case]:
    done = 0
    chunk = 0
    rate = 0.0   # examples per second so far, to size the next chunk
    seen: dict[str, Finding] = {}   # the smallest failing example per invariant, as it shrinks

    def example_done(units: int) -> None:
        nonlocal done
        done += 1
        if on_example is not None:
            on_example(units)

    def saw(found: Finding) -> None:
        if on_finding is not None:
            on_finding(found)
        old = seen.get(found.violation.invariant)
        if old is None or len(found.steps) < len(old.steps):
            seen[found.violation.invariant] = found

    try:
        while True:
            left = None if max_examples is None else max_examples - done
            if (left is not None and left <= 0) or (deadline is not None and time.monotonic() >= deadline):
                return []
            first = FIRST_CHUNK if parse_target(knobs.target).in_process else FIRST_CHUNK_UDP
            size = left if deadline is None else _chunk_size(rate, deadline - time.monotonic(), left, first)
            t0, before = time.monotonic(), done
            found = _run_chunk(knobs, seed, chunk, size, database, example_done, deadline, state, saw)
            if state.failure is not None:
                raise ToolError(state.failure)
            found = found or state.findings
            rate = (done - before) / max(time.monotonic() - t0, 1e-6)
            if found:
                return [_case(f, knobs, seed, chunk, done) for f in found]
            chunk += 1
    except KeyboardInterrupt:
        # Hypothesis lets an interrupt through at once, shrinking or not: hand the campaign
        # what was seen (over UDP the side channel has it; in-process the smallest so far).
        found = state.findings or list(seen.values())
        raise SearchInterrupted([_case(f, knobs, seed, chunk, done) for f in found],
                                phase="shrinking" if seen and not state.findings else "search") from None


def replay(case: Case, *, capture: CaptureHook | None = None) -> Violation | None:
    """Re-run the case's steps (in virtual time for in-process targets); the first broken
    invariant, or None. `found_by.handover` rebuilds the world with operator control (a case
    saved before the knob existed has none, and replays as it was found)."""
    handover = case_handover(case.found_by)
    for i, step in enumerate(case.steps):
        _check_step(step, f"step {i}", handover)
    profile = case.found_by.get("profile")
    if profile is not None and not isinstance(profile, str):
        raise UsageError(f"found_by.profile: expected a profile name or file, got {profile!r:.40}")
    runner = Runner(case.target, case.seed, capture=capture, atomic=case.found_by.get("atomic"),
                    profile=profile, latency=case_latency(case.found_by), handover=handover)
    if handover and runner.world.connection is not None:
        try:
            _require_control_status(runner.world.connection)
        except BaseException:
            runner.close()
            raise
    mark = getattr(capture, "mark", None)   # a capture that labels where each step starts
    try:
        for i, step in enumerate(case.steps):
            if mark is not None:
                mark(f"step {i}: {step['op']}", clock=runner.world.driver.clock)
            violation = runner.apply(step) or runner.check()
            if violation is not None:
                return violation
        return None
    finally:
        runner.close()


def case_handover(found_by: dict[str, Any]) -> bool:
    """Whether a case was found with operator control on (`found_by.handover`; absent: off)."""
    value = found_by.get("handover", False)
    if not isinstance(value, bool):
        raise UsageError(f"found_by.handover: expected true or false, got {value!r:.40}")
    return value


# --- internals -------------------------------------------------------------------------------

def _require_control_status(connection: TargetConnection) -> None:
    """--operator-control over UDP: the target must be an operator-control system manager, which
    streams CONTROL_STATUS; one that sends none has nothing to fuzz (a usage mistake, exit 2)."""
    since = connection.driver.clock.now() - CONTROL_STATUS_WAIT
    if connection.control_status_after(since, CONTROL_STATUS_WAIT) is None:
        raise UsageError(f"--operator-control: {connection.uri} sent no CONTROL_STATUS in {CONTROL_STATUS_WAIT:g} s: "
                         "it is no operator-control system manager (MAV_CMD_REQUEST_OPERATOR_CONTROL); "
                         "fuzz it without --operator-control")


def _chunk_size(rate: float, time_left: float, left: int | None, first: int = FIRST_CHUNK) -> int:
    """Half the remaining budget's worth of examples at the last rate (a small first chunk)."""
    size = first if rate <= 0 else int(rate * max(time_left, 0.0) / 2)
    size = max(1, min(size, MAX_CHUNK))
    return size if left is None else min(size, left)


def _run_chunk(knobs: Knobs, seed: int, chunk: int, size: int, database: ExampleDatabase | None,
               on_example: Callable[[int], None], stop_at: float | None = None,
               state: CampaignState | None = None,
               on_finding: Callable[[Finding], None] | None = None) -> list[Finding]:
    machine = machine_class(knobs, on_example=on_example, on_finding=on_finding, stop_at=stop_at,
                            state=state)
    test = get_state_machine_test(machine, settings=settings(
        max_examples=size, stateful_step_count=knobs.steps, deadline=None, database=database,
        derandomize=False, suppress_health_check=list(HealthCheck), verbosity=Verbosity.quiet,
        # Over real sockets every try costs seconds and a dead target fails them all: no shrink.
        phases=(Phase.explicit, Phase.reuse, Phase.generate)
        + ((Phase.shrink,) if parse_target(knobs.target).in_process else ()),
        report_multiple_bugs=True, print_blob=False))
    # Database key: the machine and the knobs (seed left out, so shards share findings). A
    # campaign without --operator-control keeps the key it had before that knob existed.
    key = repr(knobs) if knobs.handover else repr(knobs).replace(", handover=False", "")
    test.hypothesis.inner_test._hypothesis_internal_add_digest = hashlib.sha256(
        repr(("mavconform-protocol-fuzz/1", key)).encode()).digest()
    test._hypothesis_internal_use_seed = stable_seed("protocol", seed, chunk)
    try:
        with seeded_hypothesis(virtual_time=parse_target(knobs.target).in_process):
            test()
    except BaseException as exc:   # noqa: BLE001 - sorted below: findings, or re-raised
        if caused_by_interrupt(exc):   # before CampaignOver: it may be what Hypothesis handled
            raise KeyboardInterrupt from exc
        if _ended_by_us(exc):
            return []              # what the campaign found is in its state
        findings, others = _split(exc)
        if any(caused_by_interrupt(o) for o in others):
            raise KeyboardInterrupt from exc
        if others or not findings:
            raise
        return _smallest_per_invariant(findings)
    return []


def _ended_by_us(exc: BaseException | None) -> bool:
    """`CampaignOver`, or what Hypothesis made of it: ending a test case half-way can make
    it report a `FlakyStrategyDefinition` (the same choices drew more before), with ours as
    its context."""
    return raised_while_handling(exc, CampaignOver)


def _split(exc: BaseException) -> tuple[list[Finding], list[BaseException]]:
    if isinstance(exc, Finding):
        return [exc], []
    if isinstance(exc, BaseExceptionGroup):
        findings: list[Finding] = []
        others: list[BaseException] = []
        for inner in exc.exceptions:
            f, o = _split(inner)
            findings += f
            others += o
        return findings, others
    return [], [exc]


def _smallest_per_invariant(findings: list[Finding]) -> list[Finding]:
    best: dict[str, Finding] = {}
    for f in findings:
        old = best.get(f.violation.invariant)
        if old is None or len(f.steps) < len(old.steps):
            best[f.violation.invariant] = f
    return list(best.values())


def _case(found: Finding, knobs: Knobs, seed: int, chunk: int, examples: int) -> Case:
    found_by: dict[str, Any] = {"search_seed": seed, "chunk": chunk, "examples": examples,
                                "max_items": knobs.max_items, "min_items": knobs.min_items,
                                "steps_per_example": knobs.steps, "faults": knobs.faults,
                                "max_wait": knobs.max_wait}
    if knobs.atomic is not None:
        found_by["atomic"] = knobs.atomic
    if knobs.profile is not None:
        found_by["profile"] = knobs.profile
    if knobs.handover:
        found_by["handover"] = True
    if parse_target(knobs.target).in_process:
        found_by["latency"] = LINK_LATENCY
    return Case(MODE, knobs.target, found.seed, tuple(found.steps), found.violation, found_by)


def _with_target(knobs: Knobs, target: str) -> Knobs:
    from dataclasses import replace
    return replace(knobs, target=target)


def _check_step(step: Any, where: str, handover: bool = False) -> None:
    """A saved case is a file a user may have edited: a bad step is a usage error."""
    if not isinstance(step, dict) or step.get("op") not in _OPS:
        raise UsageError(f"{where}: expected an object with op one of {', '.join(_OPS)}, got {step!r:.80}")
    missing = [k for k in _OPS[step["op"]] if k not in step]
    if missing:
        raise UsageError(f"{where}: {step['op']} step lacks {', '.join(missing)}")
    if step["op"] in _HANDOVER_OPS and not handover:
        raise UsageError(f"{where}: a {step['op']} step needs operator control (found_by.handover: true)")
    if step["op"] in _HANDOVER_OPS and step.get("gcs") not in ("a", "b"):
        raise UsageError(f"{where}: gcs must be \"a\" or \"b\", got {step.get('gcs')!r:.40}")
    if step["op"] == "control" and step.get("action") not in ("request", "release", "allow", "disallow"):
        raise UsageError(f"{where}: action must be request, release, allow or disallow, got {step.get('action')!r:.40}")
    for key in ("of", "first", "second", "during"):
        if step.get(key) is not None:
            _check_step(step[key], f"{where}.{key}", handover)
    for key in ("after", "seconds", "wait", "timeout"):
        if key in step:
            value = step[key]
            if (not isinstance(value, (int, float)) or isinstance(value, bool)
                    or not 0 <= value <= MAX_STEP_WAIT):
                raise UsageError(f"{where}: {key} must be a number of seconds in 0..{MAX_STEP_WAIT:g}, "
                                 f"got {value!r:.40}")
