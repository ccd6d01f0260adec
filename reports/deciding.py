"""Which event of a clause's exchange decided its verdict, so the diagram can mark it.

The checks record it: a clause carries `decided_by`, the index of the event its check
judged last (the frame its last `expect`/`poll_for`/`collect` consumed, the note an
expectation that timed out wrote, the frame that broke an `expect_silence`, or one the check
named). That index wins. A document without one (an older run, a clause whose deciding
message was not kept, a verdict from a shared observation) gets a guess from the verdict's
own text, first rule that finds something:

1. a note that restates the verdict (a timed-out expectation notes "expected X within N s:
   nothing matching arrived", and the verdict quotes "expected X within N s"): the silence
   decided, so the note is marked;
2. the last event the verdict cites with its fields ("MISSION_CURRENT{seq=0, total=3}"),
   every cited field that the event has agreeing, one from the target preferred;
3. the last message from the target that the verdict names bare ("answered with
   MISSION_REQUEST"), but not one it says did not come ("no MISSION_ACK", "expected X");
4. the last message received from the target; else the last event.

A skipped clause was decided by no message, so it gets None.
"""

from __future__ import annotations

import re
from typing import Any

from mavconform.reports.enum_names import field_value_name
from mavconform.reports.run_document import NOTE, RX, SKIPPED, kept_event_index
from mavconform.reports.text import value_text

_CITED = re.compile(r"\b([A-Z][A-Z0-9]*(?:_[A-Z0-9]+)+)(\{[^{}]*\})?")
_PAIR = re.compile(r"(\w+)=([^,{}\s]+)")
_ABSENT = re.compile(r"(?:\bno|\bexpected|\bnor|\bwithout|\bnever)\s+$")
_MIN_RESTATED = 12   # characters of a note that must recur in the verdict to count


def deciding_event(clause: dict[str, Any], events: list[dict[str, Any]],
                   detail: str | None = None) -> int | None:
    """The index in `events` (the clause's exchange) of the event that decided the clause.
    `detail`: the verdict's text as a person reads it (default: the clause's own)."""
    recorded = recorded_event(clause, events)
    if recorded is not None:
        return recorded
    if not events or clause.get("outcome") == SKIPPED:
        return None
    if detail is None:
        detail = clause.get("detail") or ""
    for rule in (_restating_note, _cited_with_fields, _named_bare):
        found = rule(detail, events)
        if found is not None:
            return found
    received = [i for i, e in enumerate(events) if e["dir"] == RX]
    return received[-1] if received else len(events) - 1


def recorded_event(clause: dict[str, Any], events: list[dict[str, Any]]) -> int | None:
    """The clause's own `decided_by` (an index among the kept events), as an index in
    `events` (ambient ones merged in), if it names one; else None (then `deciding_event`
    guesses, and the report must not say the check recorded it)."""
    recorded = clause.get("decided_by")
    if isinstance(recorded, int) and not isinstance(recorded, bool):
        return kept_event_index(events, recorded)
    return None


def _restating_note(detail: str, events: list[dict[str, Any]]) -> int | None:
    for i in range(len(events) - 1, -1, -1):
        event = events[i]
        if event["dir"] != NOTE:
            continue
        text = event["msg"]
        head = text.rsplit(": ", 1)[0] if ": " in text else text
        if len(head) >= _MIN_RESTATED and head in detail:
            return i
    return None


def _cited_with_fields(detail: str, events: list[dict[str, Any]]) -> int | None:
    best: tuple[bool, int] | None = None
    for match in _CITED.finditer(detail):
        name, braces = match.group(1), match.group(2)
        if braces is None or _ABSENT.search(detail[:match.start()]):
            continue
        cited = dict(_PAIR.findall(braces))
        for i, event in enumerate(events):
            if event["msg"] == name and event["dir"] != NOTE and _agrees(event, cited):
                key = (event["dir"] == RX, i)
                best = key if best is None or key > best else best
    return None if best is None else best[1]


def _named_bare(detail: str, events: list[dict[str, Any]]) -> int | None:
    names = {m.group(1) for m in _CITED.finditer(detail)
             if not _ABSENT.search(detail[:m.start()])}
    found = [i for i, e in enumerate(events) if e["dir"] == RX and e["msg"] in names]
    return found[-1] if found else None


def _agrees(event: dict[str, Any], cited: dict[str, str]) -> bool:
    """Every cited field the event has shows the cited value as the verdict wrote it (the
    number, or its enum name); a citation sharing no field with the event is not of it."""
    fields = event["fields"]
    shared = [name for name in cited if name in fields]
    if cited and not shared:
        return False
    return all(cited[name] in (value_text(fields[name]), str(fields[name]),
                               field_value_name(event["msg"], name, fields[name]))
               for name in shared)
