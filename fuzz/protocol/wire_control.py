"""Operator control as the protocol fuzzer sees it over the wire (UDP targets): which GCSs may
own control, from the answers our GCSs got and the CONTROL_STATUS the target sends, since
nothing else can be seen there (fuzz/protocol/control.py: the rules, and the in-process
watch that sees the vehicle's own state)."""

from __future__ import annotations

import math
from typing import Callable, Iterable

from mavconform.reference_impl.handover.control_results import ControlOperation, ControlOutcome, ControlResult


class WireControl:
    """Which GCSs may own control, from the answers our GCSs got and the CONTROL_STATUS the
    target sends (UDP targets: nothing else can be seen). `possible` is None until the first
    CONTROL_STATUS is heard."""

    def __init__(self, name: Callable[[int], str] = lambda s: f"GCS {s}") -> None:
        self.name = name
        self.possible: set[int] | None = None
        self.because = "the last CONTROL_STATUS"
        self.answered_at = -math.inf       # the time of the last answer that moved `possible`
        self.by_answer = False             # `possible` was last set by an ACCEPTED answer

    def observed(self, gcs_main: int) -> None:
        self.possible = {gcs_main}
        self.because, self.by_answer = "the last CONTROL_STATUS", False

    def widen(self, sysids: Iterable[int], because: str) -> None:
        """Control may have gone to one of `sysids` (0: nobody), e.g. an unanswered request,
        or an owner that may have been dropped while its HEARTBEATs did not get through."""
        if self.possible is not None and not set(sysids) <= self.possible:
            self.possible |= set(sysids)
            self.because = f"{self.because}, then {because}"

    def result(self, sysid: int, result: ControlResult, now: float) -> None:
        """Fold in one control operation's result (ours, user or answer)."""
        op, outcome = result.operation, result.outcome
        releases = op in (ControlOperation.RELEASE, ControlOperation.ANSWER_RELEASE)
        who = self.name(sysid)
        if outcome is ControlOutcome.GRANTED and not releases:
            self.possible, self.by_answer = {sysid}, True
            self.because = f"the ACCEPTED answer to {who}'s {op.value}"
            self.answered_at = now
        elif outcome is ControlOutcome.RELEASED:
            self.possible = ((self.possible or set()) - {sysid}) | {0}
            self.by_answer = True
            self.because = f"the ACCEPTED answer to {who}'s {op.value}"
            self.answered_at = now
        elif outcome is ControlOutcome.TIMEOUT:
            self.widen([0] if releases else [sysid], f"{who}'s unanswered {op.value}")
        # refused, not in control, rejected: nothing changed hands

    def judge(self, gcs_main: int, secondary: Iterable[int]) -> tuple[str, str] | None:
        """(invariant, detail) if the CONTROL_STATUS heard cannot be, else None; then it is
        what the target holds."""
        others = [s for s in secondary if s]
        if others:
            return "two-owners", (f"CONTROL_STATUS names GCS {gcs_main} as gcs_main and {others} as "
                                  "secondary owners: more than one GCS in control")
        possible = self.possible
        if possible is not None and gcs_main not in possible:
            heard = self.name(gcs_main) if gcs_main else "nobody"
            could = " or ".join(sorted(self.name(s) if s else "nobody" for s in possible))
            if self.by_answer:   # over the wire, which of the two is wrong cannot be told
                return "control-status-lies", (
                    f"CONTROL_STATUS says {heard} is in control, but after {self.because} only {could} "
                    "can be: the status or the answer is wrong")
            return "owner-without-request", (
                f"CONTROL_STATUS says {heard} is in control, but after {self.because} only {could} can "
                "be: no request, release or owner loss explains the change")
        self.observed(gcs_main)
        return None

    def may_write(self, sysid: int) -> bool:
        """Could `sysid` be allowed to write now (it may own control, or nobody may, and the
        target may be open while nobody is in control)?"""
        return self.possible is None or sysid in self.possible or 0 in self.possible
