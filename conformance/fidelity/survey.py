"""Run the fidelity survey against a target: upload each cell, download it, classify it.

Bounded by batching (issue 26): the cells of one plan type and item kind go up in one upload
where the target takes them all; a batch the target refuses is split into one upload per
cell, since a refusal ends an upload and would hide the other cells' fate. A fence's return
point goes alone (a fence holds one). Where the target keeps its home in mission slot 0
(ArduPilot, A1), a placeholder waypoint goes first and is not judged. Each upload and
download is the suite's own bounded procedure (harness/procedures.py): a target that does
not answer leaves its cells `unanswered`, never a hang.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field, replace
from typing import Any, Callable

from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import procedures
from ..harness.exchange import Exchange
from ..harness.tester import Tester
from .cells import FENCE_RETURN, HOME_X, HOME_Y, Cell, numbered
from .classify import classify, fields_of

OnCell = Callable[[dict[str, Any]], None]
RE_READ_AFTER = 1.0     # s before a download that came back short is read again


@dataclass
class Survey:
    cells: list[dict[str, Any]] = field(default_factory=list)
    uploads: int = 0
    exchanges: list[list[dict[str, Any]]] = field(default_factory=list)   # each upload's, by `exchange` index


def _entry(cell: Cell, cls: str, back: list[MissionItem] | None) -> dict[str, Any]:
    return {"plan_type": cell.plan_type.label, "frame": cell.frame, "command": cell.command,
            "sent": [fields_of(it) for it in cell.items],
            "back": [fields_of(it) for it in back] if back is not None else None, "class": cls}


def _placeholder(t: Tester, plan_type: MissionType) -> list[MissionItem]:
    if not t.form.home_slot_of(plan_type):
        return []
    return [MissionItem(0, 0, Cmd.NAV_WAYPOINT, 0.0, 0.0, 0.0, 0.0, HOME_X, HOME_Y, 10.0, 0, 1)]


def _try(t: Tester, survey: Survey, cells: list[Cell]) -> list[dict[str, Any]] | str:
    """Upload `cells` as one plan: their entries, or why not ("refused:NAME", "unanswered")."""
    plan_type = cells[0].plan_type
    lead = _placeholder(t, plan_type)
    items = numbered(lead + [it for c in cells for it in c.items])
    survey.uploads += 1
    exchange = t.exchange = Exchange(t.now())
    try:
        result = _upload_and_read(t, cells, lead, items)
    finally:
        t.exchange = None
        survey.exchanges.append(exchange.finish(t.now()))
    if isinstance(result, list):
        for entry in result:
            entry["exchange"] = len(survey.exchanges) - 1
    return result


def _upload_and_read(t: Tester, cells: list[Cell], lead: list[MissionItem],
                     items: list[MissionItem]) -> list[dict[str, Any]] | str:
    plan_type = cells[0].plan_type
    ack = procedures.upload(t, items, plan_type)
    if ack is None:
        return "unanswered"
    if ack.msg.type != MissionResult.ACCEPTED:
        return "refused:" + procedures.result_name(ack.msg.type).removeprefix("MAV_MISSION_")
    got = procedures.download(t, plan_type)
    if got is not None and len(got.items) < len(items):
        # fewer items than were accepted: read once more after a moment (ArduCopter, still
        # booting, served an accepted fence circle as an empty fence until the survey waited
        # for readiness), so a storage race is not taken for a loss; the second read decides
        t.wait_until(lambda: False, RE_READ_AFTER)
        got = procedures.download(t, plan_type) or got
    if got is None:
        return [_entry(c, "unread", None) for c in cells]
    back = got.items[len(lead):]
    out, at = [], 0
    for c in cells:
        n = len(c.items)
        mine = back[at:at + n]
        sent = numbered(list(c.items), len(lead) + at)
        out.append(_entry(c, classify(sent, [replace(b, current=0) for b in mine], t.form), mine))
        at += n
    if len(back) > at:   # more came back than went up: every cell of the batch says so
        out = [{**e, "class": f"changed:count {len(items)}->{len(got.items)}"} for e in out]
    return out


def run_survey(t: Tester, cells: list[Cell], on_cell: OnCell | None = None) -> Survey:
    survey = Survey()
    groups: dict[tuple[MissionType, int], list[Cell]] = defaultdict(list)
    for cell in cells:
        groups[(cell.plan_type, cell.command)].append(cell)
    for (plan_type, command), members in groups.items():
        batch = _try(t, survey, members) if command != FENCE_RETURN and len(members) > 1 else None
        if not isinstance(batch, list):
            batch = []
            for cell in members:
                one = _try(t, survey, [cell])
                batch += one if isinstance(one, list) else [{**_entry(cell, one, None),
                                                             "exchange": len(survey.exchanges) - 1}]
        for entry in batch:
            survey.cells.append(entry)
            if on_cell is not None:
                on_cell(entry)
    return survey
