"""The atomicity oracle: which stored plans the vehicle may hold, given what it answered.

For each plan type we keep the set of plans the vehicle may be storing now. A write (an
upload, a clear, a stray MISSION_COUNT 0 or MISSION_CLEAR_ALL) that the vehicle confirmed
replaces the set; one whose outcome is unknown (the two-generals case: the last item went
out, the ACK never came back) adds its plan to it; one that definitely failed leaves it
alone (an upload refused before a single item went out, e.g. DENIED by the operator-control
filter to a GCS not in control, changed nothing even on a non-atomic vehicle: `untouched`).
Writes that overlap in time (a second GCS, a stray message mid-transfer) may have
landed in any order, so a group of them is folded in at once. Whenever the vehicle's
plan is observed (in-process: read; over the wire: downloaded), it must be one of the set,
and the set shrinks to it. Plans are compared in the target's stored form (`StoredForm`:
home in mission slot 0, compact item storage, frame synonyms, reserved params, the
`current` flag), so a vehicle that keeps a plan the way its profile documents is never
taken for one that invented a plan. The set holds plans as stored: a written plan enters
it through the storage form, an observed one as it was read.

A non-atomic vehicle (ArduPilot-like, VARIANTS A2) may hold any mix of old and new after
an upload that did not complete: there the set becomes "unknown" (None) until the next
confirmed write or observation, and only confirmed outcomes are judged.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Sequence

from mavconform.conformance.harness.stored_form import SPEC_FORM, StoredForm
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionItem, MissionType

Plan = tuple[MissionItem, ...]


@dataclass(frozen=True)
class Write:
    """One attempt to change the stored plans of `types` to one of `plans` (variants of
    the same plan, e.g. as sent with int and with float x/y)."""

    types: tuple[MissionType, ...]
    plans: tuple[Plan, ...]
    confirmed: bool        # the vehicle said it is done (ACCEPTED)
    maybe: bool            # not confirmed, and it may have been applied
    untouched: bool = False   # refused before any item went out: nothing of it applied, anywhere


class Versions:
    def __init__(self, initial: dict[MissionType, Plan | None], *, atomic: bool = True,
                 form: StoredForm = SPEC_FORM) -> None:
        self.atomic = atomic
        self.form = form
        self.possible: dict[MissionType, list[Plan] | None] = {
            t: (None if initial.get(t) is None else [initial[t]]) for t in PLAN_TYPES}

    def allows(self, t: MissionType, plan: Sequence[MissionItem]) -> bool:
        known = self.possible[t]
        return known is None or any(self.form.same(plan, p, want_stored=True) for p in known)

    def allows_count(self, t: MissionType, count: int) -> bool:
        """Could the vehicle hold a plan of `count` items (the MISSION_COUNT a download
        starts with)? Judged only where a count maps one to one onto the stored plan (no
        home item in slot 0, items stored as sent)."""
        known = self.possible[t]
        if known is None or self.form.home_slot_of(t) or self.form.storage != "exact":
            return True
        return any(len(p) == count for p in known)

    def observe(self, t: MissionType, plan: Sequence[MissionItem]) -> None:
        """The vehicle holds `plan` now (call `allows` first to judge it)."""
        self.possible[t] = [tuple(plan)]

    def apply(self, writes: Iterable[Write]) -> None:
        """Fold in a group of writes that may have been applied in any order."""
        by_type: dict[MissionType, list[Write]] = {}
        for w in writes:
            for t in w.types:
                by_type.setdefault(t, []).append(w)
        stored = self.form.stored_plan
        for t, group in by_type.items():
            confirmed = [stored(p) for w in group if w.confirmed for p in w.plans]
            maybe = [stored(p) for w in group if w.maybe for p in w.plans]
            incomplete = any(not w.confirmed and not w.untouched for w in group)
            if not self.atomic and incomplete:
                # an unfinished upload may have left a mix; a confirmed one in the same
                # group may have landed before it
                self.possible[t] = None
                continue
            if confirmed:
                self.possible[t] = self._unique(confirmed + maybe)
            elif maybe and self.possible[t] is not None:
                self.possible[t] = self._unique(self.possible[t] + maybe)

    def _unique(self, plans: list[Plan]) -> list[Plan]:
        out: list[Plan] = []
        for p in plans:
            if not any(self.form.same(p, q, want_stored=True) for q in out):
                out.append(p)
        return out

    def describe(self, t: MissionType) -> str:
        known = self.possible[t]
        if known is None:
            return "any plan"
        return " or ".join(f"{len(p)} items" + (f" (id {_digest(p)})" if p else "") for p in known)


def describe_plan(plan: Sequence[MissionItem]) -> str:
    return f"{len(plan)} items" + (f" (id {_digest(tuple(plan))})" if plan else "")


def _digest(plan: Plan) -> str:
    from mavconform.reference_impl.mission.store import plan_digest
    return f"0x{plan_digest(plan):08x}"
