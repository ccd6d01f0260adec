"""Whole operations done the cooperative way, for setting up and checking state.

A check scripts the exchange its clause is about message by message; everything around
it (put a known plan on the target first, read the plan back after) goes through these
helpers, which behave like a careful GCS: spec timeouts, up to 5 resends, every loop
bounded. When one of them cannot finish, the clause is undecided (`PreconditionFailed`),
not failed: the clause that owns that behaviour is where it gets judged.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import Any, Callable, TypeVar

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import CommandResult, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.frame import Frame

from ..outcome import ClauseFailed, PreconditionFailed
from .match import REQUESTS, Match, ack, msg, request
from .stored_form import SPEC_FORM, StoredForm, describe_differences
from .tester import Tester

RETRIES = 5
MAX_ITEMS = 5000   # the largest plan read back (restoring a bigger one is left to the user)
F = TypeVar("F", bound=Callable[..., Any])


def _cooperative(fn: F) -> F:
    """A whole operation: the float forms on a float-only target, whatever the clause."""
    @functools.wraps(fn)
    def run(t: Tester, *args: Any, **kwargs: Any) -> Any:
        with t.cooperative():
            return fn(t, *args, **kwargs)
    return run   # type: ignore[return-value]


@dataclass
class Download:
    count: int
    items: list[MissionItem]
    count_frame: Frame


def result_name(code: int) -> str:
    try:
        return f"MAV_MISSION_{MissionResult(code).name}"
    except ValueError:
        return f"MAV_MISSION_RESULT {code} (not a defined value)"


def command_result_name(code: int) -> str:
    try:
        return f"MAV_RESULT_{CommandResult(code).name}"
    except ValueError:
        return f"MAV_RESULT {code} (not a defined value)"


@_cooperative
def upload(t: Tester, items: list[MissionItem], mission_type: MissionType, *,
           as_int: bool = True) -> Frame | None:
    """Upload `items`; the vehicle's final MISSION_ACK (any code), or None if it never came
    (then `other_type_answer` says whether it answered for another plan type)."""
    mt = int(mission_type)
    t.mark()
    t.send(m.count_message(len(items), mission_type, t.target))
    reply = request(mission_type=mt) | ack(mission_type=mt)
    resends = 0
    answered = 0
    for _ in range((len(items) + 2) * (RETRIES + 2)):   # bounded: every round answers or resends
        frame = t.poll_for(reply, t.timings.default_timeout)
        if frame is None:
            if resends >= RETRIES:
                return None
            resends += 1
            if answered == 0:
                t.send(m.count_message(len(items), mission_type, t.target))
            continue
        if frame.msg._type == "MISSION_ACK":
            return frame
        seq = frame.msg.seq
        if not 0 <= seq < len(items):
            continue
        answered += 1
        t.send(m.item_message(items[seq], t.target, as_int=as_int))
    return None


def other_type_answer(t: Tester, mission_type: MissionType) -> str | None:
    """After an upload of `mission_type` that got no MISSION_ACK: if the vehicle answered it
    with requests or an ACK for another plan type (INAV ignores mission_type and takes every
    upload as the mission), what it did, for a clause to say it cannot judge such a vehicle."""
    mt = int(mission_type)
    for frame in reversed(t.since_mark()):
        name = frame.msg._type
        if (name in REQUESTS or name == "MISSION_ACK") and getattr(frame.msg, "mission_type", mt) != mt:
            return (f"the vehicle answered a {mission_type.label} MISSION_COUNT with {name} for mission_type "
                    f"{frame.msg.mission_type}: it does not keep {mission_type.label} plans apart "
                    "(MIS.TYP.02 judges that)")
    return None


@_cooperative
def serve_upload(t: Tester, items: list[MissionItem], mission_type: MissionType = MissionType.MISSION, *,
                 as_int: bool = True) -> Frame | None:
    """Answer whatever the vehicle requests of a running upload of `items` until its
    MISSION_ACK, which is returned; None if it falls silent for the reply timeout first."""
    mt = int(mission_type)
    reply = request(mission_type=mt) | ack(mission_type=mt)
    for _ in range((len(items) + 2) * (RETRIES + 2)):   # bounded: a vehicle that never ends
        frame = t.poll_for(reply, t.timings.default_timeout)
        if frame is None or frame.msg._type == "MISSION_ACK":
            return frame
        if 0 <= frame.msg.seq < len(items):
            t.send(m.item_message(items[frame.msg.seq], t.target, as_int=as_int))
    return None


def ensure_plan(t: Tester, items: list[MissionItem], mission_type: MissionType) -> Frame:
    """Put `items` on the target as its `mission_type` plan (the accepting MISSION_ACK is
    returned), or make the clause undecided."""
    return accepted(upload(t, items, mission_type), len(items), mission_type)


def accepted(frame: Frame | None, count: int, mission_type: MissionType) -> Frame:
    """A setup upload's final MISSION_ACK if it accepted the plan, else the clause is undecided."""
    if frame is None:
        raise PreconditionFailed(f"setup: uploading a {count}-item {mission_type.label} plan "
                                 "got no MISSION_ACK")
    if frame.msg.type != MissionResult.ACCEPTED:
        raise PreconditionFailed(f"setup: uploading a {count}-item {mission_type.label} plan "
                                 f"was answered {result_name(frame.msg.type)}")
    return frame


PLAN_TAKEN_WAIT = 3.5   # s: the next 1 Hz MISSION_CURRENT, with room for a busy vehicle


def await_plan_taken(t: Tester, accepted: Frame) -> None:
    """After an accepted mission upload, wait (bounded) until the vehicle says it flies the
    new plan: a MISSION_CURRENT whose mission_id is the upload's opaque_id. A vehicle takes
    a new plan in its own time (PX4's navigator reads it after the ACK), and a set-current or
    mission start sent before that is lost to the race, not to the clause it would judge.
    Vehicles without plan ids in MISSION_CURRENT are not waited for."""
    opaque_id = getattr(accepted.msg, "opaque_id", 0)
    if not opaque_id:
        return
    if t.poll_for(msg("MISSION_CURRENT", mission_id=opaque_id), PLAN_TAKEN_WAIT, forced=True) is None:
        t.note(f"no MISSION_CURRENT reported the new plan (mission_id 0x{opaque_id:08x}) within "
               f"{PLAN_TAKEN_WAIT * t.scale:g} s; going on")


def send_count(t: Tester, count: int, mission_type: MissionType | int, answer: Match) -> Frame:
    """MISSION_COUNT, and the vehicle's answer to it (`answer`). Unanswered within the spec's
    timeout it is resent once, as a spec GCS does: INAV 9.1's SITL now and then leaves a
    MISSION_COUNT that follows a quiet spell unanswered (seen in MIS.CAN.04 and MIS.UP.08;
    150 COUNTs from pymavlink drew 150 answers), and a lost message is not what the clauses
    that open an upload this way judge. A COUNT never answered still fails (`t.expect`)."""
    t.send(m.count_message(count, mission_type, t.target))
    first = t.poll_for(answer, t.timings.default_timeout)
    if first is None:
        t.note(f"no answer to MISSION_COUNT within {t.reply_timeout:g} s: the GCS resends it once")
        t.send(m.count_message(count, mission_type, t.target))
        first = t.expect(answer)
    return first


def open_download(t: Tester, mission_type: MissionType | int, *, resends: int = RETRIES) -> Frame | None:
    """MISSION_REQUEST_LIST (resent up to `resends` times); the MISSION_COUNT (`fresh_count`),
    or None."""
    mt = int(mission_type)
    frame = None
    for _ in range(resends + 1):
        t.send(m.request_list_message(mission_type, t.target))
        frame = t.poll_for(msg("MISSION_COUNT", mission_type=mt), t.timings.default_timeout)
        if frame is not None:
            break
    return None if frame is None else fresh_count(t, frame)


def fresh_count(t: Tester, count: Frame) -> Frame | None:
    """`count` (a MISSION_COUNT), unless it names another plan id than the last upload or
    clear the vehicle accepted from the session's GCSs: then the vehicle still serves the plan
    from before it (PX4 answers a download sent right after the ACK from its old plan, now
    and then: its navigator's stale mission topic resets MavlinkMissionManager's count and
    id, mavlink_mission.cpp check_active_mission), so that download is ended, the vehicle is
    given until it reports the new plan, and the list is asked for once more. The race is
    noted in the exchange. After an operation acknowledged with id 0 (PX4 clears to id 0; a
    vehicle without plan ids always says 0), only an id that operation replaced is stale."""
    mt = count.msg.mission_type
    expected = t.plan_ids.get(mt, 0)
    reported = getattr(count.msg, "opaque_id", 0)
    if reported == expected or (not expected and reported not in t.replaced_ids.get(mt, ())):
        return count
    t.note(f"racy: the download was answered from the plan before the accepted upload or clear (id "
           f"0x{reported:08x}, not 0x{expected:08x}); ending it and asking again once the vehicle "
           "reports the new plan")
    t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mt, t.target))
    if mt == int(MissionType.MISSION):
        t.poll_for(msg("MISSION_CURRENT", mission_id=expected), PLAN_TAKEN_WAIT, forced=True)
    else:
        t.wait_until(lambda: False, t.timings.default_timeout)
    t.send(m.request_list_message(mt, t.target))
    return t.poll_for(msg("MISSION_COUNT", mission_type=mt), t.timings.default_timeout)


def set_current(t: Tester, seq: int, *, resends: int = 1) -> tuple[Frame | None, str]:
    """MISSION_SET_CURRENT `seq`, resent if no MISSION_CURRENT reports it within the reply
    timeout, as a GCS does (the message has no ACK: MAVSDK's client retransmits the same
    way). Returns that MISSION_CURRENT (None if none came) and a remark when only a resend
    was acted on: a race in the target (PX4's navigator has dropped a set-current sent right
    after a new plan), which the report shows instead of hiding."""
    for attempt in range(resends + 1):
        t.mark()
        t.send(m.set_current_message(seq, t.target))
        frame = t.poll_for(msg("MISSION_CURRENT", seq=seq), t.timings.default_timeout)
        if frame is not None:
            return frame, ("" if attempt == 0 else
                           f"racy: the first MISSION_SET_CURRENT {seq} was not acted on within "
                           f"{t.reply_timeout:g} s; the resend was (a race in the target)")
        if attempt < resends:
            t.note(f"no MISSION_CURRENT{{seq={seq}}} within {t.reply_timeout:g} s: the GCS resends")
    return None, ""


@_cooperative
def download(t: Tester, mission_type: MissionType, *, as_int: bool = True) -> Download | None:
    """Read the `mission_type` plan back; None if the target did not complete the download."""
    mt = int(mission_type)
    t.mark()
    count_frame = open_download(t, mission_type)
    if count_frame is None:
        return None
    count = count_frame.msg.count
    if count > MAX_ITEMS:   # more than any check uploads: not read (a truncated copy would mislead)
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, t.target))
        return None
    items: list[MissionItem] = []
    want = "MISSION_ITEM_INT" if as_int else "MISSION_ITEM"
    for seq in range(count):
        frame = None
        for _ in range(RETRIES + 1):
            t.send(m.request_message(seq, mission_type, t.target, as_int=as_int))
            frame = t.poll_for(msg(want, seq=seq, mission_type=mt), t.timings.default_timeout)
            if frame is not None:
                break
        item = None if frame is None else m.item_from_message(frame.msg)
        if item is None:   # the download is given up: end it on the vehicle too
            t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, t.target))
            return None
        items.append(item)
    # every download we open is ended, an empty one too: a target that keeps a download
    # open until the GCS's ACK must not be left holding it
    t.send(m.ack_message(MissionResult.ACCEPTED, mission_type, t.target))
    return Download(count, items, count_frame)


def stored(t: Tester, mission_type: MissionType) -> list[MissionItem]:
    """The plan on the target (compare it in `t.form`), or the clause is undecided."""
    got = download(t, mission_type)
    if got is None:
        raise PreconditionFailed(f"could not download the {mission_type.label} plan to check it")
    return got.items


def clear(t: Tester, mission_type: MissionType | int) -> Frame | None:
    t.mark()
    mt = int(mission_type)
    for _ in range(RETRIES + 1):
        t.send(m.clear_all_message(mission_type, t.target))
        frame = t.poll_for(ack(mission_type=mt), t.timings.default_timeout)
        if frame is not None:
            return frame
    return None


def comparable(item: MissionItem, form: StoredForm = SPEC_FORM) -> MissionItem:
    """An item as a plan comparison sees it (`StoredForm.canonical`): `current` is the
    vehicle's progress marker on download (seed 000 field table), not part of the plan."""
    return form.canonical(item)


def same_plan(a: list[MissionItem], b: list[MissionItem], form: StoredForm = SPEC_FORM) -> bool:
    return form.same(a, b)


def require_same_plan(got: list[MissionItem], want: list[MissionItem], what: str,
                      form: StoredForm = SPEC_FORM) -> None:
    if form.same(got, want):
        return
    diffs = form.differences(got, want)
    shown = f" (in the target's stored form: {describe_differences(diffs)})" if diffs else ""
    raise ClauseFailed(f"{what}: the target holds {len(got)} items, "
                       f"{'a different plan' if len(got) == len(want) else f'expected {len(want)}'}{shown}")


def setup_expect(t: Tester, match: Match, what: str) -> Frame:
    """`t.expect` for a step the clause builds on but does not judge: if it does not come,
    the clause is undecided (the clause that owns the step judges it)."""
    frame = t.poll_for(match, t.timings.default_timeout)
    if frame is None:
        raise PreconditionFailed(f"setup: {what}: expected {match} within {t.reply_timeout:g} s "
                                 "(another clause judges that step)")
    return frame


def judge_stored(t: Tester, want: list[MissionItem], before: list[MissionItem], what: str,
                 mission_type: MissionType = MissionType.MISSION) -> None:
    """The stored plan must be `want`, the plan just accepted. If it is still `before`, the
    vehicle stores no accepted upload at all: MIS.UP.04's finding, not this clause's."""
    got = stored(t, mission_type)
    if t.form.same(got, want):
        return
    if t.form.same(got, before):
        raise PreconditionFailed(f"{what}: the vehicle accepted the upload but still holds the plan from "
                                 "before it (MIS.UP.04 judges that)")
    require_same_plan(got, want, what, t.form)
