"""The upload clauses (MIS.G.UP.*): the GCS answers the vehicle's requests, as planned, and
resends what got no answer."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult

from ...harness.measured import Measured
from ...outcome import ClauseFailed
from ..harness import GcsHarness, Operation
from ..job import Job
from ..scripted_vehicle import ITEMS, REQUESTS, Deaf, Swap, named
from . import check
from .common import (FLOAT_XY_SLACK, MISSION, MISSION_NAMES, N, REANSWER_WITHIN, WATCH_AFTER,
                     answer_after, clean_upload, fail, first_mission_message, first_told,
                     item_diff, mission_sent, names, require_failure, require_success, resent,
                     scripted, short, silent_to_count, upload_job)


@check("MIS.G.UP.01")
def count_first(h: GcsHarness) -> str:
    op = clean_upload(h)
    first = first_mission_message(h, op)
    if first.msg._type != "MISSION_COUNT":
        raise fail(h, op, first, f"the upload began with {names([first])}, not MISSION_COUNT")
    h.decide(op, first)
    if first.msg.count != N or first.msg.mission_type != MISSION:
        raise ClauseFailed(f"MISSION_COUNT count {first.msg.count} mission_type {first.msg.mission_type}; "
                           f"the plan has {N} mission items (type 0)")
    return f"MISSION_COUNT {N} (mission_type 0)"


def _answers(h: GcsHarness, op: Operation, *, slack: int, forms: tuple[str, ...]) -> str:
    plan = list(op.job.items)
    requests = op.told(*REQUESTS)
    if not requests:
        raise fail(h, op, None, f"the vehicle never got to request an item ({op.result.line()})")
    for request in requests:
        answer = answer_after(op, request, ITEMS)
        if answer is None:
            raise fail(h, op, request, f"{short(request.msg)} got no item with seq {request.msg.seq}; "
                                       f"the GCS sent {names(op.after(request, *MISSION_NAMES))}")
        if answer.msg._type not in forms:
            raise fail(h, op, answer, f"{short(request.msg)} was answered by {answer.msg._type}, "
                                      f"not {' or '.join(forms)}")
        diff = item_diff(m.item_from_message(answer.msg), plan[request.msg.seq], slack)
        if diff:
            raise fail(h, op, answer, f"{short(answer.msg)} is not the planned item: {diff}")
    require_success(h, op, "every request was answered with the planned item")
    h.decide(op, answer)
    return f"{len(requests)} requests, each answered with the planned item"


@check("MIS.G.UP.02")
def items_as_requested(h: GcsHarness) -> str:
    return _answers(h, clean_upload(h), slack=0, forms=("MISSION_ITEM_INT",))


@check("MIS.G.UP.03")
def float_requests(h: GcsHarness) -> str:
    # upstream deprecates MISSION_REQUEST: "respond with MISSION_ITEM_INT (as though
    # MISSION_REQUEST_INT was received)", so either form answers it
    op = h.run(upload_job(), request_float=True)
    return _answers(h, op, slack=FLOAT_XY_SLACK, forms=ITEMS)


@check("MIS.G.UP.04")
def repeated_request(h: GcsHarness) -> str:
    last = N - 1
    op = h.run(upload_job(), rules=[Deaf(named(*ITEMS, seq=last), rerequest_after=0.25,
                                      what=f"item {last}; requested again 250 ms later")])
    repeat = [e for e in op.told(*REQUESTS) if e.msg.seq == last][1:]
    if not repeat:
        raise fail(h, op, None, f"the vehicle never got to repeat its request ({op.result.line()})")
    answer = answer_after(op, repeat[0], ITEMS)
    if answer is None or answer.t - repeat[0].t > REANSWER_WITHIN:
        late = "" if answer is None else (f" within {REANSWER_WITHIN:g} s (the item came {answer.t - repeat[0].t:.1f} s "
                                          "later: the GCS's own resend, not an answer)")
        raise fail(h, op, repeat[0], f"the repeated {short(repeat[0].msg)} got no answer{late}; the GCS sent "
                                     f"{names(op.after(repeat[0], *MISSION_NAMES))} ({op.result.line()})")
    require_success(h, op, f"the repeated request for item {last} was answered")
    h.decide(op, answer)
    return Measured("the repeated request for the last item was answered after <s> s",
                    s=f"{answer.t - repeat[0].t:.3f}")


@check("MIS.G.UP.05")
def last_item_resent(h: GcsHarness) -> str:
    op = h.run(upload_job(), rules=[Swap(named("MISSION_ACK", type=MissionResult.ACCEPTED), what="final ACK lost",
                                      armed_by=named(*ITEMS, seq=N - 1))])
    last = [e for e in op.sent(*ITEMS) if e.msg.seq == N - 1]
    if len(last) < 2:
        raise fail(h, op, last[-1] if last else None,
                   f"the last item was sent {len(last)} time(s): never resent when the final MISSION_ACK "
                   f"did not come ({op.result.line()})")
    require_success(h, op, "the last item was resent and the vehicle's ACK came")
    h.decide(op, last[1])
    return Measured("the last item was resent <s> s after the first, and the upload succeeded",
                    s=f"{last[1].t - last[0].t:.3f}")


@check("MIS.G.UP.06")
def count_resent(h: GcsHarness) -> str:
    op = h.run(upload_job(), rules=[Deaf(named("MISSION_COUNT"), what="the first MISSION_COUNT")])
    return resent(h, op, op.sent("MISSION_COUNT"), "MISSION_COUNT", "the vehicle did not answer")


@check("MIS.G.UP.07")
def silent_upload_given_up(h: GcsHarness) -> str:
    op = silent_to_count(h)
    counts = op.sent("MISSION_COUNT")
    require_failure(h, op, f"the vehicle never answered any of {len(counts)} MISSION_COUNT")
    h.decide(op, counts[-1])
    return Measured(f"given up after {len(counts)} MISSION_COUNT, <s> s: <said>",
                    s=f"{op.result.at - op.started:.1f}", said=op.result.said)


@check("MIS.G.UP.08")
def error_ack_ends_upload(h: GcsHarness) -> str:
    op = h.run(upload_job(), after=WATCH_AFTER,
               rules=[Swap(named(*REQUESTS, seq=0), what="MISSION_ACK NO_SPACE",
                           instead=lambda reply, v: [m.ack_message(MissionResult.NO_SPACE, MISSION, v.target)])])
    nack = scripted(op, "its NO_SPACE", "MISSION_ACK")
    items = op.after(nack, *ITEMS)
    if items:
        raise fail(h, op, items[0], f"{short(items[0].msg)} was sent after the vehicle's NO_SPACE")
    require_failure(h, op, "the vehicle answered MISSION_COUNT with NO_SPACE")
    h.decide(op, nack)
    return f"no item after NO_SPACE; {op.result.line()}"


@check("MIS.G.UP.09")
def no_flood(h: GcsHarness) -> str:
    op = clean_upload(h)
    asked: dict[int, int] = {}
    for e in op.events:
        if e.dir == "tx" and e.msg._type in REQUESTS:
            asked[e.msg.seq] = asked.get(e.msg.seq, 0) + 1
        elif e.dir == "rx" and e.msg._type in ITEMS:
            seq = e.msg.seq
            if asked.get(seq, 0) == 0:
                raise fail(h, op, e, f"{short(e.msg)} was sent "
                                     + ("before it was requested" if seq not in asked else
                                        "more times than it was requested"))
            asked[seq] -= 1
    return "each item was sent once per request"


@check("MIS.G.UP.10")
def empty_upload(h: GcsHarness) -> str:
    op = h.run(Job("upload", MISSION, ()))
    counts, items = op.sent("MISSION_COUNT"), op.sent(*ITEMS)
    if not counts or counts[0].msg.count != 0:
        sent = mission_sent(op)
        raise fail(h, op, counts[0] if counts else None,
                   f"an empty plan was uploaded as {names(sent[:3])}, not MISSION_COUNT 0 ({op.result.line()})")
    if items:
        raise fail(h, op, items[0], f"{short(items[0].msg)} was sent for an empty plan")
    require_success(h, op, "MISSION_COUNT 0 was accepted")
    h.decide(op, first_told(op, "MISSION_ACK"))
    return "MISSION_COUNT 0, accepted"
