"""A target that answers only the float forms: MISSION_ITEM and MISSION_REQUEST.

The spec's GCS speaks MISSION_ITEM_INT and MISSION_REQUEST_INT, and so do the checks. INAV
9.1 handles neither: its telemetry dispatch has no case for them, so they get no reply at
all (src/main/telemetry/mavlink.c:1389-1437, `default: return false` at 1430), and it
answers and asks with the float forms only. Against such a target every clause that
uploads or reads a plan would end undecided for that one reason. So before the first
clause the suite finds out (`probe`, from readiness.py): a MISSION_REQUEST_INT that gets
nothing while a MISSION_REQUEST gets an answer marks the target float-only, and from then
on the testers send the float form of each _INT message and take the float form of each
_INT reply they wait for, saying so in every exchange where that happened.

Clauses about the _INT forms themselves (`JUDGES_INT_FORMS`) get no such help: there the
target is judged on what it does with them. That is where ignoring the _INT forms shows
up, once, and not in forty unrelated clauses.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.items import MissionType

from .match import Match, msg

INT_TO_FLOAT = {"MISSION_ITEM_INT": "MISSION_ITEM", "MISSION_REQUEST_INT": "MISSION_REQUEST"}
# the clauses that judge the _INT forms (catalogue.py): never translated
JUDGES_INT_FORMS = frozenset({"MIS.DN.02"})


def to_float(message: Any) -> Any:
    """The float form of a MISSION_ITEM_INT or MISSION_REQUEST_INT (the same item, request)."""
    target = (message.target_system, message.target_component)
    if message._type == "MISSION_ITEM_INT":
        item = m.item_from_message(message)
        return m.item_message(item, target, as_int=False)
    return m.request_message(message.seq, message.mission_type, target, as_int=False)


def widen(match: Match) -> Match:
    """`match`, also taking the float twin of each _INT message it names."""
    names = match.names
    if not names or not names & INT_TO_FLOAT.keys():
        return match
    return Match(names | {INT_TO_FLOAT[n] for n in names if n in INT_TO_FLOAT}, match.fields,
                 match.test, match.label or str(match))


def probe(t: Any) -> str:
    """Does the target answer MISSION_REQUEST_INT for an item it holds? If not, but it
    answers MISSION_REQUEST with that MISSION_ITEM, mark the tester float-only (`int_forms`
    False). Only an item decides: a request beyond the list is a stray that some targets
    answer in one form and not the other (MAVSDK's server). With no item to ask for, what the
    profile says stands (`--profile inav`, builtin:inav: the session starts float-only). The
    line says what was found."""
    from . import procedures   # (procedures imports the tester, which imports this module)
    t.mark()
    count = procedures.open_download(t, MissionType.MISSION, resends=1)
    if count is None:
        return "forms probe: no MISSION_COUNT (the clauses judge that)"
    if count.msg.count == 0:
        t.send(m.ack_message(0, MissionType.MISSION, t.target))
        kept = "the float forms, as its profile says" if not t.int_forms else "the _INT forms"
        return f"forms probe: undecided (the target holds no item to ask for): the clauses use {kept}"
    item0 = msg(("MISSION_ITEM_INT", "MISSION_ITEM"), seq=0)
    t.send(m.request_message(0, MissionType.MISSION, t.target, as_int=True))
    said = "forms probe: MISSION_REQUEST_INT answered"
    if t.poll_for(item0, t.timings.default_timeout) is None:
        t.send(m.request_message(0, MissionType.MISSION, t.target, as_int=False))
        if t.poll_for(item0, t.timings.default_timeout) is not None:
            t.int_forms = False
            said = ("forms probe: MISSION_REQUEST_INT got no reply, MISSION_REQUEST did: the target "
                    "answers only the float forms, so the clauses use MISSION_ITEM / MISSION_REQUEST "
                    f"(except {', '.join(sorted(JUDGES_INT_FORMS))}, which judges the _INT forms)")
        else:
            said = "forms probe: neither MISSION_REQUEST_INT nor MISSION_REQUEST got item 0 (the clauses judge that)"
    t.send(m.ack_message(0, MissionType.MISSION, t.target))
    return said

