"""Stateful protocol fuzzing: GCS operations, stray messages and link faults against a vehicle.

A Hypothesis `RuleBasedStateMachine` (machine.py) whose rules are what GCSs and links do;
each rule is a JSON step (steps.py) applied to a world (world.py: the target and three
GCSs, in virtual time for in-process targets, over UDP otherwise), and the invariants
(`INVARIANTS`) are checked after every step. `search` finds and shrinks violations into
replayable `Case`s; `replay` re-runs one. With operator control (`Knobs.handover`,
`--operator-control`) GCSs also request, release and hand over control and fall silent, and the
control invariants (`control.CONTROL_INVARIANTS`, `invariants(True)`) are checked too.
"""

from .machine import Knobs
from .search import replay, search
from .steps import INVARIANTS, invariants

__all__ = ["INVARIANTS", "Knobs", "invariants", "replay", "search"]
