"""Download (seed 000, "Download a Mission from the Vehicle"): MIS.DN.*"""

from __future__ import annotations

import math
from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType, xy_scale

from ..harness import plans, procedures
from ..harness.match import ITEMS, ack, item, msg
from ..harness.stored_form import StoredForm
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
MT = int(MISSION)
COUNT = msg("MISSION_COUNT", mission_type=MT)


def _list(t: Tester) -> int:
    """Send MISSION_REQUEST_LIST; the count the vehicle answers with."""
    t.mark()
    frame = procedures.open_download(t, MISSION, resends=0)
    return (frame if frame is not None else t.expect(COUNT)).msg.count


def _request(t: Tester, seq: int, *, as_int: bool = True) -> None:
    t.send(m.request_message(seq, MISSION, t.target, as_int=as_int))


def _end(t: Tester, result: MissionResult = MissionResult.ACCEPTED) -> None:
    t.send(m.ack_message(result, MISSION, t.target))


PARAM_REFUSALS = frozenset({MissionResult.INVALID_PARAM1, MissionResult.INVALID_PARAM2,
                            MissionResult.INVALID_PARAM3, MissionResult.INVALID_PARAM4})


def _detailed(n: int, variant: int) -> list[MissionItem]:
    """Waypoints whose params are not all zero (acceptance radius, yaw), so a download that
    loses a field shows it."""
    return [replace(it, param2=2.0 + it.seq, param4=90.0) for it in plans.mission(n, variant)]


def _detailed_or_plain(t: Tester, n: int, variant: int) -> tuple[list[MissionItem], str]:
    """Upload `_detailed` waypoints; a target that refuses a param it cannot store
    (MAV_MISSION_INVALID_PARAMn, as the spec lets it: an MSP flight controller has no slot for
    acceptance radius or yaw) gets the plain ones, and the clause's detail says so."""
    items = _detailed(n, variant)
    frame = procedures.upload(t, items, MISSION)
    if frame is None or frame.msg.type not in PARAM_REFUSALS:
        procedures.accepted(frame, len(items), MISSION)   # else the clause is undecided, saying why
        return items, ""
    items = plans.mission(n, variant)
    note = (f"the target refused waypoints with params 2 and 4 set ({procedures.result_name(frame.msg.type)}): "
            "checked with params 0")
    t.note(note)
    procedures.ensure_plan(t, items, MISSION)
    return items, note


def _check_count(t: Tester, items: list[MissionItem]) -> int:
    """Open a download; the check needs the vehicle to report the plan just uploaded."""
    count = _list(t)
    if count != len(items):
        _end(t, MissionResult.OPERATION_CANCELLED)
        raise PreconditionFailed(f"the vehicle reported {count} items for the {len(items)}-item "
                                 "plan just uploaded (MIS.DN.01 judges that)")
    return count


def _describe(it: MissionItem) -> str:
    return (f"seq={it.seq} command={it.command} frame={it.frame} params=({it.param1:g}, "
            f"{it.param2:g}, {it.param3:g}, {it.param4:g}) x={it.x} y={it.y} z={it.z:g}")


def _second_gcs_not_denied(s: Session, after: str) -> None:
    """A second GCS starts a download; it must get the count, not DENIED."""
    t2 = s.second()
    t2.mark()
    t2.send(m.request_list_message(MISSION, t2.target))
    frame = t2.expect(COUNT | ack(mission_type=MT))
    if frame.msg._type == "MISSION_ACK":
        raise ClauseFailed(f"{after}, a second GCS's MISSION_REQUEST_LIST was answered "
                           f"{procedures.result_name(frame.msg.type)}; expected MISSION_COUNT "
                           "(the first download should be over)")
    _end(t2, MissionResult.OPERATION_CANCELLED)


@check("MIS.DN.01")
def request_list_draws_stored_count(s: Session) -> None:
    t = s.t
    items = plans.mission(6, variant=11)
    procedures.ensure_plan(t, items, MISSION)
    count = _list(t)
    counted = t.decided_by   # the MISSION_COUNT judged, not the items read after it
    _end(t, MissionResult.OPERATION_CANCELLED)
    if count == len(items):
        return
    # Is it our plan, miscounted, or did the accepted upload not store it (MIS.UP.04's case)?
    held = _fetch(t, min(max(count, 1), len(items)))
    if held is None or not procedures.same_plan(held, items[:len(held)], t.form):
        raise PreconditionFailed(f"the vehicle reports {count} items and does not hold the "
                                 f"{len(items)}-item plan it accepted (MIS.UP.04 judges that)")
    t.decided_by = counted
    raise ClauseFailed(f"MISSION_REQUEST_LIST was answered with count {count}; expected "
                       f"{len(items)} (the vehicle holds the {len(items)}-item plan just uploaded)")


def _fetch(t: Tester, n: int) -> list[MissionItem] | None:
    """Items 0..n-1 of a download opened afresh, or None if one does not come."""
    _list(t)
    out = []
    for seq in range(n):
        _request(t, seq)
        frame = t.poll_for(msg("MISSION_ITEM_INT", seq=seq, mission_type=MT), t.timings.default_timeout)
        got = None if frame is None else m.item_from_message(frame.msg)
        if got is None:
            break
        out.append(got)
    _end(t, MissionResult.OPERATION_CANCELLED)
    return out if len(out) == n else None


@check("MIS.DN.02")
def request_int_draws_item_int(s: Session) -> str:
    t = s.t
    items, note = _detailed_or_plain(t, 3, variant=12)
    _check_count(t, items)
    for want in items:
        _request(t, want.seq)
        frame = t.expect(msg("MISSION_ITEM_INT", seq=want.seq, mission_type=MT))
        got = m.item_from_message(frame.msg)
        if got is None or not procedures.same_plan([got], [want], t.form):
            raise ClauseFailed(f"MISSION_REQUEST_INT {want.seq} was answered with "
                               f"{_describe(got) if got else 'an unreadable item'}; expected the "
                               f"stored item {_describe(want)}")
    _end(t)
    return note


def _float_matches(frame_msg, want: MissionItem, form: StoredForm) -> bool:
    """MISSION_ITEM carries x/y as float32: allow one float32 step of rounding."""
    got = m.item_from_message(frame_msg)
    if got is None:
        return False
    if form.same([got], [want]):
        return True   # equal in the target's stored form (e.g. its home in slot 0)
    if not form.same([replace(got, x=want.x, y=want.y)], [want]):
        return False
    scale = xy_scale(want.frame)
    for have, exact in ((frame_msg.x, want.x / scale), (frame_msg.y, want.y / scale)):
        if abs(have - exact) > _ulp32(exact):
            return False
    return True


def _ulp32(v: float) -> float:
    """The spacing of float32 values around v."""
    return 2.0 ** (math.frexp(v)[1] - 24) if v else 2.0 ** -149


@check("MIS.DN.03")
def request_float_draws_item_float(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=13)
    procedures.ensure_plan(t, items, MISSION)
    _check_count(t, items)
    for want in items:
        _request(t, want.seq, as_int=False)
        frame = t.expect(item(want.seq, mission_type=MT))
        if frame.msg._type != "MISSION_ITEM":
            raise ClauseFailed(f"MISSION_REQUEST {want.seq} was answered with {frame.msg._type}; "
                               "expected MISSION_ITEM (the float form the GCS asked in)")
        if not _float_matches(frame.msg, want, t.form):
            got = m.item_from_message(frame.msg)
            raise ClauseFailed(f"MISSION_REQUEST {want.seq} was answered with "
                               f"{_describe(got) if got else 'an unreadable item'}; expected the "
                               f"stored item {_describe(want)}")
    _end(t)


@check("MIS.DN.04")
def empty_plan_counts_zero(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=14), MISSION)
    t.mark()
    t.send(m.clear_all_message(MISSION, t.target))
    cleared = t.poll_for(ack(mission_type=MT), t.timings.default_timeout)
    count = _list(t)
    if count == 0:
        _end(t)   # even an empty download is ended: PX4 holds it open until its 5 s timeout otherwise
        return
    if cleared is None or cleared.msg.type != MissionResult.ACCEPTED:
        raise PreconditionFailed("setup: the plan could not be cleared (MISSION_CLEAR_ALL was "
                                 + ("not answered)" if cleared is None else
                                    f"answered {procedures.result_name(cleared.msg.type)})"))
    _end(t, MissionResult.OPERATION_CANCELLED)
    raise ClauseFailed(f"after an accepted MISSION_CLEAR_ALL, MISSION_REQUEST_LIST was answered "
                       f"with count {count}; expected 0")


@check("MIS.DN.05")
def request_beyond_list_draws_error(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=15)
    procedures.ensure_plan(t, items, MISSION)
    count = _check_count(t, items)
    _request(t, count)
    got = t.poll_for(msg(ITEMS, seq=count, mission_type=MT) | ack(mission_type=MT),
                     t.timings.default_timeout)
    if got is None:
        _end(t, MissionResult.OPERATION_CANCELLED)
        raise ClauseFailed(f"MISSION_REQUEST_INT {count} (one past the {count}-item list) was not "
                           "answered; expected a MISSION_ACK with an error code")
    if got.msg._type != "MISSION_ACK":
        _end(t, MissionResult.OPERATION_CANCELLED)
        raise ClauseFailed(f"MISSION_REQUEST_INT {count} (one past the {count}-item list) was "
                           f"answered with {got.msg._type} {count}; expected an error MISSION_ACK")
    if got.msg.type == MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_REQUEST_INT {count} (one past the {count}-item list) was "
                           "answered MAV_MISSION_ACCEPTED; expected an error code")


@check("MIS.DN.06")
def repeated_requests_answered_again(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=16)
    procedures.ensure_plan(t, items, MISSION)
    _check_count(t, items)
    t.note("the GCS repeats MISSION_REQUEST_LIST, as if the MISSION_COUNT had been lost")
    t.send(m.request_list_message(MISSION, t.target))
    frame = t.poll_for(COUNT, t.timings.default_timeout)
    if frame is None:
        raise ClauseFailed("the repeated MISSION_REQUEST_LIST was not answered; expected "
                           "MISSION_COUNT again")
    t.note("each item is requested twice, as if the first MISSION_ITEM_INT had been lost")
    for seq in range(len(items)):
        for attempt in ("first", "repeated"):
            _request(t, seq)
            frame = t.poll_for(msg("MISSION_ITEM_INT", seq=seq, mission_type=MT),
                               t.timings.default_timeout)
            if frame is None:
                _end(t, MissionResult.OPERATION_CANCELLED)
                raise ClauseFailed(f"the {attempt} MISSION_REQUEST_INT {seq} was not answered; "
                                   f"expected MISSION_ITEM_INT {seq}")
    _end(t)


@check("MIS.DN.07")
def finished_download_frees_the_vehicle(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=17), MISSION)
    s.second()
    got = procedures.download(t, MISSION)   # ends with the GCS's MISSION_ACK ACCEPTED
    if got is None:
        raise PreconditionFailed("setup: the download of the plan did not complete")
    _second_gcs_not_denied(s, "right after the first GCS's MISSION_ACK ACCEPTED ended its download")


@check("MIS.DN.08")
def error_ack_cancels_download(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=18)
    procedures.ensure_plan(t, items, MISSION)
    s.second()
    _check_count(t, items)
    _request(t, 0)
    t.expect(msg(ITEMS, seq=0, mission_type=MT))
    t.note("the GCS ends the download with an error (MAV_MISSION_ERROR)")
    _end(t, MissionResult.ERROR)
    try:
        _second_gcs_not_denied(s, "after the first GCS sent MISSION_ACK MAV_MISSION_ERROR mid-download")
    except ClauseFailed:
        _end(t)   # close the download the vehicle kept open, for the clauses after this one
        raise


# --- MIS.DN.09 ----------------------------------------------------------------------------

CURRENT_PLAN = 4   # items in the plan the current flag is judged on
CURRENT_SEQ = 2    # the item made current: neither slot 0 (home on ArduPilot, A1) nor where a
                   # flight starts (0, or 1 after a home slot), so a fixed flag cannot pass


def _inbox_mark(t: Tester) -> object:
    """The last frame received so far (times do not order frames: in virtual time many
    arrive at one instant)."""
    inbox = t.node.inbox
    return inbox[-1] if inbox else None


def _currents_after(t: Tester, mark: object) -> list[int]:
    """The seqs of every MISSION_CURRENT received after `mark`, oldest first."""
    seqs = []
    for entry in reversed(t.node.inbox):
        if entry is mark:
            break
        if entry[1].msg._type == "MISSION_CURRENT":
            seqs.append(entry[1].msg.seq)
    return seqs[::-1]


@check("MIS.DN.09")
def download_flags_the_current_item(s: Session) -> None:
    """The `current` flag is judged against the item the vehicle itself reports current in
    MISSION_CURRENT (its own numbering: with home in slot 0 that is the download's too), not
    against what the GCS asked for."""
    t = s.t
    items = plans.mission(CURRENT_PLAN, variant=19)
    procedures.ensure_plan(t, items, MISSION)
    asked = _inbox_mark(t)
    t.mark()
    t.note(f"the GCS makes item {CURRENT_SEQ} current; the vehicle's MISSION_CURRENT says which item is")
    t.send(m.set_current_message(CURRENT_SEQ, t.target))
    if t.poll_for(msg("MISSION_CURRENT", seq=CURRENT_SEQ), t.timings.default_timeout) is not None:
        current = CURRENT_SEQ
    else:
        reported = _currents_after(t, asked)
        if not reported and not any(f.msg._type == "MISSION_CURRENT" for _, f in t.node.inbox):
            raise NotApplicable("the vehicle has sent no MISSION_CURRENT since the run began (MIS.CUR.06 "
                                "judges that), so which item it holds current cannot be known")
        if not reported:
            raise PreconditionFailed(f"setup: after MISSION_SET_CURRENT {CURRENT_SEQ} the vehicle sent no "
                                     "MISSION_CURRENT, so which item is current is unknown (MIS.CUR.01 "
                                     "judges that)")
        current = reported[-1]
        t.note(f"the vehicle reports item {current} current (it did not take item {CURRENT_SEQ})")
    before = _inbox_mark(t)
    got = procedures.download(t, MISSION)
    if got is None:
        raise PreconditionFailed("the download of the plan did not complete")
    moved = sorted(set(_currents_after(t, before)) - {current})
    if moved:
        raise PreconditionFailed(f"the vehicle reported item(s) {moved} current during the download "
                                 f"(item {current} before it): the current item moved while it was read")
    if got.count <= current:
        raise PreconditionFailed(f"the vehicle reports item {current} current but a download has only "
                                 f"{got.count} items")
    wrong = [f"item {it.seq} current={it.current}" for it in got.items
             if it.current != (1 if it.seq == current else 0)]
    if wrong:
        raise ClauseFailed(f"the vehicle reports item {current} current (MISSION_CURRENT seq={current}), "
                           f"but its download has {', '.join(wrong)}; expected current=1 on item "
                           f"{current} and current=0 on the other {got.count - 1}")
