"""Idle and cancellation (seed 000, "Canceling Operations"): MIS.IDL.01, MIS.CAN.*

A GCS cancels by answering a request with MISSION_ACK OPERATION_CANCELLED; both ends then
return to idle, where a stray request or item is ignored or refused ("may respond with an
appropriate error for that state"), and a cancelled upload leaves the stored plan as it was.
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.frame import Frame

from ..harness import plans, procedures
from ..harness.match import ITEMS, ack, msg, request
from ..harness.measured import Measured
from ..harness.sentinel import answers_before_sentinel, brief
from ..harness.tester import Tester
from ..outcome import ClauseFailed, PreconditionFailed
from ..session import Session
from . import check
from .upload import silence_window

MISSION = MissionType.MISSION
MT = int(MISSION)
RETRIES = procedures.RETRIES
CANCELLED = MissionResult.OPERATION_CANCELLED
# How long requests must stay away after a cancel: the spec's default timeout, so a vehicle
# that ignored the cancel has resent its request even with a 1 s item timeout (ArduPilot's).
AFTER_CANCEL_WINDOW = 1.5
LET_GO_WAIT = 12.0        # s a vehicle that ignores the cancel may take to give the upload up (ArduPilot: 8 s)


def _partial_upload(t: Tester, items: list[MissionItem], answered: int) -> None:
    """Start an upload of `items`, answer the first `answered` requests and wait for the next."""
    t.mark()
    t.send(m.count_message(len(items), MISSION, t.target))
    for seq in range(answered):
        procedures.setup_expect(t, request(seq, mission_type=MT), "an upload runs")
        t.send(m.item_message(items[seq], t.target))
    procedures.setup_expect(t, request(answered, mission_type=MT), "an upload runs")


@check("MIS.IDL.01")
def stray_item_or_request_not_accepted(s: Session) -> None:
    t = s.t
    old = plans.mission(2, variant=60)
    procedures.ensure_plan(t, old, MISSION)
    stray = plans.mission(2, variant=61)
    t.mark()
    t.note("the upload is over, so the vehicle is idle: a MISSION_ITEM_INT 0 with no MISSION_COUNT "
           "before it")
    t.send(m.item_message(stray[0], t.target))
    _judge_stray_answers(t, "a stray MISSION_ITEM_INT 0")
    held = procedures.stored(t, MISSION)   # a download ended by the GCS's ACK: idle again
    read = t.decided_by   # where `held` was read, for a verdict about it
    t.mark()
    t.note("the download is over, so the vehicle is idle: a MISSION_REQUEST_INT 1 with no "
           "MISSION_REQUEST_LIST before it")
    t.send(m.request_message(1, MISSION, t.target))
    _judge_stray_answers(t, "a stray MISSION_REQUEST_INT 1")
    if any(procedures.comparable(it, t.form) == procedures.comparable(stray[0], t.form) for it in held):
        t.decided_by = read
        raise ClauseFailed("a stray MISSION_ITEM_INT 0 sent in idle is now in the stored plan; expected it "
                           "to be ignored or refused")
    if not procedures.same_plan(held, old, t.form):
        raise PreconditionFailed(f"the vehicle holds {len(held)} items, not the {len(old)}-item plan it "
                                 "accepted before the stray item (MIS.UP.04 judges that)")


def _judge_stray_answers(t: Tester, what: str) -> None:
    for frame in answers_before_sentinel(t):
        got = frame.msg
        if getattr(got, "mission_type", MT) != MT:
            continue
        if got._type == "MISSION_ACK" and got.type == MissionResult.ACCEPTED:
            t.decided_by_frame(frame)
            raise ClauseFailed(f"{what} in idle was answered MISSION_ACK ACCEPTED; expected no answer or "
                               "an error MISSION_ACK")
        if got._type in ITEMS:
            t.decided_by_frame(frame)
            raise ClauseFailed(f"{what} in idle was answered {brief(got)}, as if a download were running; "
                               "expected no answer or an error MISSION_ACK")
        if got._type in ("MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_COUNT"):
            t.decided_by_frame(frame)
            raise ClauseFailed(f"{what} in idle drew {brief(got)}: the vehicle took it as part of a "
                               "transfer; expected no answer or an error MISSION_ACK")


@dataclass
class CancelledUpload:
    old: list[MissionItem]
    late_requests: list[tuple[float, int]]   # (s after the cancel, seq) of requests that still came
    stored: list[MissionItem]
    window: float                            # how long requests were watched for (unscaled s)
    first_late: Frame | None = None          # the first late request's frame: it decides MIS.CAN.01


def cancelled_upload(s: Session) -> CancelledUpload:
    window = silence_window(s, AFTER_CANCEL_WINDOW)   # measured outside the shared observation
    return s.shared("cancelled_upload", lambda: _observe_cancelled_upload(s.t, window))


def _observe_cancelled_upload(t: Tester, window: float) -> CancelledUpload:
    procedures.ensure_plan(t, plans.mission(3, variant=62), MISSION)
    old = procedures.stored(t, MISSION)
    _partial_upload(t, plans.mission(3, variant=63), answered=2)
    t.note("the GCS answers the request for item 2 with MISSION_ACK OPERATION_CANCELLED")
    t.send(m.ack_message(CANCELLED, MISSION, t.target))
    seen = t.collect(request(mission_type=MT), window)
    late = [(dt, f.msg.seq) for dt, f in seen]
    if late:   # make sure it is over before reading the plan back: wait (bounded) until it gives the
        # upload up or stops asking, and only then, if it is still at it, cancel again; anything
        # sent sooner would race its own give-up, which may come as the window closes
        opened = t.now()
        rest = t.collect(request(mission_type=MT) | ack(mission_type=MT), LET_GO_WAIT,
                         stop=ack(mission_type=MT), quiet=window)
        if not rest or (rest[-1][1].msg._type != "MISSION_ACK" and t.now() - opened >= LET_GO_WAIT * t.scale):
            t.send(m.ack_message(CANCELLED, MISSION, t.target))
    return CancelledUpload(old, late, procedures.stored(t, MISSION), window,
                           seen[0][1] if seen else None)


@check("MIS.CAN.01")
def cancel_stops_upload_requests(s: Session) -> None:
    obs = cancelled_upload(s)
    if obs.late_requests:
        dt, seq = obs.late_requests[0]
        s.t.decided_by_frame(obs.first_late)
        raise ClauseFailed(Measured(
            f"after MISSION_ACK OPERATION_CANCELLED the vehicle kept requesting: "
            f"{len(obs.late_requests)} request(s) in <window> s, "
            f"the first for item {seq} after <after> s; expected none",
            window=f"{obs.window * s.scale:g}", after=f"{dt:.3f}"))   # the window follows its retries


@check("MIS.CAN.02")
def cancelled_upload_keeps_plan(s: Session) -> None:
    obs = cancelled_upload(s)
    procedures.require_same_plan(obs.stored, obs.old, "after an upload cancelled at item 2 of 3", s.t.form)


@check("MIS.CAN.03")
def cancel_ends_download(s: Session) -> None:
    t, t2 = s.t, s.second()
    procedures.ensure_plan(t, plans.mission(3, variant=64), MISSION)
    t.mark()
    opened = procedures.open_download(t, MISSION, resends=0)
    if opened is None:
        raise PreconditionFailed("setup: a download starts: no MISSION_COUNT came (MIS.DN.01 judges that)")
    count = opened.msg.count
    if count == 0:
        t.send(m.ack_message(MissionResult.ACCEPTED, MISSION, t.target))   # even an empty download is ended
        raise PreconditionFailed("the vehicle reports an empty plan after accepting a 3-item upload, so "
                                 "there is no download to cancel (MIS.UP.04 judges that)")
    t.send(m.request_message(0, MISSION, t.target))
    procedures.setup_expect(t, msg(ITEMS, seq=0, mission_type=MT), "a download serves item 0")
    t.note("the GCS cancels its download after item 0; then a second GCS asks for the plan")
    t.send(m.ack_message(CANCELLED, MISSION, t.target))
    t2.mark()
    t2.send(m.request_list_message(MISSION, t2.target))
    frame = t2.expect(msg("MISSION_COUNT", mission_type=MT) | ack(mission_type=MT))
    got = frame.msg
    if got._type == "MISSION_ACK":
        t.send(m.ack_message(MissionResult.ACCEPTED, MISSION, t.target))   # end it for the clauses after
        raise ClauseFailed(f"after the first GCS cancelled its download, the second GCS's "
                           f"MISSION_REQUEST_LIST was answered {procedures.result_name(got.type)}: the "
                           "vehicle still held the cancelled download; expected MISSION_COUNT")
    t2.send(m.ack_message(MissionResult.ACCEPTED, MISSION, t2.target))   # even an empty download is ended


@check("MIS.CAN.04")
def new_upload_after_cancel_starts_at_0(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=67), MISSION)
    before = procedures.stored(t, MISSION)
    cancelled = plans.mission(3, variant=65)
    _partial_upload(t, cancelled, answered=2)
    t.note("the GCS cancels at item 2, then starts a new upload with the same count")
    t.send(m.ack_message(CANCELLED, MISSION, t.target))
    answers_before_sentinel(t)   # let any request already on its way arrive first
    items = plans.mission(3, variant=66)
    t.mark()
    first = procedures.send_count(t, len(items), MISSION, request(mission_type=MT) | ack(mission_type=MT))
    if first.msg._type == "MISSION_ACK":
        raise ClauseFailed(f"after a cancelled upload, a new MISSION_COUNT was answered "
                           f"{procedures.result_name(first.msg.type)}; expected a request for item 0")
    if first.msg.seq != 0:
        t.send(m.ack_message(CANCELLED, MISSION, t.target))
        raise ClauseFailed(f"after a cancelled upload, a new MISSION_COUNT drew a request for item "
                           f"{first.msg.seq}; expected item 0 (a new upload starts afresh)")
    frame = _finish_upload(t, items)
    if frame is None:
        raise PreconditionFailed("the new upload drew no final MISSION_ACK (MIS.UP.03 judges that)")
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"the new upload after a cancelled one ended with "
                           f"{procedures.result_name(frame.msg.type)}; expected MAV_MISSION_ACCEPTED")
    procedures.judge_stored(t, items, before, "after a new upload that followed a cancelled one")


def _finish_upload(t: Tester, items: list[MissionItem]):
    """Answer item 0 and every later mission request; the final mission MISSION_ACK, or None
    if the vehicle falls silent first."""
    t.send(m.item_message(items[0], t.target))
    return procedures.serve_upload(t, items)
