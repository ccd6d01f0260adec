"""Uploading a plan file's parts (mission, fence, rally) as one unit, as far as the protocol lets.

Each plan type is its own upload and the protocol has no transaction across them, so a vehicle
may take the mission and refuse the fence. By default the parts go in order and the first that
fails stops the rest: a refused mission must not leave the vehicle flying its old mission inside
the new fence. Nothing is rolled back (the GCS holds no copy of what the vehicle had), so the
report says which parts went, which did not, and which earlier plans they replaced.
`keep_going` tries every part, as a plan upload always did before.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

from .constants import MissionState
from .items import PLAN_TYPES, MissionItem, MissionType
from .results import OperationResult

Upload = Callable[[MissionType, Sequence[MissionItem]], OperationResult]
NO_MISSION_TOTAL = 0xFFFF   # MISSION_CURRENT.total: "UINT16_MAX if no mission is present"


@dataclass(frozen=True)
class PlanUpload:
    results: tuple[OperationResult, ...]          # one per part tried, in order
    not_sent: tuple[MissionType, ...] = ()        # parts left out after a failure
    stopped: bool = False                         # a failure ended it (not keep_going)
    # True: the vehicle held a plan of that type before; False: it held none; None: unknown
    previous: Mapping[MissionType, bool | None] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return not self.stopped and all(r.ok for r in self.results)

    @property
    def uploaded(self) -> tuple[MissionType, ...]:
        return tuple(r.mission_type for r in self.results if r.ok)

    def report(self) -> list[str]:
        """What a user needs to know when not every part went; nothing when all did."""
        if self.ok:
            return []
        failed = [r for r in self.results if not r.ok]
        head = (f"plan upload stopped at the {failed[0].mission_type.label}" if self.stopped
                else "plan upload incomplete")
        lines = [f"{head}: uploaded {_labels(self.uploaded)}; not uploaded "
                 + ", ".join([*(f"{r.mission_type.label} ({r.outcome.value})" for r in failed),
                              *(f"{t.label} (not sent)" for t in self.not_sent)])]
        lines += [f"the vehicle may have stored the {r.mission_type.label} anyway (outcome unknown)"
                  for r in failed if r.outcome_unknown]
        for t in self.uploaded:
            before = self.previous.get(t)
            if before is None:
                lines.append(f"the {t.label} replaced whatever {t.label} the vehicle held before "
                             "(not rolled back)")
            elif before:
                lines.append(f"the {t.label} replaced the vehicle's previous {t.label} (not rolled back)")
        return lines


def upload_plan(parts: Sequence[tuple[MissionType, Sequence[MissionItem]]], upload: Upload, *,
                keep_going: bool = False,
                previous: Mapping[MissionType, bool | None] | None = None) -> PlanUpload:
    """Upload `parts` in order with `upload`; stop at the first that fails unless `keep_going`."""
    results: list[OperationResult] = []
    for i, (mission_type, items) in enumerate(parts):
        result = upload(mission_type, items)
        results.append(result)
        if not result.ok and not keep_going:
            return PlanUpload(tuple(results), tuple(t for t, _ in parts[i + 1:]), True, dict(previous or {}))
    return PlanUpload(tuple(results), (), False, dict(previous or {}))


def previous_plans(received: Sequence[Any]) -> dict[MissionType, bool | None]:
    """Which plans the vehicle held, from the last MISSION_CURRENT among `received` (before the
    upload): its plan ids say so when the vehicle reports ids (0 = none; all 0 may also mean
    no ids), and its total / mission_state say so for the mission. Unknown without one."""
    current = next((msg for msg in reversed(received) if msg.get_type() == "MISSION_CURRENT"), None)
    if current is None:
        return {t: None for t in PLAN_TYPES}
    ids = {MissionType.MISSION: getattr(current, "mission_id", 0),
           MissionType.FENCE: getattr(current, "fence_id", 0),
           MissionType.RALLY: getattr(current, "rally_points_id", 0)}
    reports_ids = any(ids.values())
    out: dict[MissionType, bool | None] = {t: (bool(ids[t]) if reports_ids else None) for t in PLAN_TYPES}
    if current.mission_state == MissionState.NO_MISSION or current.total == NO_MISSION_TOTAL:
        out[MissionType.MISSION] = False
    elif current.total:
        out[MissionType.MISSION] = True
    return out


def _labels(types: Sequence[MissionType]) -> str:
    return ", ".join(t.label for t in types) or "nothing"
