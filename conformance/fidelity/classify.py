"""What came back of a cell, judged by the rules, not by our models (issue 26).

`exact`: every field as sent. `int_twin`: only the frame differs, and it came back as its INT
encoding twin or the other way round (0<->5, 3<->6, 10<->11: upstream common.xml declares them
the same frame), the one change upstream allows. Anything else is `changed:` with each field's
from and to; a change a documented rule explains gets `(rule: ...)`: upstream's own (INT twins;
a param common.xml marks "Reserved" carries nothing, so neither does the altitude reference of
an item without an altitude; fence and rally items have no autocontinue) or the target
profile's storage form, named by its id (run.json's `basis` says where the profile has it).
A refusal is `refused:<MISSION_ACK result name>`.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Sequence

from mavconform.reference_impl.mission.items import PLAIN_FRAME, MissionItem
from mavconform.reference_impl.mission.store import STORAGE_FORMS

from ..harness.stored_form import StoredForm
from .command_facts import COMMANDS
from .probes import FIELD

FIELDS = ("frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z", "autocontinue")
UPSTREAM_RESERVED = ("upstream: INT-twin frames, Reserved params, no autocontinue on fence and rally items, "
                     "no altitude reference without an altitude")


def fields_of(item: MissionItem) -> dict[str, Any]:
    return {f: _plain(getattr(item, f)) for f in FIELDS}


def _plain(v: Any) -> Any:
    if isinstance(v, float):
        return "NaN" if v != v else v
    return int(v)


def _same(a: Any, b: Any) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and a != a and b != b)


def _differing(sent: MissionItem, back: MissionItem) -> list[str]:
    return [f for f in FIELDS if not _same(getattr(sent, f), getattr(back, f))]


def classify(sent: Sequence[MissionItem], back: Sequence[MissionItem], form: StoredForm) -> str:
    """The class of a cell whose items were accepted: `sent` as uploaded, `back` as downloaded."""
    if len(back) != len(sent):
        return f"changed:count {len(sent)}->{len(back)}"
    diffs = [(s, b, _differing(s, b)) for s, b in zip(sent, back)]
    if all(not d for _, _, d in diffs):
        return "exact"
    if all(d in ([], ["frame"]) and PLAIN_FRAME.get(s.frame, s.frame) == PLAIN_FRAME.get(b.frame, b.frame)
           for s, b, d in diffs):
        return "int_twin"
    shown = []
    for s, b, d in diffs:
        for f in d:
            text = f"{f} {_plain(getattr(s, f))}->{_plain(getattr(b, f))}"
            if text not in shown:
                shown.append(text)
    rule = explained_by(sent, back, form)
    return "changed:" + ", ".join(shown) + (f" (rule: {rule})" if rule else "")


def precision(sent: Sequence[MissionItem], back: Sequence[MissionItem]) -> dict[str, float]:
    """For each float field that came back as another finite number: how far it moved (the
    precision the round trip kept: 1234.5677 stored in whole centimetres moves 0.0077)."""
    out: dict[str, float] = {}
    for s, b in zip(sent, back):
        for f in ("param1", "param2", "param3", "param4", "z"):
            a, c = getattr(s, f), getattr(b, f)
            if a != c and math.isfinite(a) and math.isfinite(c):
                out[f] = max(out.get(f, 0.0), abs(a - c))
    return out


def _without_reserved(item: MissionItem) -> MissionItem:
    """`item` with the params upstream marks reserved for its command set to 0 (command_facts)."""
    fact = COMMANDS.get(int(item.command))
    if fact is None:
        return item
    blank = {FIELD[index]: 0 if index in (5, 6) else 0.0
             for index, p in enumerate(fact.params, start=1) if p.reserved}
    return replace(item, **blank)


def explained_by(sent: Sequence[MissionItem], back: Sequence[MissionItem], form: StoredForm) -> str | None:
    """Which documented rule turns what was sent into what came back, if one does."""
    upstream = StoredForm(basis="upstream")

    def seen(item: MissionItem, stored: bool) -> dict[str, Any]:      # NaN equal to NaN
        return fields_of(_without_reserved(upstream.canonical(item, stored=stored)))
    if all(seen(b, True) == seen(s, False) for s, b in zip(sent, back)):
        return UPSTREAM_RESERVED
    if form.storage != "exact":
        keep = STORAGE_FORMS[form.storage]
        if all(seen(b, True) == seen(keep(s), True) for s, b in zip(sent, back)):
            return f"{form.storage} item storage"
    return None

