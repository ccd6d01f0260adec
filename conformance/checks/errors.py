"""Errors and completion (seed 000, "Errors/Completion"): MIS.ERR.*

Every operation ends with a MISSION_ACK whose type is a MAV_MISSION_RESULT; an error ends
the operation and leaves the vehicle idle, with its plan unaltered.
"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionType

from ..harness import plans, procedures
from ..harness.match import ITEMS, REQUESTS, ack, msg
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
MT = int(MISSION)
UNKNOWN_TYPE = 230        # no MAV_MISSION_TYPE has this value
TOO_MANY = 65535          # the largest count MISSION_COUNT can carry
BEYOND = 5                # how far past the end of the list the stray request asks
RESULTS = frozenset(int(r) for r in MissionResult)


def _cancel_if_started(t: Tester, frame, mission_type: int) -> None:
    """A trigger meant to draw an error started a transfer instead: end it."""
    if frame is not None and frame.msg._type != "MISSION_ACK":
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, t.target))


def _request_beyond_list(t: Tester, n: int):
    """Open a download of the n-item mission plan and ask for item n + BEYOND: the first
    answer (an ACK or an item), or None."""
    t.mark()
    if procedures.open_download(t, MISSION, resends=0) is None:
        return None
    t.send(m.request_message(n + BEYOND, MISSION, t.target))
    frame = t.poll_for(ack(mission_type=MT) | msg(ITEMS, mission_type=MT), t.timings.default_timeout)
    if frame is None or frame.msg._type != "MISSION_ACK":
        t.send(m.ack_message(MissionResult.ACCEPTED, MISSION, t.target))   # close the download
    return frame


def _count_too_many(t: Tester):
    t.mark()
    t.send(m.count_message(TOO_MANY, MISSION, t.target))
    frame = t.poll_for(ack(mission_type=MT) | msg(REQUESTS, mission_type=MT), t.timings.default_timeout)
    _cancel_if_started(t, frame, MT)
    return frame


@check("MIS.ERR.01")
def every_ack_carries_a_result(s: Session) -> None:
    t = s.t
    triggers: list[tuple[str, int]] = []   # (what was sent, inbox index before it)

    def trigger(label: str) -> None:
        triggers.append((label, len(t.node.inbox)))

    trigger("a 2-item mission upload")
    items = plans.mission(2, variant=70)
    procedures.upload(t, items, MISSION)
    trigger(f"MISSION_COUNT with mission_type {UNKNOWN_TYPE}")
    t.mark()
    t.send(m.count_message(2, UNKNOWN_TYPE, t.target))
    frame = t.poll_for(ack() | msg(REQUESTS), t.timings.default_timeout)
    _cancel_if_started(t, frame, UNKNOWN_TYPE)
    trigger(f"MISSION_COUNT {TOO_MANY}")
    _count_too_many(t)
    trigger(f"MISSION_REQUEST_INT for item {len(items) + BEYOND} of a {len(items)}-item plan")
    _request_beyond_list(t, len(items))
    trigger("")
    acks = 0
    for (label, begin), (_, end) in zip(triggers, triggers[1:]):
        for _, frame in t.node.inbox[begin:end]:
            got = frame.msg
            if got._type != "MISSION_ACK":
                continue
            acks += 1
            if got.type not in RESULTS:
                t.decided_by_frame(frame)
                raise ClauseFailed(f"{label} drew MISSION_ACK{{type={got.type}, mission_type="
                                   f"{got.mission_type}}}: {got.type} is not a MAV_MISSION_RESULT "
                                   f"value (0..{max(RESULTS)})")
    if not acks:
        raise PreconditionFailed("none of the operations drew a MISSION_ACK, so there was no result to check")


@check("MIS.ERR.02")
def idle_after_error(s: Session) -> None:
    t, t2 = s.t, s.second()
    procedures.ensure_plan(t, plans.mission(2, variant=71), MISSION)
    old = procedures.stored(t, MISSION)
    frame = _request_beyond_list(t, len(old))
    how = f"a request for item {len(old) + BEYOND} of a {len(old)}-item plan"
    if frame is None or frame.msg._type != "MISSION_ACK" or frame.msg.type == MissionResult.ACCEPTED:
        how = f"MISSION_COUNT {TOO_MANY}"
        frame = _count_too_many(t)
    if frame is None or frame.msg._type != "MISSION_ACK" or frame.msg.type == MissionResult.ACCEPTED:
        raise NotApplicable("neither a request beyond the list nor a count beyond any capacity drew an "
                            "error MISSION_ACK, so there is no error to recover from")
    error = procedures.result_name(frame.msg.type)
    t.note(f"the vehicle answered {how} with {error}; now a second GCS uploads a new plan")
    new = plans.mission(3, variant=72)
    done = procedures.upload(t2, new, MISSION)
    if done is None:
        raise ClauseFailed(f"after the vehicle's {error} (to {how}), another GCS's upload got no "
                           "MISSION_ACK; expected the vehicle to be idle and take the upload")
    if done.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"after the vehicle's {error} (to {how}), another GCS's upload was answered "
                           f"{procedures.result_name(done.msg.type)}; expected MAV_MISSION_ACCEPTED "
                           "(the vehicle should be idle again)")
    procedures.judge_stored(t, new, old, f"after an upload that followed the vehicle's {error}")
