"""What a profile says each cell should come to, from its declared rules alone (issue 26).

A profile declares which items its vehicle refuses and with which MISSION_ACK code (its item
rules, reference_impl/mission/validation.py), which plan types it stores, and how it stores an
item it takes (its storage form, store.STORAGE_FORMS, each with its VARIANTS.md row). From
those the cell's class follows without running a vehicle: the survey of a builtin target must
come out equal to it cell for cell (tests/conformance/fidelity/), and a real target's survey is
read against it (`predicted` beside `class` in run.json): a cell that differs is either the
vehicle changing something no rule says or a rule the profile lacks, and the report says which
cells to read in the autopilot's source.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.store import STORAGE_FORMS
from mavconform.reference_impl.mission.validation import first_defect

from ..harness.stored_form import StoredForm
from .cells import Cell, numbered
from .classify import UPSTREAM_RESERVED, classify

REFUSED = "refused:"


def kept_as_upstream_allows(cls: str) -> bool:
    """exact, an INT twin, or a change upstream's own rules explain (a reserved param dropped,
    a fence item's autocontinue): the item kept, whatever the profile's storage form."""
    return cls in ("exact", "int_twin") or (cls.startswith("changed:") and cls.endswith(f"(rule: {UPSTREAM_RESERVED})"))


def agrees(cls: str, predicted: str) -> bool:
    """Whether a cell came out as predicted: the same class, or both kept as upstream allows
    (a profile need not say which of those its vehicle does)."""
    return cls == predicted or (kept_as_upstream_allows(cls) and kept_as_upstream_allows(predicted))


def predictable(behaviour: Any) -> bool:
    """Whether the declared rules say everything about a cell: not for a vehicle that ignores
    mission_type or answers items otherwise than by the rules (INAV's knobs)."""
    return not (behaviour.mission_type_ignored or behaviour.upload_counters_persist or not behaviour.nack_ends_upload)


def predict(cell: Cell, behaviour: Any, form: StoredForm) -> str:
    if cell.plan_type not in behaviour.supported_types:
        return REFUSED + MissionResult.UNSUPPORTED.name
    if len(cell.items) > behaviour.capacity.get(cell.plan_type, 0):
        return REFUSED + MissionResult.NO_SPACE.name
    for item in cell.items:
        defect = first_defect(item, behaviour.item_rules)
        if defect is not None:
            return REFUSED + MissionResult(defect.code).name
    keep = STORAGE_FORMS[behaviour.item_storage]
    sent = numbered(list(cell.items), 1 if form.home_slot_of(cell.plan_type) else 0)
    return classify(sent, [keep(it) for it in sent], form)
