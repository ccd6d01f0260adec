"""The download clauses (MIS.G.DN.*): the GCS asks, in order, resends, and ends with its ACK."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult

from ...harness.measured import Measured
from ...outcome import ClauseFailed
from ..harness import GcsHarness, Operation
from ..scripted_vehicle import ITEMS, REQUESTS, Deaf, Event, Swap, named
from . import check
from .common import (MISSION, MISSION_NAMES, N, clean_download, download_ended_by, download_job,
                     fail, first_mission_message, first_told, names, plan_diff, plan_of,
                     require_failure, require_success, resent, scripted, short, stored)


@check("MIS.G.DN.01")
def request_list_first(h: GcsHarness) -> str:
    op = clean_download(h)
    first = first_mission_message(h, op)
    h.decide(op, first)
    if first.msg._type != "MISSION_REQUEST_LIST" or first.msg.mission_type != MISSION:
        raise ClauseFailed(f"the download began with {short(first.msg)}"
                           + (f" of mission_type {first.msg.mission_type}" if hasattr(first.msg, "mission_type") else "")
                           + ", not MISSION_REQUEST_LIST of the mission (type 0)")
    return "MISSION_REQUEST_LIST (mission_type 0)"


@check("MIS.G.DN.02")
def requested_in_order(h: GcsHarness) -> str:
    op = clean_download(h)
    requests = op.sent(*REQUESTS)
    seqs = [e.msg.seq for e in requests]
    if seqs != list(range(N)):
        raise fail(h, op, requests[0] if requests else None,
                   f"items were requested in the order {seqs}, expected {list(range(N))}")
    for previous, request in zip(requests, requests[1:]):
        item = first_told(op, *ITEMS, seq=previous.msg.seq)
        if item is None or request.t < item.t:
            raise fail(h, op, request, f"{short(request.msg)} was sent before item {previous.msg.seq} came")
    require_success(h, op, "every item was requested in order")
    diff = plan_diff(op.result.items, plan_of())
    if diff:
        raise fail(h, op, requests[-1], f"the plan the GCS reported is not the vehicle's: {diff}")
    h.decide(op, requests[-1])
    return f"items 0..{N - 1} requested in order; the plan got is the vehicle's"


@check("MIS.G.DN.03")
def request_list_resent(h: GcsHarness) -> str:
    op = h.run(download_job(), plans=stored(), rules=[Deaf(named("MISSION_REQUEST_LIST"), what="the first MISSION_REQUEST_LIST")])
    return resent(h, op, op.sent("MISSION_REQUEST_LIST"), "MISSION_REQUEST_LIST", "the vehicle did not answer")


@check("MIS.G.DN.04")
def item_request_resent(h: GcsHarness) -> str:
    op = h.run(download_job(), plans=stored(), rules=[Swap(named(*ITEMS, seq=1), what="item 1 lost")])
    return resent(h, op, [e for e in op.sent(*REQUESTS) if e.msg.seq == 1], "the request for item 1",
                  "the item did not come")


def _final_ack(h: GcsHarness, op: Operation, last: Event, what: str) -> Event:
    """The GCS's first MISSION_ACK after the vehicle's `last` message of the download."""
    acks = op.after(last, "MISSION_ACK")
    if not acks:
        raise fail(h, op, op.sent()[-1], f"no MISSION_ACK after {what} ({op.result.line()})")
    ack = acks[0]
    h.decide(op, ack)
    if ack.msg.type != MissionResult.ACCEPTED or ack.msg.mission_type != op.job.mission_type:
        raise ClauseFailed(f"the final MISSION_ACK has type {MissionResult.describe(ack.msg.type)} and "
                           f"mission_type {ack.msg.mission_type}; expected ACCEPTED, {int(op.job.mission_type)}")
    return ack


@check("MIS.G.DN.05")
def final_ack(h: GcsHarness) -> str:
    op = clean_download(h)
    _final_ack(h, op, scripted(op, "the last item", *ITEMS, seq=N - 1), "the last item")
    return "MISSION_ACK ACCEPTED after the last item"


@check("MIS.G.DN.06")
def empty_download(h: GcsHarness) -> str:
    op = h.run(download_job(), plans=stored(items=[]))
    _final_ack(h, op, scripted(op, "MISSION_COUNT 0", "MISSION_COUNT"), "MISSION_COUNT 0")
    require_success(h, op, "the empty plan was acknowledged")
    if op.result.items:
        raise ClauseFailed(f"the GCS reported {len(op.result.items)} items for an empty plan")
    return "MISSION_ACK ACCEPTED after MISSION_COUNT 0; an empty plan reported"


@check("MIS.G.DN.07")
def out_of_sequence_item(h: GcsHarness) -> str:
    plan = plan_of()
    op = h.run(download_job(), plans=stored(), rules=[Swap(
        named(*ITEMS, seq=1), what="item 2 sent in its place",
        instead=lambda reply, v: [m.item_message(plan[2], v.target, as_int=reply._type == "MISSION_ITEM_INT")])])
    wrong = scripted(op, "item 2 in place of item 1", *ITEMS, seq=2)
    again = next((e for e in op.after(wrong, *REQUESTS) if e.msg.seq == 1), None)
    if again is None:
        raise fail(h, op, wrong, f"after item 2 came in place of item 1 the GCS sent "
                                 f"{names(op.after(wrong, *MISSION_NAMES))}, "
                                 f"not a request for item 1 ({op.result.line()})")
    diff = plan_diff(op.result.items, plan) if op.result.ok else op.result.line()
    if diff:
        raise fail(h, op, again, f"item 1 was requested again, but the download did not end with the vehicle's "
                                 f"plan: {diff}")
    h.decide(op, again)
    return "item 1 requested again after the out-of-sequence item 2"



@check("MIS.G.DN.08")
def error_ack_ends_download(h: GcsHarness) -> str:
    return download_ended_by(h, MissionResult.ERROR)


@check("MIS.G.DN.09")
def requests_int(h: GcsHarness) -> str:
    op = clean_download(h)
    floats = op.sent("MISSION_REQUEST")
    if floats:
        raise fail(h, op, floats[0], f"items were requested with MISSION_REQUEST ({len(floats)} of "
                                     f"{len(op.sent(*REQUESTS))} requests)")
    return "every item requested with MISSION_REQUEST_INT"


@check("MIS.G.DN.10")
def silent_download_given_up(h: GcsHarness) -> str:
    op = h.run(download_job(), plans=stored(),
               rules=[Deaf(named("MISSION_REQUEST_LIST"), times=None, what="every MISSION_REQUEST_LIST")])
    lists = op.sent("MISSION_REQUEST_LIST")
    require_failure(h, op, f"the vehicle never answered any of {len(lists)} MISSION_REQUEST_LIST")
    h.decide(op, lists[-1])
    return Measured(f"given up after {len(lists)} MISSION_REQUEST_LIST, <s> s", s=f"{op.result.at - op.started:.1f}")
