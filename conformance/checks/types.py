"""Plan types (seed 000, "Mission Types"): MIS.TYP.*

Mission, fence and rally plans are "stored and handled separately/independently", and every
message of a transfer says which one it is about in its mission_type field. A type the
target refuses with MAV_MISSION_UNSUPPORTED is left out (a vehicle need not store fences);
a clause needs at least the types it compares.
"""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionItem, MissionType

from ..harness import plans, procedures
from ..harness.match import ITEMS, REQUESTS, ack, msg, request
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION, FENCE = MissionType.MISSION, MissionType.FENCE
MT = int(MISSION)
UNKNOWN_TYPE = 230            # no MAV_MISSION_TYPE has this value
RETRIES = procedures.RETRIES


def put_plan(t: Tester, items: list[MissionItem], mission_type: MissionType) -> bool:
    """Store `items` as the `mission_type` plan: True, or False if the target does not
    store that type (MAV_MISSION_UNSUPPORTED). Any other failure leaves the clause undecided."""
    frame = procedures.upload(t, items, mission_type)
    if frame is not None and frame.msg.type == MissionResult.UNSUPPORTED and mission_type is not MISSION:
        return False
    crossed = procedures.other_type_answer(t, mission_type) if frame is None else None
    if crossed is not None:
        raise NotApplicable(crossed)
    if frame is None or frame.msg.type != MissionResult.ACCEPTED:
        what = "no MISSION_ACK" if frame is None else procedures.result_name(frame.msg.type)
        raise PreconditionFailed(f"setup: uploading a {len(items)}-item {mission_type.label} plan got {what}")
    return True


def stored_plans(t: Tester, variant: int) -> dict[MissionType, list[MissionItem]]:
    """Put a distinct plan of every type the target stores on it; the plans put."""
    held = {}
    for mt in PLAN_TYPES:
        items = plans.plan(mt, variant=variant)
        if put_plan(t, items, mt):
            held[mt] = items
    return held


@check("MIS.TYP.01")
def types_stored_independently(s: Session) -> None:
    t = s.t
    types = list(stored_plans(t, variant=40))
    if len(types) < 2:
        raise NotApplicable("the vehicle stores only mission plans (fence and rally were refused "
                            "as unsupported), so there is no other type to disturb")
    # compare with what downloads say, so a vehicle that stores nothing is not judged here
    held = {mt: procedures.stored(t, mt) for mt in types}
    for changed in types:
        procedures.ensure_plan(t, plans.plan(changed, variant=41), changed)
        for other in types:
            if other is not changed:
                procedures.require_same_plan(procedures.stored(t, other), held[other],
                                             f"after uploading a new {changed.label} plan, the "
                                             f"{other.label} plan changed", t.form)
        held[changed] = procedures.stored(t, changed)


@check("MIS.TYP.02")
def upload_messages_carry_type(s: Session) -> None:
    t = s.t
    for mt in PLAN_TYPES:
        items = plans.plan(mt, variant=42)
        t.mark()
        t.send(m.count_message(len(items), mt, t.target))
        requested = False
        for _ in range((len(items) + 2) * (RETRIES + 2)):
            frame = t.poll_for(msg(REQUESTS) | ack(), t.timings.default_timeout)
            if frame is None:
                raise PreconditionFailed(f"the {mt.label} upload stalled: no request or MISSION_ACK "
                                         "came within the reply timeout")
            got = frame.msg
            if got._type == "MISSION_ACK":
                if got.type == MissionResult.UNSUPPORTED and not requested and mt is not MISSION:
                    break   # the vehicle does not store this type: nothing to check
                if got.mission_type != mt:
                    raise ClauseFailed(f"the {mt.label} upload ended with MISSION_ACK{{type="
                                       f"{procedures.result_name(got.type)}, mission_type="
                                       f"{got.mission_type}}}; expected mission_type={int(mt)}")
                break
            if got.mission_type != mt:
                raise ClauseFailed(f"during a {mt.label} upload the vehicle sent {got._type}{{seq="
                                   f"{got.seq}, mission_type={got.mission_type}}}; expected "
                                   f"mission_type={int(mt)}")
            requested = True
            if 0 <= got.seq < len(items):
                t.send(m.item_message(items[got.seq], t.target))
        else:
            raise PreconditionFailed(f"the {mt.label} upload did not end")


def _download_checked(t: Tester, mt: MissionType, want: list[MissionItem]) -> None:
    t.mark()
    frame = None
    for _ in range(RETRIES + 1):
        t.send(m.request_list_message(mt, t.target))
        frame = t.poll_for(msg("MISSION_COUNT") | ack(), t.timings.default_timeout)
        if frame is not None:
            break
    if frame is not None and frame.msg._type == "MISSION_COUNT" and frame.msg.mission_type == mt:
        frame = procedures.fresh_count(t, frame)
    if frame is None:
        raise PreconditionFailed(f"MISSION_REQUEST_LIST for the {mt.label} plan got no answer")
    got = frame.msg
    if got._type != "MISSION_COUNT":
        raise ClauseFailed(f"MISSION_REQUEST_LIST for the {mt.label} plan (holding {len(want)} items) "
                           f"was answered MISSION_ACK {procedures.result_name(got.type)}")
    if got.mission_type == mt and got.count == 0:
        raise PreconditionFailed(f"the vehicle reports an empty {mt.label} plan after accepting a "
                                 f"{len(want)}-item upload (MIS.UP.04 judges that)")
    if got.mission_type != mt or got.count != len(want):
        raise ClauseFailed(f"MISSION_REQUEST_LIST for the {mt.label} plan was answered MISSION_COUNT"
                           f"{{count={got.count}, mission_type={got.mission_type}}}; expected "
                           f"count={len(want)}, mission_type={int(mt)}")
    for seq, expected in enumerate(want):
        frame = None
        for _ in range(RETRIES + 1):
            t.send(m.request_message(seq, mt, t.target))
            frame = t.poll_for(msg(ITEMS, seq=seq), t.timings.default_timeout)
            if frame is not None:
                break
        if frame is None:
            raise PreconditionFailed(f"{mt.label} item {seq} never came")
        got = frame.msg
        if got.mission_type != mt:
            raise ClauseFailed(f"{mt.label} item {seq} came as {got._type} with mission_type="
                               f"{got.mission_type}; expected mission_type={int(mt)}")
        item = m.item_from_message(got)
        if item is None or not t.form.same([item], [expected]):
            raise ClauseFailed(f"{mt.label} item {seq} came as {item}; the {mt.label} plan holds {expected}")
    t.send(m.ack_message(MissionResult.ACCEPTED, mt, t.target))


@check("MIS.TYP.03")
def download_reports_requested_type(s: Session) -> None:
    t = s.t
    for mt in PLAN_TYPES:   # 3 waypoints, 4 fence vertices, 2 rally points: distinct counts
        items = plans.plan(mt, variant=43)
        if put_plan(t, items, mt):
            _download_checked(t, mt, items)


@check("MIS.TYP.04")
def unknown_type_refused(s: Session) -> None:
    t = s.t
    t.mark()
    t.send(m.count_message(2, UNKNOWN_TYPE, t.target))
    frame = t.expect(msg(REQUESTS) | ack())
    got = frame.msg
    if got._type != "MISSION_ACK":
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, got.mission_type, t.target))
        raise ClauseFailed(f"MISSION_COUNT with mission_type {UNKNOWN_TYPE} (no such type) started an "
                           f"upload: the vehicle sent {got._type}{{seq={got.seq}, mission_type="
                           f"{got.mission_type}}}; expected an error MISSION_ACK")
    if got.type == MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_COUNT with mission_type {UNKNOWN_TYPE} (no such type) was answered "
                           "MAV_MISSION_ACCEPTED; expected an error (e.g. MAV_MISSION_UNSUPPORTED)")
    t.mark()
    t.send(m.request_list_message(UNKNOWN_TYPE, t.target))
    frame = t.expect(msg("MISSION_COUNT") | ack())
    got = frame.msg
    if got._type == "MISSION_COUNT":   # the download it opened is ended, an empty one too
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, got.mission_type, t.target))
        raise ClauseFailed(f"MISSION_REQUEST_LIST with mission_type {UNKNOWN_TYPE} (no such type) was "
                           f"answered MISSION_COUNT{{count={got.count}, mission_type={got.mission_type}}}; "
                           "expected an error MISSION_ACK")
    if got.type == MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_REQUEST_LIST with mission_type {UNKNOWN_TYPE} (no such type) was "
                           "answered MAV_MISSION_ACCEPTED; expected an error MISSION_ACK")


@check("MIS.TYP.05")
def other_type_item_not_taken_into_upload(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(3, variant=44), MISSION)
    old = procedures.stored(t, MISSION)
    items = plans.mission(3, variant=45)
    k = 1
    # item k's seq, but a FENCE item (with a different altitude, so it could never pass for item k)
    intruder = replace(items[k], mission_type=FENCE, z=items[k].z + 7.0)
    mission_reply = request(mission_type=MT) | ack(mission_type=MT)
    t.mark()
    t.send(m.count_message(len(items), MISSION, t.target))
    for seq in range(k + 1):
        procedures.setup_expect(t, request(seq, mission_type=MT), "a mission upload runs")
        if seq < k:
            t.send(m.item_message(items[seq], t.target))
    t.note(f"answer the request for mission item {k} with a FENCE item of seq {k}")
    t.send(m.item_message(intruder, t.target))
    frame = t.poll_for(mission_reply, t.timings.default_timeout, forced=True)   # the item timeout
    if frame is None:
        raise ClauseFailed(f"after a FENCE item of seq {k} the mission upload went silent; expected "
                           f"mission item {k} to be requested again")
    got = frame.msg
    if got._type == "MISSION_ACK":
        if got.type == MissionResult.ACCEPTED:
            raise ClauseFailed(f"a FENCE item of seq {k} sent during a {len(items)}-item mission upload "
                               "drew MISSION_ACK ACCEPTED for the mission: it was taken as a mission item")
        # the vehicle refused the mix by ending the upload: the item did not join it
        procedures.require_same_plan(procedures.stored(t, MISSION), old,
                                     f"after the mission upload ended on a FENCE item "
                                     f"({procedures.result_name(got.type)})", t.form)
        t.note("the vehicle ended the mission upload on the FENCE item; the old plan is kept")
        return
    if got.seq != k:
        raise ClauseFailed(f"after a FENCE item of seq {k} the vehicle requested mission item {got.seq}; "
                           f"expected item {k} again (the FENCE item is not part of the mission upload)")
    frame = _finish(t, items, k)
    if frame is None:
        raise PreconditionFailed("the mission upload drew no final MISSION_ACK (MIS.UP.03 judges that)")
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"the mission upload ended with {procedures.result_name(frame.msg.type)} "
                           "after the FENCE item; expected MAV_MISSION_ACCEPTED")
    procedures.judge_stored(t, items, old, "after a mission upload with a FENCE item slipped in")


def _finish(t: Tester, items: list[MissionItem], first: int):
    """Answer every mission request from `first` on; the final mission MISSION_ACK, or None
    if the vehicle falls silent first."""
    t.send(m.item_message(items[first], t.target))
    return procedures.serve_upload(t, items)
