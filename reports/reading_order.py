"""The order every report reads in (HTML, Markdown, the terminal): what a reader acts on first.

1. what fails the run (the gating clauses), red, and only when there is any;
2. the known deviations, each with the expectation that excuses it;
3. whatever else did not pass without failing the run (a SHOULD failure without --strict);
4. the not-applicable and skipped clauses, counted in groups by their reason ("21 clauses:
   the target sent no CONTROL_STATUS ..."), which a writer folds away.

A passing run against a real autopilot has a dozen deviations and twenty-odd clauses that do
not apply to it; listed one by one under a red heading, they read as a failure.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mavconform.reports.run_document import PASS, clause_detail

KNOWN_DEVIATION, NOT_APPLICABLE, SKIPPED = "known-deviation", "not-applicable", "skipped"
GROUPED = (NOT_APPLICABLE, SKIPPED)   # in this order, after everything else


@dataclass(frozen=True)
class Group:
    """Clauses with one outcome for one reason (their detail, measured numbers put back)."""
    outcome: str
    reason: str
    clauses: tuple[dict[str, Any], ...]


@dataclass(frozen=True)
class ReadingOrder:
    failing: list[dict[str, Any]]      # fail the run: gating, whatever their outcome
    deviations: list[dict[str, Any]]   # known deviations (not gating)
    other: list[dict[str, Any]]        # did not pass, do not fail the run, are no deviation
    groups: list[Group]                # not-applicable, then skipped, by reason

    @property
    def listed(self) -> list[dict[str, Any]]:
        """Every clause not passing, in reading order."""
        return self.failing + self.deviations + self.other + [c for g in self.groups for c in g.clauses]


def reading_order(doc: dict[str, Any]) -> ReadingOrder:
    """The document's clauses that did not pass (or gate), sorted as the module says; each
    part keeps the run's order, and groups come in the order of their first clause."""
    clauses = doc["clauses"]
    failing = [c for c in clauses if c["gating"]]
    rest = [c for c in clauses if not c["gating"] and c["outcome"] != PASS]
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for outcome in GROUPED:
        for c in rest:
            if c["outcome"] == outcome:
                groups.setdefault((outcome, clause_detail(doc, c) or "no reason given"), []).append(c)
    return ReadingOrder(
        failing=failing,
        deviations=[c for c in rest if c["outcome"] == KNOWN_DEVIATION],
        other=[c for c in rest if c["outcome"] not in (KNOWN_DEVIATION, *GROUPED)],
        groups=[Group(outcome, reason, tuple(members)) for (outcome, reason), members in groups.items()])


def group_title(group: Group) -> str:
    """"21 clauses not applicable: the target sent no CONTROL_STATUS ..." (one line's worth)."""
    n = len(group.clauses)
    said = "not applicable" if group.outcome == NOT_APPLICABLE else group.outcome
    return f"{n} clause{'' if n == 1 else 's'} {said}: {group.reason}"
