"""The protocol fuzzer as a Hypothesis `RuleBasedStateMachine`.

Rules are what a GCS (or a link) does: upload, download, clear, set the current item,
cancel mid-way, let a second GCS start a transfer, send stray messages, change the link's
faults, wait; with `Knobs.handover` also request, release and hand over operator control,
fall silent for a while, let GCS B operate alone, send stray control commands. Each rule draws one step dict and hands it to the `Runner`, which records
nothing Hypothesis does not also know: the machine keeps the list of steps it ran, so a
failure carries the exact program that `replay` re-runs. Invariants are checked after
every rule (and by `replay` after every step) through the same `Runner.check`.

Over UDP a finding is not raised into Hypothesis: a live target does not repeat itself
when Hypothesis runs the failing example again to report it (it raised
`FlakyStrategyDefinition` against a crashed ArduPilot and the finding was lost). There the
finding goes to the campaign's `CampaignState` and `CampaignOver` ends the run at once. An exception of our own (a `ToolFailure`) is recorded the same way, in
every transport, and never taken for a finding about the target.
"""

from __future__ import annotations

import time

from dataclasses import dataclass, field
from typing import Any, Callable

from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from mavconform.fuzz import control_strategies as cs
from mavconform.fuzz import strategies as fs

from ..case import LINK_LATENCY, Violation
from ..outcomes import DEATH_KINDS, ToolFailure
from .connection import TargetConnection
from .steps import Runner

DEATH_CONTEXT_STEPS = 40   # steps kept before a target's death (this example's and the last one's)


@dataclass(frozen=True)
class Knobs:
    """What a campaign varies besides the seed."""

    target: str = "builtin:spec"
    max_items: int = 20          # largest plan an upload draws
    min_items: int = 0           # smallest (the bench draws exactly-50-item plans)
    steps: int = 10              # rules per example (Hypothesis stateful_step_count)
    faults: bool = True          # draw link-fault steps
    atomic: bool | None = None   # override the target profile's atomicity (None: profile's)
    max_wait: float = 20.0       # longest wait step, in protocol seconds (mid-operation cues: 4 s)
    profile: str | None = None   # UDP targets: the vehicle profile whose rules the oracles use
    max_burst: float = 30.0      # longest total link outage a faults step draws, in seconds
    handover: bool = False       # operator control: control steps, GCS loss, the control invariants


class Finding(AssertionError):
    """A broken invariant, with the program that broke it. One subclass per invariant, so
    Hypothesis keeps (and shrinks) distinct invariants as distinct bugs."""

    def __init__(self, violation: Violation, steps: list[dict[str, Any]], seed: int) -> None:
        super().__init__(str(violation))
        self.violation, self.steps, self.seed = violation, list(steps), seed


@dataclass
class CampaignState:
    """What the examples of one campaign share: the UDP connection (None in-process), and
    what ended the campaign when it is not raised into Hypothesis."""

    connection: TargetConnection | None = None
    findings: list[Finding] = field(default_factory=list)
    failure: ToolFailure | None = None
    previous_steps: list[dict[str, Any]] = field(default_factory=list)

    @property
    def side_channel(self) -> bool:
        return self.connection is not None

    @property
    def stopped(self) -> bool:
        return self.failure is not None or bool(self.findings)


class CampaignOver(BaseException):
    """Ends a UDP campaign's Hypothesis run at once (the budget is spent, or the campaign
    has its finding). A BaseException, so Hypothesis neither takes it for a failure nor
    replays the example: over UDP there is no shrinking to interrupt, and the examples it
    would otherwise still draw and run empty cost up to half a second each."""


_FINDING_TYPES: dict[str, type[Finding]] = {}


def finding_type(invariant: str) -> type[Finding]:
    cls = _FINDING_TYPES.get(invariant)
    if cls is None:
        name = "Broke_" + "".join(ch if ch.isalnum() else "_" for ch in invariant)
        cls = _FINDING_TYPES[invariant] = type(name, (Finding,), {})
    return cls


def machine_class(knobs: Knobs, *, on_example: Callable[[int], None] | None = None,
                  on_finding: Callable[[Finding], None] | None = None,
                  stop_at: float | None = None,
                  state: CampaignState | None = None) -> type[RuleBasedStateMachine]:
    """A machine class for one campaign (strategies depend on the knobs). Past `stop_at`
    (time.monotonic) the rules do nothing, so an example running when a wall-time budget
    ends stops within one step: over UDP one example can take longer than the budget."""
    n = knobs.max_items
    after = min(4.0, knobs.max_wait)
    shared = state if state is not None else CampaignState()

    def _spent() -> bool:
        """Past the budget, or the campaign has what ended it. Over UDP that ends the
        Hypothesis run at once (`CampaignOver`); in-process the example goes on empty, since
        Hypothesis may be shrinking a finding."""
        spent = shared.stopped or (stop_at is not None and time.monotonic() >= stop_at)
        if spent and shared.side_channel:
            raise CampaignOver()
        return spent

    class ProtocolMachine(RuleBasedStateMachine):
        def __init__(self) -> None:
            super().__init__()
            self.runner: Runner | None = None
            self.steps: list[dict[str, Any]] = []
            self.seed = 0

        @initialize(seed=st.integers(0, 2**32 - 1))
        def connect(self, seed: int) -> None:
            self.seed = seed
            if not _spent():   # past the budget the example is empty: no world to open
                self._guarded(lambda: setattr(self, "runner", Runner(
                    knobs.target, seed, atomic=knobs.atomic, connection=shared.connection,
                    profile=knobs.profile, latency=LINK_LATENCY, handover=knobs.handover)))

        def _do(self, step: dict[str, Any]) -> None:
            if _spent() or self.runner is None:
                return
            self.steps.append(step)
            self._raise(self._guarded(lambda: self.runner.apply(step)))

        def _guarded(self, call: Callable[[], Any]) -> Any:
            """Run our code; an exception in it is a tool failure, recorded, never raised
            into Hypothesis (which would shrink our bug as if it were the target's)."""
            try:
                return call()
            except Exception as exc:   # noqa: BLE001 - every exception here is ours
                if shared.failure is None:
                    shared.failure = ToolFailure.from_exception(exc, self.steps, self.seed)
                return None

        def _raise(self, violation: Violation | None) -> None:
            if violation is None:
                return
            steps = self.steps
            if shared.side_channel and violation.invariant in DEATH_KINDS:
                # the target's state carries over between examples: keep the last ones too
                keep = max(0, DEATH_CONTEXT_STEPS - len(steps))
                context = shared.previous_steps[-keep:] if keep else []
                steps = context + steps
                if violation.step is not None:
                    violation = Violation(violation.invariant, violation.detail, violation.step + len(context))
            found = finding_type(violation.invariant)(violation, steps, self.seed)
            if on_finding is not None:
                on_finding(found)
            if shared.side_channel:
                shared.findings.append(found)
                return
            raise found

        @rule(step=fs.upload_op(n, min_items=knobs.min_items))
        def upload(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.upload_op(n, edges=False, min_items=knobs.min_items))
        def upload_a_valid_plan(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.download_op())
        def download(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.clear_op())
        def clear(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.set_current_op())
        def set_current(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.cancel_step(n, after))
        def cancel_midway(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.second_gcs_step(n, after))
        def second_gcs_starts_a_transfer(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.stray_step(n, after))
        def stray_messages(self, step: dict[str, Any]) -> None:
            self._do(step)

        @rule(step=fs.wait_step(knobs.max_wait))
        def wait(self, step: dict[str, Any]) -> None:
            self._do(step)

        if knobs.faults:
            @rule(step=fs.faults_step(max_burst=knobs.max_burst))
            def link_faults(self, step: dict[str, Any]) -> None:
                self._do(step)

        if knobs.handover:
            @rule(step=cs.control_step(max_timeout=knobs.max_wait, actions=("request",)))
            def request_control(self, step: dict[str, Any]) -> None:
                self._do(step)

            @rule(step=cs.control_step(max_timeout=knobs.max_wait, actions=("release", "allow", "disallow")))
            def release_or_hand_over_control(self, step: dict[str, Any]) -> None:
                self._do(step)

            @rule(step=cs.gcs_loss_step(min(12.0, knobs.max_burst), knobs.max_wait))
            def a_gcs_falls_silent(self, step: dict[str, Any]) -> None:
                self._do(step)

            @rule(step=cs.b_operation(n))
            def second_gcs_operates_alone(self, step: dict[str, Any]) -> None:
                self._do(step)

            @rule(step=fs.stray_step(n, after, handover=True))
            def stray_control_commands(self, step: dict[str, Any]) -> None:
                self._do(step)

        @invariant()
        def vehicle_keeps_the_protocol_invariants(self) -> None:
            if self.runner is not None and self.steps and not _spent():
                self._raise(self._guarded(self.runner.check))

        def teardown(self) -> None:
            if self.runner is not None:
                self._guarded(self.runner.close)
                shared.previous_steps = list(self.steps)
            if on_example is not None and self.runner is not None:   # an empty one (past the budget) is none
                on_example(len(self.steps))

    return ProtocolMachine
