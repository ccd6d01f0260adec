"""Several GCSs and addressing: MIS.GCS.*

A transfer belongs to the GCS that started it (upstream MAV_MISSION_DENIED: "Not accepting
any mission commands from this communication partner"); another GCS's messages must
neither join nor end it. A message addressed to another system is not ours to act on
(seed 001, routing). The second GCS is `s.second()`: another system id on its own socket.
"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import plans, procedures
from ..harness.match import ack, request
from ..harness.sentinel import answers_before_sentinel, brief
from ..harness.tester import Tester
from ..outcome import ClauseFailed, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
MT = int(MISSION)
RETRIES = procedures.RETRIES


def _drive(t: Tester, items: list[MissionItem]):
    """Answer the vehicle's mission requests until it ends the upload: its MISSION_ACK,
    or the clause fails on silence."""
    reply = request(mission_type=MT) | ack(mission_type=MT)
    last_sent = False
    for _ in range((len(items) + 2) * (RETRIES + 2)):
        frame = t.poll_for(reply, t.timings.default_timeout)
        if frame is None:
            if last_sent:
                raise PreconditionFailed("the last item drew no MISSION_ACK (MIS.UP.03 judges that)")
            raise ClauseFailed(f"the first GCS's upload went silent: no request or MISSION_ACK within "
                               f"{t.reply_timeout:g} s")
        if frame.msg._type == "MISSION_ACK":
            return frame
        if 0 <= frame.msg.seq < len(items):
            t.send(m.item_message(items[frame.msg.seq], t.target))
            last_sent = last_sent or frame.msg.seq == len(items) - 1
    raise ClauseFailed("the first GCS's upload never ended")


@check("MIS.GCS.01")
def second_gcs_count_denied(s: Session) -> None:
    t, t2 = s.t, s.second()
    t.mark()
    t.send(m.count_message(3, MISSION, t.target))
    procedures.setup_expect(t, request(mission_type=MT), "the first GCS starts an upload")
    t.note("the first GCS's upload is running; the second GCS sends MISSION_COUNT")
    t2.mark()
    t2.send(m.count_message(2, MISSION, t2.target))
    frame = t2.expect(ack(mission_type=MT) | request(mission_type=MT))
    t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
    got = frame.msg
    if got._type != "MISSION_ACK":
        t2.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t2.target))
        raise ClauseFailed(f"while the first GCS's upload was running, the second GCS's MISSION_COUNT "
                           f"was answered {got._type}{{seq={got.seq}}}: a second upload was started; "
                           "expected MISSION_ACK MAV_MISSION_DENIED")
    if got.type != MissionResult.DENIED:
        raise ClauseFailed(f"while the first GCS's upload was running, the second GCS's MISSION_COUNT "
                           f"was answered {procedures.result_name(got.type)}; expected MAV_MISSION_DENIED")


@check("MIS.GCS.02")
def second_gcs_does_not_disturb_upload(s: Session) -> None:
    t, t2 = s.t, s.second()
    procedures.ensure_plan(t, plans.mission(2, variant=50), MISSION)
    before = procedures.stored(t, MISSION)
    items = plans.mission(3, variant=51)
    theirs = plans.mission(3, variant=52)
    t.mark()
    t.send(m.count_message(len(items), MISSION, t.target))
    procedures.setup_expect(t, request(0, mission_type=MT), "the first GCS starts an upload")
    t.send(m.item_message(items[0], t.target))
    procedures.setup_expect(t, request(1, mission_type=MT), "the first GCS's upload goes on to item 1")
    t.note("the second GCS sends MISSION_COUNT, MISSION_REQUEST_LIST, MISSION_ITEM_INT 1, "
           "MISSION_REQUEST_INT 0 and MISSION_ACK OPERATION_CANCELLED, all for the mission plan")
    t2.mark()
    for message in (m.count_message(len(theirs), MISSION, t2.target),
                    m.request_list_message(MISSION, t2.target),
                    m.item_message(theirs[1], t2.target),
                    m.request_message(0, MISSION, t2.target),
                    m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t2.target)):
        t2.send(message)
    t.send(m.item_message(items[1], t.target))
    frame = _drive(t, items)
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"after another GCS's mission messages, the first GCS's upload ended with "
                           f"{procedures.result_name(frame.msg.type)}; expected MAV_MISSION_ACCEPTED")
    procedures.judge_stored(t, items, before, "after an upload another GCS talked into")


@check("MIS.GCS.03")
def other_system_messages_ignored(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=53), MISSION)
    old = procedures.stored(t, MISSION)
    system, component = t.target
    other = (200 if system != 200 else 201, component)
    new = plans.mission(2, variant=54)
    t.mark()
    t.note(f"mission messages addressed to system {other[0]} (the target is system {system})")
    for message in (m.count_message(len(new), MISSION, other),
                    m.item_message(new[0], other),
                    m.request_list_message(MISSION, other),
                    m.request_message(0, MISSION, other),
                    m.clear_all_message(MISSION, other)):
        t.send(message)
    replies = answers_before_sentinel(t)
    if replies:
        t.decided_by_frame(replies[0])
        raise ClauseFailed(f"messages addressed to system {other[0]} drew {brief(replies[0].msg)} from "
                           f"system {system}; expected no answer")
    procedures.require_same_plan(procedures.stored(t, MISSION), old,
                                 f"after messages addressed to system {other[0]}", t.form)



# --- MIS.GCS.04 ---------------------------------------------------------------------------

# What the second GCS sends before each of the first GCS's requests for items 1, 2, 3: the
# ACK that ends a download, a cancel, and an error. None of them is from the GCS receiving
# the data (seed 000, "Errors/Completion"), so none may end the first GCS's download.
FOREIGN_ACKS = (MissionResult.ACCEPTED, MissionResult.OPERATION_CANCELLED, MissionResult.ERROR)

from ..harness.match import ITEMS, msg  # noqa: E402  (appended section: the imports above are shared)


@check("MIS.GCS.04")
def second_gcs_ack_does_not_end_download(s: Session) -> None:
    t, t2 = s.t, s.second()
    items = plans.mission(len(FOREIGN_ACKS) + 1, variant=55)
    procedures.ensure_plan(t, items, MISSION)
    t.mark()
    opened = procedures.open_download(t, MISSION, resends=0)
    if opened is None:
        raise PreconditionFailed("setup: the first GCS starts a download: no MISSION_COUNT came "
                                 "(MIS.DN.01 judges that)")
    count = opened.msg.count
    if count != len(items):
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
        raise PreconditionFailed(f"the vehicle reported {count} items for the {len(items)}-item plan "
                                 "just uploaded (MIS.DN.01 judges that)")
    got = []
    reply = msg(ITEMS, mission_type=MT) | ack(mission_type=MT)
    for seq in range(count):
        if seq:
            code = FOREIGN_ACKS[seq - 1]
            t.note(f"the second GCS sends MISSION_ACK {procedures.result_name(code)} for the mission plan, "
                   "in the middle of the first GCS's download")
            t2.send(m.ack_message(code, MISSION, t2.target))
        t.send(m.request_message(seq, MISSION, t.target))
        frame = t.poll_for(reply, t.timings.default_timeout)
        if frame is not None and frame.msg._type != "MISSION_ACK" and frame.msg.seq == seq:
            got.append(m.item_from_message(frame.msg))
            continue
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
        if not seq:
            raise PreconditionFailed("setup: the first GCS's MISSION_REQUEST_INT 0 drew "
                                     + ("nothing" if frame is None else frame.msg._type)
                                     + " (MIS.DN.02 judges that)")
        after = (f"after the second GCS's MISSION_ACK {procedures.result_name(FOREIGN_ACKS[seq - 1])}, "
                 f"the first GCS's MISSION_REQUEST_INT {seq}")
        if frame is None:
            raise ClauseFailed(f"{after} was not answered; expected MISSION_ITEM_INT {seq} (the download "
                               "is the first GCS's)")
        if frame.msg._type == "MISSION_ACK":
            raise ClauseFailed(f"{after} was answered MISSION_ACK {procedures.result_name(frame.msg.type)}: "
                               f"the download was ended; expected MISSION_ITEM_INT {seq}")
        raise ClauseFailed(f"{after} was answered {frame.msg._type} {frame.msg.seq}; expected "
                           f"MISSION_ITEM_INT {seq}")
    t.send(m.ack_message(MissionResult.ACCEPTED, MISSION, t.target))
    if None in got or procedures.same_plan(got, items, t.form):
        return   # an unreadable item is MIS.DN.02's to judge
    # Not the uploaded plan: disturbed, or just what this vehicle serves (MIS.DN.02's case)?
    clean = procedures.stored(t, MISSION)
    if not procedures.same_plan(got, clean, t.form):
        procedures.require_same_plan(got, clean, "the download another GCS's MISSION_ACKs were sent "
                                     "into served other items than an undisturbed download", t.form)
