"""The set-current clauses (MIS.G.SC.*)."""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission.constants import Cmd

from ...harness import plans
from ...outcome import ClauseFailed, PreconditionFailed
from ..harness import GcsHarness, Operation
from ..job import Job
from ..scripted_vehicle import Event
from . import check
from .common import (MISSION, WATCH_AFTER, fail, first_told, mission_sent, names, require_success,
                     stored)


SET_CURRENT_SEQ = 2


def _set_current(h: GcsHarness) -> Operation:
    return h.observe("set current", Job("set-current", MISSION, seq=SET_CURRENT_SEQ),
                     plans=stored(items=plans.mission(5)), after=WATCH_AFTER)


def _set_current_messages(op: Operation) -> list[Event]:
    return [e for e in op.sent("MISSION_SET_CURRENT", "COMMAND_LONG")
            if e.msg._type == "MISSION_SET_CURRENT" or e.msg.command == Cmd.DO_SET_MISSION_CURRENT]


def _seq_of(msg: Any) -> int:
    return msg.seq if msg._type == "MISSION_SET_CURRENT" else int(msg.param1)


@check("MIS.G.SC.01")
def set_current_sent(h: GcsHarness) -> str:
    op = _set_current(h)
    sent = _set_current_messages(op)
    if not sent:
        raise fail(h, op, None, f"set-current sent {names(mission_sent(op))}: neither MISSION_SET_CURRENT nor "
                                "MAV_CMD_DO_SET_MISSION_CURRENT")
    h.decide(op, sent[0])
    if _seq_of(sent[0].msg) != SET_CURRENT_SEQ:
        raise ClauseFailed(f"{sent[0].msg._type} names item {_seq_of(sent[0].msg)}, not {SET_CURRENT_SEQ}")
    require_success(h, op, f"{sent[0].msg._type} {SET_CURRENT_SEQ} was confirmed by MISSION_CURRENT")
    return f"{sent[0].msg._type} for item {SET_CURRENT_SEQ}, confirmed"


@check("MIS.G.SC.02")
def set_current_not_repeated(h: GcsHarness) -> str:
    op = _set_current(h)
    sent = _set_current_messages(op)
    if not sent:
        raise PreconditionFailed(f"the GCS sent no set-current ({names(mission_sent(op))})")
    asked = _seq_of(sent[0].msg)   # what it asked for, right or wrong (MIS.G.SC.01 judges that)
    confirmed = first_told(op, "MISSION_CURRENT", seq=asked)
    if confirmed is None:
        raise PreconditionFailed(f"the vehicle did not confirm item {asked} (it holds {len(op.vehicle.plans[MISSION])})")
    again = [e for e in sent if e.t > confirmed.t]
    if again:
        raise fail(h, op, again[0], f"{again[0].msg._type} was sent {len(again)} more time(s) after MISSION_CURRENT "
                                    f"{asked} confirmed it")
    h.decide(op, confirmed)
    return "nothing resent after MISSION_CURRENT confirmed it"
