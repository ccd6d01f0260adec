"""Run the fidelity survey against a target: upload each cell, download it, classify it.

Bounded by batching (issue 26): the cells of one plan type and item kind (frame matrix), or
of one command (command matrix), go up in one upload where the target takes them all. A
refusal ends an upload at the item it answers: that cell is refused, and the rest go up again
without it; a refusal that answers no item (the count) splits the batch into one upload per
cell. A command's nominal item goes first and alone: a command the target does not take has
no param cells. A fence's return point goes alone (a fence holds one). Where the target keeps
its home in mission slot 0 (ArduPilot, A1), a placeholder waypoint goes first and is not judged. Each upload and
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
from .classify import classify, fields_of, precision

OnCell = Callable[[dict[str, Any]], None]
RE_READ_AFTER = 1.0     # s before a download that came back short is read again


@dataclass
class Survey:
    cells: list[dict[str, Any]] = field(default_factory=list)
    uploads: int = 0
    exchanges: list[list[dict[str, Any]]] = field(default_factory=list)   # each upload's, by `exchange` index


def _entry(cell: Cell, cls: str, back: list[MissionItem] | None) -> dict[str, Any]:
    entry = {"plan_type": cell.plan_type.label, "frame": cell.frame, "command": cell.command}
    if cell.probe:
        entry["probe"] = cell.probe
    entry.update({"sent": [fields_of(it) for it in cell.items],
                  "back": [fields_of(it) for it in back] if back is not None else None, "class": cls})
    if back is not None:
        kept = precision(cell.items, back)
        if kept:
            entry["precision"] = kept
    return entry


def _placeholder(t: Tester, plan_type: MissionType) -> list[MissionItem]:
    if not t.form.home_slot_of(plan_type):
        return []
    return [MissionItem(0, 0, Cmd.NAV_WAYPOINT, 0.0, 0.0, 0.0, 0.0, HOME_X, HOME_Y, 10.0, 0, 1)]


def _try(t: Tester, survey: Survey, cells: list[Cell]) -> tuple[list[dict[str, Any]] | str, int | None]:
    """Upload `cells` as one plan: their entries, or why not ("refused:NAME", "unanswered") and
    which of them the refusal answered (None: not one item, or none of the cells')."""
    plan_type = cells[0].plan_type
    lead = _placeholder(t, plan_type)
    items = numbered(lead + [it for c in cells for it in c.items])
    survey.uploads += 1
    exchange = t.exchange = Exchange(t.now())
    refused_at = None
    try:
        result = _upload_and_read(t, cells, lead, items)
        if isinstance(result, str) and result.startswith("refused:"):
            refused_at = _refused_cell(t, cells, len(lead))
    finally:
        t.exchange = None
        survey.exchanges.append(exchange.finish(t.now()))
    if isinstance(result, list):
        for entry in result:
            entry["exchange"] = len(survey.exchanges) - 1
    return result, refused_at


def _refused_cell(t: Tester, cells: list[Cell], lead: int) -> int | None:
    """The cell whose item the refusing MISSION_ACK answered: the last item the vehicle asked
    for before it (a vehicle checks each item as it arrives and ends the upload at the first
    it will not store). None where it refused before asking for any of the cells' items."""
    seq = None
    for frame in t.since_mark():
        if frame.msg._type in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):
            seq = frame.msg.seq
        elif frame.msg._type == "MISSION_ACK":
            break
    if seq is None or seq < lead:
        return None
    at = seq - lead
    for n, cell in enumerate(cells):
        if at < len(cell.items):
            return n
        at -= len(cell.items)
    return None


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


def _settle(t: Tester, survey: Survey, members: list[Cell]) -> list[dict[str, Any]]:
    """Every member's entry, in as few uploads as the target allows: the batch; where it is
    refused at one cell, that cell is refused (the refusal is its own) and the rest go up
    again; where the refusal names no cell, or nothing answers, one upload per cell."""
    decided: dict[int, dict[str, Any]] = {}
    remaining = list(range(len(members)))
    for _ in range(len(members)):                   # bounded: each round decides a cell or all
        if len(remaining) < 2 or members[remaining[0]].command == FENCE_RETURN:
            break
        result, at = _try(t, survey, [members[i] for i in remaining])
        if isinstance(result, list):
            decided.update(zip(remaining, result))
            remaining = []
            break
        if at is None:
            break
        n = remaining.pop(at)
        decided[n] = _unstored(survey, members[n], result)
    for n in remaining:
        one, _ = _try(t, survey, [members[n]])
        decided[n] = one[0] if isinstance(one, list) else _unstored(survey, members[n], one)
    return [decided[n] for n in range(len(members))]


def _unstored(survey: Survey, cell: Cell, why: str) -> dict[str, Any]:
    """The entry of a cell the last upload did not store ("refused:NAME", "unanswered")."""
    return {**_entry(cell, why, None), "exchange": len(survey.exchanges) - 1}


def run_survey(t: Tester, cells: list[Cell], on_cell: OnCell | None = None) -> Survey:
    """Frame cells grouped by plan type and item kind; command cells by command, their nominal
    item first and alone: a command the target refuses as such has no param cells surveyed."""
    survey = Survey()
    groups: dict[tuple[MissionType, int, bool], list[Cell]] = defaultdict(list)
    for cell in cells:
        groups[(cell.plan_type, cell.command, bool(cell.probe))].append(cell)
    for (_, _, probing), members in groups.items():
        if probing and members[0].probe == "nominal":
            batch = _settle(t, survey, members[:1])
            if batch[0]["class"].split(":")[0] in ("exact", "int_twin", "changed"):
                batch += _settle(t, survey, members[1:])
        else:
            batch = _settle(t, survey, members)
        for entry in batch:
            survey.cells.append(entry)
            if on_cell is not None:
                on_cell(entry)
    return survey
