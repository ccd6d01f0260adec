"""The plan-type clauses (MIS.G.TY.*): MAVLink 2 with mission_type, and another type's traffic
never taken for the running operation."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult

from ...harness import plans
from ...outcome import ClauseFailed
from ..harness import GcsHarness
from ..scripted_vehicle import ITEMS, Swap, named
from . import check
from .common import (FENCE, MISSION, N, RALLY, TYPED, download_job, fail, first_told, plan_diff,
                     plan_of, scripted, short, stored, upload_job)


@check("MIS.G.TY.01")
def typed_and_v2(h: GcsHarness) -> str:
    ops = [h.run(upload_job(FENCE)), h.run(download_job(RALLY), plans=stored(RALLY))]
    for op in ops:
        mt = op.job.mission_type
        for e in op.sent(*TYPED):
            if e.version != 2:
                raise fail(h, op, e, f"{short(e.msg)} of a {mt.label} {op.job.op} went as MAVLink {e.version}: "
                                     "mission_type is a MAVLink 2 extension")
            if e.msg.mission_type != mt:
                raise fail(h, op, e, f"{short(e.msg)} of a {mt.label} {op.job.op} carries mission_type "
                                     f"{e.msg.mission_type}, not {int(mt)}")
    return "fence upload and rally download: every message MAVLink 2 with its mission_type"


@check("MIS.G.TY.02")
def other_type_request(h: GcsHarness) -> str:
    # the fence's request comes first, in place of the mission's first one: an item the GCS
    # sends before the mission's own request can only be its answer to the fence's (a GCS
    # that floods items answers a request too, just with more than it asked for)
    op = h.run(upload_job(), rules=[Swap(
        named("MISSION_REQUEST_INT", seq=0, mission_type=MISSION), then_after=0.5,
        what="MISSION_REQUEST_INT 0 of the fence; the mission's 500 ms later",
        instead=lambda reply, v: [m.request_message(0, FENCE, v.target)])])
    odd = scripted(op, "the fence's request", "MISSION_REQUEST_INT", mission_type=FENCE)
    proper = first_told(op, "MISSION_REQUEST_INT", seq=0, mission_type=MISSION)
    answered = [e for e in op.after(odd, *ITEMS) if e.msg.seq == 0 and (proper is None or e.t < proper.t)]
    if answered:
        raise fail(h, op, answered[0], f"the fence's request for item 0 was answered with {short(answered[0].msg)} "
                                       f"(mission_type {answered[0].msg.mission_type}) during a mission upload")
    h.decide(op, odd)
    return "the fence's request was not answered with an item"


@check("MIS.G.TY.03")
def other_type_ack(h: GcsHarness) -> str:
    op = h.run(upload_job(), rules=[Swap(
        named("MISSION_REQUEST_INT", seq=1, mission_type=MISSION), then_after=0.2,
        what="MISSION_ACK ACCEPTED of the rally points; the request 200 ms later",
        instead=lambda reply, v: [m.ack_message(MissionResult.ACCEPTED, RALLY, v.target)])])
    odd = scripted(op, "the rally ACK", "MISSION_ACK", mission_type=RALLY)
    h.decide(op, odd)
    rest = [e.msg.seq for e in op.after(odd, *ITEMS)]
    if not op.result.ok or not set(range(1, N)) <= set(rest):
        raise ClauseFailed(f"after a rally MISSION_ACK mid-upload the GCS sent items {rest} and "
                           f"{op.result.line()}: the other type's ACK ended the mission upload")
    return "the rally ACK was ignored; the mission upload went on and succeeded"


@check("MIS.G.TY.04")
def other_type_item(h: GcsHarness) -> str:
    plan, fence = plan_of(), plans.fence()
    op = h.run(download_job(), plans=stored(), rules=[Swap(
        named(*ITEMS, seq=1, mission_type=MISSION), then_after=0.1,
        what="a fence item with seq 1; the mission's 100 ms later",
        instead=lambda reply, v: [m.item_message(fence[1], v.target, as_int=reply._type == "MISSION_ITEM_INT")])])
    odd = scripted(op, "the fence item", *ITEMS, mission_type=FENCE)
    h.decide(op, odd)
    if not op.result.ok:   # refusing the odd item ends the download, but takes nothing in
        return f"the fence item was not taken: {op.result.line()}"
    diff = plan_diff(op.result.items, plan)
    if diff:
        raise ClauseFailed(f"the fence item was taken into the mission: {diff}")
    return "the fence item was not taken; the mission downloaded whole"
