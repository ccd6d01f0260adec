"""One check per GCS clause: the operation it has the GCS do, the vehicle's script, the verdict.

A check returns a short text when the clause holds and raises `ClauseFailed` saying what
the GCS did instead. Operations several clauses judge alike (a clean upload, a vehicle
silent to MISSION_COUNT) are run once per run (`GcsHarness.observe`). Every plan is small
and distinct (conformance/harness/plans.py), so a wrong item can never match by accident.
"""

from __future__ import annotations

import statistics
from dataclasses import replace
from decimal import Decimal
from typing import Any, Callable

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import plans
from ..harness.measured import Measured
from ..outcome import ClauseFailed, PreconditionFailed
from .harness import GcsHarness, Operation
from .job import Job
from .scripted_vehicle import ITEMS, REQUESTS, Deaf, Event, Mute, Swap, named

Check = Callable[[GcsHarness], "str | None"]
GCS_CHECKS: dict[str, Check] = {}

MISSION, FENCE, RALLY = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY
N = 3                           # items in the plans the checks move
DEFAULT_TIMEOUT = 1.5           # s, seed 000:533
MAX_RETRIES = 5                 # seed 000:537
ACCEPTED_TIMEOUT = (0.5 * DEFAULT_TIMEOUT, 2 * DEFAULT_TIMEOUT)   # MIS.UP.07's tolerance: half to twice
KEPT_OPEN = 0.5 * DEFAULT_TIMEOUT * (MAX_RETRIES + 1)             # half the spec's whole retry sequence
REANSWER_WITHIN = 0.5 * DEFAULT_TIMEOUT   # s: an answer, not the GCS's own resend at its timeout
WATCH_AFTER = 1.5 * DEFAULT_TIMEOUT   # s watched after an operation ended, for anything still sent
FLOAT_XY_SLACK = 64             # degE7: what float32 degrees may lose near 47 degrees (ulp ~38)
TYPED = ("MISSION_COUNT", "MISSION_REQUEST_LIST", "MISSION_ACK", "MISSION_CLEAR_ALL") + ITEMS + REQUESTS
MISSION_NAMES = TYPED + ("MISSION_SET_CURRENT",)


def check(clause_id: str) -> Callable[[Check], Check]:
    def register(fn: Check) -> Check:
        GCS_CHECKS[clause_id] = fn
        return fn
    return register


# --- the operations ---------------------------------------------------------------------------
def truncation_prone(start: int) -> int:
    """The first degE7 value from `start` that `int(degrees * 1e7)` gets wrong (1e-7 degree
    short), though the degrees are its exact decimal: about 6 % of coordinates are. A GCS
    that converts with int() instead of round() sends them changed (MAVProxy does)."""
    value = start
    while int(float(Decimal(value).scaleb(-7)) * 1e7) == value:
        value += 1
    return value


def _plan(mt: MissionType = MISSION) -> list[MissionItem]:
    """The plan of that type. A mission's coordinates are truncation-prone, and its first
    item is marked current, as a GCS's plan files have it (MAVSDK refuses a mission with no
    current item before sending anything)."""
    if mt is not MISSION:
        return plans.plan(mt)
    items = [replace(i, x=truncation_prone(i.x), y=truncation_prone(i.y)) for i in plans.mission(N)]
    return [replace(items[0], current=1)] + items[1:]


def _upload(mt: MissionType = MISSION) -> Job:
    return Job("upload", mt, tuple(_plan(mt)))


def _download(mt: MissionType = MISSION) -> Job:
    return Job("download", mt)


def _stored(mt: MissionType = MISSION, items: list[MissionItem] | None = None) -> dict[MissionType, list]:
    return {mt: _plan(mt) if items is None else items}


def clean_upload(h: GcsHarness) -> Operation:
    return h.observe("clean upload", _upload())


def clean_download(h: GcsHarness) -> Operation:
    return h.observe("clean download", _download(), plans=_stored())


def silent_to_count(h: GcsHarness) -> Operation:
    return h.observe("silent to MISSION_COUNT", _upload(),
                     rules=[Deaf(named("MISSION_COUNT"), times=None, what="every MISSION_COUNT")])


# --- judging helpers --------------------------------------------------------------------------
def fail(h: GcsHarness, op: Operation, event: Event | None, text: str) -> ClauseFailed:
    h.decide(op, event)
    return ClauseFailed(text)


def mission_sent(op: Operation) -> list[Event]:
    """What the GCS sent of the Mission Protocol (not its commands: MAVSDK asks for
    AUTOPILOT_VERSION on connect, MAVProxy for the home position every 2 s)."""
    return [e for e in op.sent() if e.msg._type.startswith("MISSION_")]


def names(events: list[Event]) -> str:
    shown = ", ".join(_short(e.msg) for e in events[:8])
    return (shown + (", ..." if len(events) > 8 else "")) or "nothing"


def _short(msg: Any) -> str:
    seq = getattr(msg, "seq", None)
    return msg._type + (f" {seq}" if seq is not None and msg._type != "MISSION_COUNT" else "")


def item_diff(got: MissionItem | Any, want: MissionItem, slack: int = 0) -> str | None:
    """How a sent item differs from the planned one (None: it does not); `current` is the
    GCS's to set, and x/y may differ by `slack` (the float form's rounding)."""
    if not isinstance(got, MissionItem):
        return "its x/y cannot be an int32"
    diffs = []
    for name in ("frame", "command", "autocontinue"):
        if getattr(got, name) != getattr(want, name):
            diffs.append(f"{name} {getattr(got, name)} (planned {getattr(want, name)})")
    for name in ("param1", "param2", "param3", "param4", "z"):
        a, b = getattr(got, name), getattr(want, name)
        if not (a == b or (a != a and b != b)):
            diffs.append(f"{name} {a:g} (planned {b:g})")
    for name in ("x", "y"):
        if abs(getattr(got, name) - getattr(want, name)) > slack:
            diffs.append(f"{name} {getattr(got, name)} (planned {getattr(want, name)})")
    return ", ".join(diffs) or None


def plan_diff(got: tuple[MissionItem, ...] | None, want: list[MissionItem]) -> str | None:
    if got is None:
        return "the GCS reported no items"
    if len(got) != len(want):
        return f"{len(got)} items, the vehicle holds {len(want)}"
    for a, b in zip(got, want):
        diff = item_diff(a, b)
        if diff:
            return f"item {b.seq}: {diff}"
    return None


def require_success(h: GcsHarness, op: Operation, what: str) -> None:
    if not op.result.ok:
        raise fail(h, op, op.sent()[-1] if op.sent() else None, f"{what}, but {op.result.line()}")


def require_failure(h: GcsHarness, op: Operation, what: str) -> None:
    if not op.result.ended:
        raise fail(h, op, op.sent()[-1] if op.sent() else None,
                   f"{what}; the GCS never ended the operation ({op.result.said})")
    if op.result.ok:
        raise fail(h, op, op.sent()[-1] if op.sent() else None, f"{what}, but {op.result.line()}")


def answer_after(op: Operation, request: Event, names_: tuple[str, ...]) -> Event | None:
    """The first item the GCS sent after `request` with the request's seq."""
    return next((e for e in op.after(request, *names_) if e.msg.seq == request.msg.seq), None)


def first_told(op: Operation, *names_: str, **fields: Any) -> Event | None:
    return next((e for e in op.told(*names_) if all(getattr(e.msg, k) == v for k, v in fields.items())), None)


def scripted(op: Operation, what: str, *names_: str, **fields: Any) -> Event:
    """The vehicle's scripted move the check is about; if the GCS never led the vehicle to
    it, the clause is undecided, not failed (another clause judges what the GCS did)."""
    event = first_told(op, *names_, **fields)
    if event is None:
        raise PreconditionFailed(f"the GCS never led the vehicle to send {what}; it sent "
                                 f"{names(mission_sent(op))} ({op.result.line()})")
    return event


# --- upload -------------------------------------------------------------------------------------
@check("MIS.G.UP.01")
def count_first(h: GcsHarness) -> str:
    op = clean_upload(h)
    sent = mission_sent(op)
    if not sent:
        raise fail(h, op, None, f"the GCS sent no mission message ({op.result.line()})")
    first = sent[0]
    if first.msg._type != "MISSION_COUNT":
        raise fail(h, op, first, f"the upload began with {names(sent[:1])}, not MISSION_COUNT")
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
            raise fail(h, op, request, f"{_short(request.msg)} got no item with seq {request.msg.seq}; "
                                       f"the GCS sent {names(op.after(request, *MISSION_NAMES))}")
        if answer.msg._type not in forms:
            raise fail(h, op, answer, f"{_short(request.msg)} was answered by {answer.msg._type}, "
                                      f"not {' or '.join(forms)}")
        diff = item_diff(m.item_from_message(answer.msg), plan[request.msg.seq], slack)
        if diff:
            raise fail(h, op, answer, f"{_short(answer.msg)} is not the planned item: {diff}")
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
    op = h.run(_upload(), request_float=True)
    return _answers(h, op, slack=FLOAT_XY_SLACK, forms=ITEMS)


@check("MIS.G.UP.04")
def repeated_request(h: GcsHarness) -> str:
    last = N - 1
    op = h.run(_upload(), rules=[Deaf(named(*ITEMS, seq=last), rerequest_after=0.25,
                                      what=f"item {last}; requested again 250 ms later")])
    repeat = [e for e in op.told(*REQUESTS) if e.msg.seq == last][1:]
    if not repeat:
        raise fail(h, op, None, f"the vehicle never got to repeat its request ({op.result.line()})")
    answer = answer_after(op, repeat[0], ITEMS)
    if answer is None or answer.t - repeat[0].t > REANSWER_WITHIN:
        late = "" if answer is None else (f" within {REANSWER_WITHIN:g} s (the item came {answer.t - repeat[0].t:.1f} s "
                                          "later: the GCS's own resend, not an answer)")
        raise fail(h, op, repeat[0], f"the repeated {_short(repeat[0].msg)} got no answer{late}; the GCS sent "
                                     f"{names(op.after(repeat[0], *MISSION_NAMES))} ({op.result.line()})")
    require_success(h, op, f"the repeated request for item {last} was answered")
    h.decide(op, answer)
    return Measured("the repeated request for the last item was answered after <s> s",
                    s=f"{answer.t - repeat[0].t:.3f}")


@check("MIS.G.UP.05")
def last_item_resent(h: GcsHarness) -> str:
    op = h.run(_upload(), rules=[Swap(named("MISSION_ACK", type=MissionResult.ACCEPTED), what="final ACK lost",
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
    op = h.run(_upload(), rules=[Deaf(named("MISSION_COUNT"), what="the first MISSION_COUNT")])
    counts = op.sent("MISSION_COUNT")
    if len(counts) < 2:
        raise fail(h, op, counts[0], f"MISSION_COUNT was sent once and never again when the vehicle did not "
                                     f"answer ({op.result.line()})")
    require_success(h, op, "MISSION_COUNT was resent")
    h.decide(op, counts[1])
    return Measured("MISSION_COUNT resent after <s> s", s=f"{counts[1].t - counts[0].t:.3f}")


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
    op = h.run(_upload(), after=WATCH_AFTER,
               rules=[Swap(named(*REQUESTS, seq=0), what="MISSION_ACK NO_SPACE",
                           instead=lambda reply, v: [m.ack_message(MissionResult.NO_SPACE, MISSION, v.target)])])
    nack = scripted(op, "its NO_SPACE", "MISSION_ACK")
    items = op.after(nack, *ITEMS)
    if items:
        raise fail(h, op, items[0], f"{_short(items[0].msg)} was sent after the vehicle's NO_SPACE")
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
                raise fail(h, op, e, f"{_short(e.msg)} was sent "
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
        raise fail(h, op, items[0], f"{_short(items[0].msg)} was sent for an empty plan")
    require_success(h, op, "MISSION_COUNT 0 was accepted")
    h.decide(op, first_told(op, "MISSION_ACK"))
    return "MISSION_COUNT 0, accepted"


# --- download -------------------------------------------------------------------------------------
@check("MIS.G.DN.01")
def request_list_first(h: GcsHarness) -> str:
    op = clean_download(h)
    sent = mission_sent(op)
    if not sent:
        raise fail(h, op, None, f"the GCS sent no mission message ({op.result.line()})")
    first = sent[0]
    h.decide(op, first)
    if first.msg._type != "MISSION_REQUEST_LIST" or first.msg.mission_type != MISSION:
        raise ClauseFailed(f"the download began with {_short(first.msg)}"
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
            raise fail(h, op, request, f"{_short(request.msg)} was sent before item {previous.msg.seq} came")
    require_success(h, op, "every item was requested in order")
    diff = plan_diff(op.result.items, _plan())
    if diff:
        raise fail(h, op, requests[-1], f"the plan the GCS reported is not the vehicle's: {diff}")
    h.decide(op, requests[-1])
    return f"items 0..{N - 1} requested in order; the plan got is the vehicle's"


@check("MIS.G.DN.03")
def request_list_resent(h: GcsHarness) -> str:
    op = h.run(_download(), plans=_stored(), rules=[Deaf(named("MISSION_REQUEST_LIST"), what="the first MISSION_REQUEST_LIST")])
    lists = op.sent("MISSION_REQUEST_LIST")
    if len(lists) < 2:
        raise fail(h, op, lists[0] if lists else None,
                   f"MISSION_REQUEST_LIST was sent {len(lists)} time(s): never again when the vehicle did not "
                   f"answer ({op.result.line()})")
    require_success(h, op, "MISSION_REQUEST_LIST was resent")
    h.decide(op, lists[1])
    return Measured("MISSION_REQUEST_LIST resent after <s> s", s=f"{lists[1].t - lists[0].t:.3f}")


@check("MIS.G.DN.04")
def item_request_resent(h: GcsHarness) -> str:
    op = h.run(_download(), plans=_stored(), rules=[Swap(named(*ITEMS, seq=1), what="item 1 lost")])
    asked = [e for e in op.sent(*REQUESTS) if e.msg.seq == 1]
    if len(asked) < 2:
        raise fail(h, op, asked[0] if asked else None,
                   f"item 1 was requested {len(asked)} time(s): never again when it did not come "
                   f"({op.result.line()})")
    require_success(h, op, "the request for item 1 was resent")
    h.decide(op, asked[1])
    return Measured("the request for item 1 was resent after <s> s", s=f"{asked[1].t - asked[0].t:.3f}")


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
    op = h.run(_download(), plans=_stored(items=[]))
    _final_ack(h, op, scripted(op, "MISSION_COUNT 0", "MISSION_COUNT"), "MISSION_COUNT 0")
    require_success(h, op, "the empty plan was acknowledged")
    if op.result.items:
        raise ClauseFailed(f"the GCS reported {len(op.result.items)} items for an empty plan")
    return "MISSION_ACK ACCEPTED after MISSION_COUNT 0; an empty plan reported"


@check("MIS.G.DN.07")
def out_of_sequence_item(h: GcsHarness) -> str:
    plan = _plan()
    op = h.run(_download(), plans=_stored(), rules=[Swap(
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


def _ended_by(h: GcsHarness, op: Operation, code: MissionResult) -> str:
    ack = scripted(op, f"its {code.name}", "MISSION_ACK")
    later = op.after(ack, *REQUESTS, *ITEMS, "MISSION_REQUEST_LIST", "MISSION_COUNT")
    if later:
        raise fail(h, op, later[0], f"{_short(later[0].msg)} was sent after the vehicle's {code.name}")
    require_failure(h, op, f"the vehicle answered with MISSION_ACK {code.name}")
    h.decide(op, ack)
    return f"nothing sent after {code.name}; {op.result.line()}"


@check("MIS.G.DN.08")
def error_ack_ends_download(h: GcsHarness) -> str:
    op = h.run(_download(), plans=_stored(), after=WATCH_AFTER, rules=[Swap(
        named(*ITEMS, seq=1), what="MISSION_ACK ERROR",
        instead=lambda reply, v: [m.ack_message(MissionResult.ERROR, MISSION, v.target)])])
    return _ended_by(h, op, MissionResult.ERROR)


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
    op = h.run(_download(), plans=_stored(),
               rules=[Deaf(named("MISSION_REQUEST_LIST"), times=None, what="every MISSION_REQUEST_LIST")])
    lists = op.sent("MISSION_REQUEST_LIST")
    require_failure(h, op, f"the vehicle never answered any of {len(lists)} MISSION_REQUEST_LIST")
    h.decide(op, lists[-1])
    return Measured(f"given up after {len(lists)} MISSION_REQUEST_LIST, <s> s", s=f"{op.result.at - op.started:.1f}")


# --- timeouts and retries ---------------------------------------------------------------------------
@check("MIS.G.TO.01")
def resend_timeout(h: GcsHarness) -> str:
    op = silent_to_count(h)
    counts = op.sent("MISSION_COUNT")
    if len(counts) < 2:
        raise fail(h, op, counts[0], "MISSION_COUNT was never resent: the GCS has no resend timeout "
                                     f"({op.result.line()})")
    gaps = [b.t - a.t for a, b in zip(counts, counts[1:])]
    median = statistics.median(gaps)
    low, high = ACCEPTED_TIMEOUT
    h.decide(op, counts[1])
    text = Measured(f"MISSION_COUNT resent every <ms> ms (median of {len(gaps)}); expected about "
                    f"{DEFAULT_TIMEOUT * 1000:.0f} ms (accepted: {low * 1000:.0f}-{high * 1000:.0f} ms)",
                    ms=f"{median * 1000:.0f}")
    if not low <= median <= high:
        raise ClauseFailed(text)
    return text


@check("MIS.G.TO.02")
def retry_limit(h: GcsHarness) -> str:
    op = silent_to_count(h)
    counts = op.sent("MISSION_COUNT")
    resends = len(counts) - 1
    h.decide(op, counts[-1])
    if resends > MAX_RETRIES:
        raise ClauseFailed(f"MISSION_COUNT was resent {resends} times"
                           + ("" if op.result.ended else " and the GCS was still sending when stopped")
                           + f"; expected at most {MAX_RETRIES}")
    return f"MISSION_COUNT resent {resends} times (at most {MAX_RETRIES})"


@check("MIS.G.TO.03")
def kept_open(h: GcsHarness) -> str:
    op = h.run(_upload(), rules=[Mute(named(*ITEMS, seq=0), what="after item 0")])
    told = op.told()
    last = told[-1] if told else op.sent()[0]
    if not op.result.ended:
        h.decide(op, last)
        return f"the upload was still open when stopped after {h.timeout_s:g} s"
    open_for = op.result.at - last.t
    h.decide(op, (mission_sent(op) or op.sent())[-1])
    text = Measured(f"the GCS gave the upload up <s> s after the vehicle's last message; the spec's timeouts "
                    f"and retries keep it open {DEFAULT_TIMEOUT * (MAX_RETRIES + 1):g} s (accepted: from "
                    f"{KEPT_OPEN:g} s)", s=f"{open_for:.1f}")
    if open_for < KEPT_OPEN:
        raise ClauseFailed(text)
    return text


# --- plan types --------------------------------------------------------------------------------------
@check("MIS.G.TY.01")
def typed_and_v2(h: GcsHarness) -> str:
    ops = [h.run(_upload(FENCE)), h.run(_download(RALLY), plans=_stored(RALLY))]
    for op in ops:
        mt = op.job.mission_type
        for e in op.sent(*TYPED):
            if e.version != 2:
                raise fail(h, op, e, f"{_short(e.msg)} of a {mt.label} {op.job.op} went as MAVLink {e.version}: "
                                     "mission_type is a MAVLink 2 extension")
            if e.msg.mission_type != mt:
                raise fail(h, op, e, f"{_short(e.msg)} of a {mt.label} {op.job.op} carries mission_type "
                                     f"{e.msg.mission_type}, not {int(mt)}")
    return "fence upload and rally download: every message MAVLink 2 with its mission_type"


@check("MIS.G.TY.02")
def other_type_request(h: GcsHarness) -> str:
    # the fence's request comes first, in place of the mission's first one: an item the GCS
    # sends before the mission's own request can only be its answer to the fence's (a GCS
    # that floods items answers a request too, just with more than it asked for)
    op = h.run(_upload(), rules=[Swap(
        named("MISSION_REQUEST_INT", seq=0, mission_type=MISSION), then_after=0.5,
        what="MISSION_REQUEST_INT 0 of the fence; the mission's 500 ms later",
        instead=lambda reply, v: [m.request_message(0, FENCE, v.target)])])
    odd = scripted(op, "the fence's request", "MISSION_REQUEST_INT", mission_type=FENCE)
    proper = first_told(op, "MISSION_REQUEST_INT", seq=0, mission_type=MISSION)
    answered = [e for e in op.after(odd, *ITEMS) if e.msg.seq == 0 and (proper is None or e.t < proper.t)]
    if answered:
        raise fail(h, op, answered[0], f"the fence's request for item 0 was answered with {_short(answered[0].msg)} "
                                       f"(mission_type {answered[0].msg.mission_type}) during a mission upload")
    h.decide(op, odd)
    return "the fence's request was not answered with an item"


@check("MIS.G.TY.03")
def other_type_ack(h: GcsHarness) -> str:
    op = h.run(_upload(), rules=[Swap(
        named("MISSION_REQUEST_INT", seq=1, mission_type=MISSION), then_after=0.2,
        what="MISSION_ACK ACCEPTED of the rally points; the request 200 ms later",
        instead=lambda reply, v: [m.ack_message(MissionResult.ACCEPTED, RALLY, v.target)])])
    odd = scripted(op, "the rally ACK", "MISSION_ACK", mission_type=RALLY)
    h.decide(op, odd)
    rest = [e.msg.seq for e in op.after(odd, *ITEMS)]
    if not op.result.ok or not {1, 2} <= set(rest):
        raise ClauseFailed(f"after a rally MISSION_ACK mid-upload the GCS sent items {rest} and "
                           f"{op.result.line()}: the other type's ACK ended the mission upload")
    return "the rally ACK was ignored; the mission upload went on and succeeded"


@check("MIS.G.TY.04")
def other_type_item(h: GcsHarness) -> str:
    plan, fence = _plan(), plans.fence()
    op = h.run(_download(), plans=_stored(), rules=[Swap(
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


# --- cancellation ------------------------------------------------------------------------------------
@check("MIS.G.CN.01")
def cancel_honoured(h: GcsHarness) -> str:
    op = h.run(_download(), plans=_stored(), after=WATCH_AFTER, rules=[Swap(
        named(*ITEMS, seq=1), what="MISSION_ACK OPERATION_CANCELLED",
        instead=lambda reply, v: [m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, v.target)])])
    return _ended_by(h, op, MissionResult.OPERATION_CANCELLED)


# --- clear ---------------------------------------------------------------------------------------------
@check("MIS.G.CL.01")
def clear_sent(h: GcsHarness) -> str:
    op = h.run(Job("clear", MISSION), plans=_stored())
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
    op = h.run(Job("clear", MISSION), plans=_stored(),
               rules=[Deaf(named("MISSION_CLEAR_ALL"), what="the first MISSION_CLEAR_ALL")])
    clears = op.sent("MISSION_CLEAR_ALL")
    if len(clears) < 2:
        raise fail(h, op, clears[0] if clears else None,
                   f"MISSION_CLEAR_ALL was sent {len(clears)} time(s): never again when the vehicle did not "
                   f"answer ({op.result.line()})")
    require_success(h, op, "MISSION_CLEAR_ALL was resent")
    h.decide(op, clears[1])
    return Measured("MISSION_CLEAR_ALL resent after <s> s", s=f"{clears[1].t - clears[0].t:.3f}")


@check("MIS.G.CL.03")
def clear_refused(h: GcsHarness) -> str:
    op = h.run(Job("clear", MISSION), plans=_stored(), rules=[Swap(
        named("MISSION_ACK", type=MissionResult.ACCEPTED), what="MISSION_ACK ERROR",
        instead=lambda reply, v: [m.ack_message(MissionResult.ERROR, MISSION, v.target)])])
    require_failure(h, op, "the vehicle answered MISSION_CLEAR_ALL with ERROR")
    h.decide(op, first_told(op, "MISSION_ACK"))
    return f"{op.result.line()}"


# --- set current -------------------------------------------------------------------------------------
SET_CURRENT_SEQ = 2


def _set_current(h: GcsHarness) -> Operation:
    return h.observe("set current", Job("set-current", MISSION, seq=SET_CURRENT_SEQ),
                     plans=_stored(items=plans.mission(5)), after=WATCH_AFTER)


def _set_current_messages(op: Operation) -> list[Event]:
    return [e for e in op.sent("MISSION_SET_CURRENT", "COMMAND_LONG")
            if e.msg._type == "MISSION_SET_CURRENT" or e.msg.command == 224]


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
