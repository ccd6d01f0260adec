"""A finding as a campaign saved it: the case on disk, its capture, what replaying it showed.

`save_unreplayed` is the way every path falls back to when it cannot replay (an interrupt, a
dead target): the case as it is, at once, with the live capture if there is one, written
whole whatever signal comes.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mavconform.reference_impl.interrupts import InterruptGuard

from .case import Case, Violation, save_case

if TYPE_CHECKING:
    from .target_death import RingCapture


@dataclass(frozen=True)
class Finding:
    case: Case
    path: Path                       # the saved case (JSON)
    capture: Path | None             # the MCAP of its replay
    replayed: Violation | None       # what replaying it showed (None: it did not reproduce)
    exchange: list[dict[str, Any]]   # the replay's frames, as report events
    note: str = ""                   # how it was saved when that is not the usual way

    @property
    def reproduced(self) -> bool:
        return (self.replayed is not None and self.case.violation is not None
                and self.replayed.invariant == self.case.violation.invariant)


class SaveInterrupted(KeyboardInterrupt):
    """An interrupt while a finding was minimised or replayed: `finding` is it, saved as it
    was then (not replayed)."""

    def __init__(self, finding: Finding) -> None:
        super().__init__()
        self.finding = finding


INTERRUPTED_NOTE = "saved unminimised and not replayed: the campaign was interrupted"


def save_unreplayed(case: Case, directory: str | Path, ring: RingCapture | None = None, *,
                    note: str) -> Finding:
    """Save the case as it is, with the live capture if there is one, no replay: quick, and
    a further interrupt waits for it, so the files are whole."""
    with InterruptGuard(held=True):
        path = save_case(case, directory)
        mcap = path.with_suffix(".mcap") if ring is not None else None
        exchange = ring.write(mcap) if ring is not None and mcap is not None else []
    return Finding(case, path, mcap, None, exchange, note=note)
