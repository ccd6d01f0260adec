"""The protocol fuzzer as a Hypothesis `RuleBasedStateMachine`.

Rules are what a GCS (or a link) does: upload, download, clear, set the current item,
cancel mid-way, let a second GCS start a transfer, send stray messages, change the link's
faults, wait. Each rule draws one step dict and hands it to the `Runner`, which records
nothing Hypothesis does not also know: the machine keeps the list of steps it ran, so a
failure carries the exact program that `replay` re-runs. Invariants are checked after
every rule (and by `replay` after every step) through the same `Runner.check`.
"""

from __future__ import annotations

import time

from dataclasses import dataclass
from typing import Any, Callable

from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from fuzz import strategies as fs

from ..case import Violation
from .steps import Runner


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


class Finding(AssertionError):
    """A broken invariant, with the program that broke it. One subclass per invariant, so
    Hypothesis keeps (and shrinks) distinct invariants as distinct bugs."""

    def __init__(self, violation: Violation, steps: list[dict[str, Any]], seed: int) -> None:
        super().__init__(str(violation))
        self.violation, self.steps, self.seed = violation, list(steps), seed


_FINDING_TYPES: dict[str, type[Finding]] = {}


def finding_type(invariant: str) -> type[Finding]:
    cls = _FINDING_TYPES.get(invariant)
    if cls is None:
        name = "Broke_" + "".join(ch if ch.isalnum() else "_" for ch in invariant)
        cls = _FINDING_TYPES[invariant] = type(name, (Finding,), {})
    return cls


def machine_class(knobs: Knobs, *, on_example: Callable[[int], None] | None = None,
                  on_finding: Callable[[Finding], None] | None = None,
                  stop_at: float | None = None) -> type[RuleBasedStateMachine]:
    """A machine class for one campaign (strategies depend on the knobs). Past `stop_at`
    (time.monotonic) the rules do nothing, so an example running when a wall-time budget
    ends stops within one step: over UDP one example can take longer than the budget."""
    n = knobs.max_items
    after = min(4.0, knobs.max_wait)

    def _spent() -> bool:
        return stop_at is not None and time.monotonic() >= stop_at

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
                self.runner = Runner(knobs.target, seed, atomic=knobs.atomic)

        def _do(self, step: dict[str, Any]) -> None:
            if _spent() or self.runner is None:
                return
            self.steps.append(step)
            self._raise(self.runner.apply(step))

        def _raise(self, violation: Violation | None) -> None:
            if violation is not None:
                found = finding_type(violation.invariant)(violation, self.steps, self.seed)
                if on_finding is not None:
                    on_finding(found)
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
            @rule(step=fs.faults_step())
            def link_faults(self, step: dict[str, Any]) -> None:
                self._do(step)

        @invariant()
        def vehicle_keeps_the_protocol_invariants(self) -> None:
            if self.runner is not None and self.steps and not _spent():
                self._raise(self.runner.check())

        def teardown(self) -> None:
            if self.runner is not None:
                self.runner.close()
            if on_example is not None and self.runner is not None:   # an empty one (past the budget) is none
                on_example(len(self.steps))

    return ProtocolMachine
