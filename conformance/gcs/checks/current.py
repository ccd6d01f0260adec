"""The set-current clauses (MIS.G.SC.*)."""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission.constants import Cmd

from ...harness import plans
from ...harness.measured import Measured
from ...outcome import ClauseFailed, PreconditionFailed
from ..harness import GcsHarness, Operation
from ..job import Job
from ..scripted_vehicle import Deaf, Event
from . import check
from .common import (MISSION, WATCH_AFTER, fail, first_told, mission_sent, names, require_success,
                     resent, stored)


SET_CURRENT_SEQ = 2


def set_current_op(h: GcsHarness) -> Operation:
    """The GCS sets item 2 of a 5-item mission current; the vehicle confirms at once."""
    return h.observe("set current", _job(), plans=stored(items=plans.mission(5)), after=WATCH_AFTER)


def _job() -> Job:
    return Job("set-current", MISSION, seq=SET_CURRENT_SEQ)


def _is_set_current(msg: Any) -> bool:
    """MISSION_SET_CURRENT, or the command that replaces it (MAV_CMD_DO_SET_MISSION_CURRENT)."""
    return msg._type == "MISSION_SET_CURRENT" or (msg._type == "COMMAND_LONG"
                                                   and msg.command == Cmd.DO_SET_MISSION_CURRENT)


def _set_current_messages(op: Operation) -> list[Event]:
    return [e for e in op.sent("MISSION_SET_CURRENT", "COMMAND_LONG") if _is_set_current(e.msg)]


def _seq_of(msg: Any) -> int:
    return msg.seq if msg._type == "MISSION_SET_CURRENT" else int(msg.param1)


@check("MIS.G.SC.01")
def set_current_sent(h: GcsHarness) -> str:
    op = set_current_op(h)
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
    op = set_current_op(h)
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


@check("MIS.G.SC.03")
def set_current_resent(h: GcsHarness) -> Measured:
    # seed 000:482 fixes no timeout for it, so any the GCS has is accepted; what is checked is
    # that the set-current goes out again before the GCS gives up
    op = h.run(_job(), plans=stored(items=plans.mission(5)),
               rules=[Deaf(_is_set_current, what="the first set-current")])
    sent = _set_current_messages(op)
    what = sent[0].msg._type if sent else "set-current"
    return resent(h, op, sent, what, "no MISSION_CURRENT confirmed it")
