"""The clear clauses (MIS.G.CL.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult

from ...outcome import ClauseFailed
from ..harness import GcsHarness
from ..job import Job
from ..scripted_vehicle import Deaf, Swap, named
from . import check
from .common import (MISSION, clean_clear, fail, first_told, mission_sent, names, require_failure,
                     require_success, resent, stored)


@check("MIS.G.CL.01")
def clear_sent(h: GcsHarness) -> str:
    op = clean_clear(h)
    clears = op.sent("MISSION_CLEAR_ALL")
    if not clears:
        raise fail(h, op, None, f"clearing sent {names(mission_sent(op))}, no MISSION_CLEAR_ALL ({op.result.line()})")
    h.decide(op, clears[0])
    if clears[0].msg.mission_type != MISSION:
        raise ClauseFailed(f"MISSION_CLEAR_ALL carries mission_type {clears[0].msg.mission_type}; the mission is 0")
    require_success(h, op, "MISSION_CLEAR_ALL was accepted")
    return "MISSION_CLEAR_ALL (mission_type 0), accepted"


@check("MIS.G.CL.02")
def clear_resent(h: GcsHarness) -> str:
    op = h.run(Job("clear", MISSION), plans=stored(),
               rules=[Deaf(named("MISSION_CLEAR_ALL"), what="the first MISSION_CLEAR_ALL")])
    return resent(h, op, op.sent("MISSION_CLEAR_ALL"), "MISSION_CLEAR_ALL", "the vehicle did not answer")


@check("MIS.G.CL.03")
def clear_refused(h: GcsHarness) -> str:
    op = h.run(Job("clear", MISSION), plans=stored(), rules=[Swap(
        named("MISSION_ACK", type=MissionResult.ACCEPTED), what="MISSION_ACK ERROR",
        instead=lambda reply, v: [m.ack_message(MissionResult.ERROR, MISSION, v.target)])])
    require_failure(h, op, "the vehicle answered MISSION_CLEAR_ALL with ERROR")
    h.decide(op, first_told(op, "MISSION_ACK"))
    return f"{op.result.line()}"
