"""Upload (seed 000, "Upload a Mission to the Vehicle"): MIS.UP.*"""

from __future__ import annotations

from dataclasses import dataclass, replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import plans, procedures
from ..harness.match import REQUESTS, ack, msg, request
from ..harness.measured import Measured
from ..harness.stored_form import StoredForm
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, beyond_the_clause
from ..session import Session
from . import check

MISSION = MissionType.MISSION
MT = int(MISSION)
ITEM_TIMEOUT = 0.25            # spec's item timeout (seed 000 line 535)
ABOUT = 1.8                    # "about 250 ms": up to 450 ms, off the 500 ms timers some stacks use
MAX_RETRIES = 5                # spec's retry limit (seed 000 line 537)
SILENT_WINDOW = 12.0           # longest we watch a silent upload: PX4 gives up after 5 s, ArduPilot 8 s
GONE_QUIET = 3.0               # no request for this long: the vehicle has stopped asking


def _start(t: Tester, items: list[MissionItem]) -> None:
    t.mark()
    t.send(m.count_message(len(items), MISSION, t.target))


def _answer(t: Tester, items: list[MissionItem], seq: int, *, as_int: bool = True) -> None:
    t.send(m.item_message(items[seq], t.target, as_int=as_int))


def _reach(t: Tester, items: list[MissionItem], seq: int) -> None:
    """Start an upload and bring it to the vehicle's request for item `seq`: setup for a
    clause about what happens next, so a failure here leaves that clause undecided."""
    with beyond_the_clause(f"bringing an upload to its request for item {seq}"):
        t.mark()
        procedures.send_count(t, len(items), MISSION, request(0, mission_type=MT))
        for k in range(seq):
            _answer(t, items, k)
            t.expect(request(k + 1, mission_type=MT))


def _serve(t: Tester, items: list[MissionItem], *, as_int: bool = True):
    """Answer whatever the vehicle requests until its MISSION_ACK, which is returned."""
    frame = procedures.serve_upload(t, items, as_int=as_int)
    if frame is None:
        t.check_alive()
        raise ClauseFailed(f"the {len(items)}-item upload stalled or never ended: no MISSION_ACK")
    return frame


def _finish(t: Tester, items: list[MissionItem], *, first: int = 0, as_int: bool = True):
    """Answer requests first..count-1 in order; return the final MISSION_ACK frame."""
    for seq in range(first, len(items)):
        t.expect(request(seq, mission_type=MT))
        _answer(t, items, seq, as_int=as_int)
    return t.expect(ack(mission_type=MT))


@check("MIS.UP.01")
def count_draws_request_for_item_0(s: Session) -> None:
    t = s.t
    _start(t, plans.mission(3, variant=1))
    t.expect(request(0, mission_type=MT))


@check("MIS.UP.02")
def items_requested_in_order(s: Session) -> None:
    t = s.t
    items = plans.mission(4, variant=2)
    _start(t, items)
    for seq in range(len(items)):
        frame = t.expect(msg(REQUESTS, mission_type=MT))
        if frame.msg.seq != seq:
            raise ClauseFailed(f"after {seq} items the vehicle requested seq {frame.msg.seq}, expected {seq}")
        _answer(t, items, seq)
    with beyond_the_clause("waiting for the final MISSION_ACK"):
        t.expect(ack(mission_type=MT))


@check("MIS.UP.03")
def last_item_draws_accepted(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=3)
    _reach(t, items, len(items) - 1)
    _answer(t, items, len(items) - 1)
    frame = t.expect(ack(mission_type=MT))
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"the upload ended with {procedures.result_name(frame.msg.type)}, "
                           "expected MAV_MISSION_ACCEPTED")


@check("MIS.UP.04")
def accepted_upload_replaces_plan(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=4), MISSION)
    new = plans.mission(3, variant=5)
    procedures.ensure_plan(t, new, MISSION)
    # the clause that owns A1: item 0 is compared too, so a vehicle that keeps its home in
    # slot 0 fails here (and only here; every other clause compares in its stored form)
    procedures.require_same_plan(procedures.stored(t, MISSION), new, "after an accepted upload",
                                 t.form.strict())


SILENT_OLD, SILENT_NEW, SILENT_SENT = 4, 3, 2   # old plan, new count, items sent before going silent


@dataclass
class SilentUpload:
    """What a vehicle does with an upload whose GCS sends some items and then nothing more
    (shared by UP.05-09): the requests it then sends are all for the next item due. Real
    items are sent (item 1 too: ArduPilot keeps home in slot 0 and drops an uploaded item 0)
    and the new count is shorter than the old plan (ArduPilot truncates at MISSION_COUNT), so
    a vehicle that writes an upload as it arrives (VARIANTS A2) holds a changed plan after."""
    requests: list[tuple[float, int]]     # (s since the last item was sent, seq) of every request
    give_up_ack: int | None               # the MISSION_ACK type it ended with, if any
    stopped: bool                         # it stopped requesting within the window
    after: float                          # when it stopped (last request), s since the last item
    before: list[MissionItem]             # the plan the vehicle held before the upload

    @property
    def repeated(self) -> list[float]:
        """Times of every request for the item it asked for first after the GCS fell silent."""
        if not self.requests:
            return []
        first = self.requests[0][1]
        return [dt for dt, seq in self.requests if seq == first]

    @property
    def gaps(self) -> list[float]:
        """The intervals between those re-requests, shortest first."""
        times = self.repeated
        return sorted(b - a for a, b in zip(times, times[1:]))


def silent_upload(s: Session) -> SilentUpload:
    return s.shared("silent_upload", lambda: _observe_silent_upload(s.t))


def _observe_silent_upload(t: Tester) -> SilentUpload:
    procedures.ensure_plan(t, plans.mission(SILENT_OLD, variant=6), MISSION)
    before = procedures.stored(t, MISSION)
    items = plans.mission(SILENT_NEW, variant=7)
    _reach(t, items, SILENT_SENT - 1)
    _answer(t, items, SILENT_SENT - 1)
    t.note(f"the GCS has sent items 0-{SILENT_SENT - 1} of a {SILENT_NEW}-item upload (the vehicle "
           f"held {len(before)} items), then goes silent")
    opened = t.now()
    seen = t.collect(request(mission_type=MT), SILENT_WINDOW, stop=ack(mission_type=MT), quiet=GONE_QUIET)
    ended_early = t.now() - opened < SILENT_WINDOW * t.scale * 0.999
    reqs = [(dt, f.msg.seq) for dt, f in seen if f.msg._type in REQUESTS]
    acks = [f.msg.type for _, f in seen if f.msg._type == "MISSION_ACK"]
    return SilentUpload(reqs, acks[0] if acks else None, bool(acks) or ended_early,
                        reqs[-1][0] if reqs else 0.0, before)


def retry_interval(s: Session) -> float | None:
    """The target's own re-request interval (median gap of the silent upload), or None if
    it never re-requested."""
    gaps = silent_upload(s).gaps
    return gaps[len(gaps) // 2] if gaps else None


def silence_window(s: Session, at_least: float) -> float:
    """How long (unscaled s) a "the vehicle stopped asking" window must last: `at_least`,
    and half as long again as the target's own measured retry interval, so a vehicle that
    re-requests every second (ArduPilot) cannot pass by being slow."""
    measured = retry_interval(s)
    return at_least if measured is None else max(at_least, 1.5 * measured / s.scale)


@check("MIS.UP.05")
def abandoned_upload_keeps_old_plan(s: Session) -> None:
    obs = silent_upload(s)
    if not obs.stopped:
        raise NotApplicable("the vehicle never gave the silent upload up, so there is no "
                            "abandoned upload to look at (MIS.UP.08 judges that)")
    procedures.require_same_plan(procedures.stored(s.t, MISSION), obs.before,
                                 f"after an upload abandoned at item {SILENT_SENT} of {SILENT_NEW}", s.t.form)


@check("MIS.UP.06")
def missing_item_is_requested_again(s: Session) -> None:
    obs = silent_upload(s)
    if len(obs.repeated) < 2:
        raise ClauseFailed(f"the item due was requested {len(obs.repeated)} time(s) while the GCS was "
                           "silent; expected it to be requested again after the item timeout")


@check("MIS.UP.07")
def item_timeout_is_about_250ms(s: Session) -> None:
    obs = silent_upload(s)
    median = retry_interval(s)   # the target's own timer: --time-scale only widens the bound
    if median is None:
        raise NotApplicable("the vehicle never re-requested, so it has no retry interval "
                            "(MIS.UP.06 judges that)")
    gaps = len(obs.repeated) - 1
    low, high = ITEM_TIMEOUT / 2, ITEM_TIMEOUT * ABOUT * s.scale
    if not low <= median <= high:
        raise ClauseFailed(Measured(f"re-requests came every <median> ms (median of "
                                    f"{gaps}); expected about {ITEM_TIMEOUT * 1000:.0f} ms "
                                    f"(accepted: {low * 1000:.0f}-{high * 1000:.0f} ms)",
                                    median=f"{median * 1000:.0f}"))


@check("MIS.UP.08")
def gives_up_and_returns_to_idle(s: Session) -> None:
    obs = silent_upload(s)
    if not obs.stopped:
        raise ClauseFailed(f"the vehicle was still requesting items {SILENT_WINDOW * s.scale:g} s "
                           f"after the GCS went silent ({len(obs.requests)} requests)")
    # idle again: a fresh upload must start from item 0 and complete
    t = s.t
    items = plans.mission(2, variant=8)
    t.mark()
    procedures.send_count(t, len(items), MISSION, request(0, mission_type=MT))
    _answer(t, items, 0)
    with beyond_the_clause("finishing the new upload"):
        frame = _finish(t, items, first=1)
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed("after giving the silent upload up, the vehicle answered a new upload "
                           f"with {procedures.result_name(frame.msg.type)}")


@check("MIS.UP.09")
def at_most_5_retries(s: Session) -> None:
    obs = silent_upload(s)
    resends = len(obs.repeated) - 1
    if resends > MAX_RETRIES:
        raise ClauseFailed(f"the item due was requested again {resends} times; expected at most {MAX_RETRIES}")


@check("MIS.UP.10")
def out_of_sequence_item_is_rerequested(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=9)
    _reach(t, items, 0)
    t.note("the GCS answers the request for item 0 with item 1")
    _answer(t, items, 1)
    frame = t.expect(msg(REQUESTS, mission_type=MT))
    if frame.msg.seq != 0:
        raise ClauseFailed(f"after an out-of-sequence item 1 the vehicle requested seq {frame.msg.seq}; "
                           "expected item 0 to be requested again")


@check("MIS.UP.11")
def out_of_sequence_is_not_an_error(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=10)
    _reach(t, items, 0)
    t.note("the GCS answers the request for item 0 with item 2")
    _answer(t, items, 2)
    with beyond_the_clause("serving the rest of the upload"):
        final = _serve(t, items)
    if final.msg.type == MissionResult.ACCEPTED:
        return
    code = procedures.result_name(final.msg.type)
    # An error ACK is the end of the upload to any GCS; say whether the vehicle thought so too
    went_on = t.poll_for(request(mission_type=MT), t.timings.default_timeout)
    if went_on is not None:
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
        raise ClauseFailed(f"the vehicle answered the out-of-sequence item with MISSION_ACK {code}, an error "
                           f"a GCS takes as the end of its upload, though the vehicle went on requesting "
                           f"(item {went_on.msg.seq}); expected the item dropped without an error")
    t.decided_by_frame(final)   # not the request that did not follow it
    raise ClauseFailed(f"the upload ended with {code} after an out-of-sequence item; expected it to go "
                       "on and end ACCEPTED")


@check("MIS.UP.12")
def gcs_error_ack_cancels_and_keeps_plan(s: Session) -> None:
    t = s.t
    # real items first, in a count shorter than the old plan: what a vehicle that writes an
    # upload as it arrives has changed by then shows (as in the silent upload, UP.05)
    window = silence_window(s, ITEM_TIMEOUT * 3)   # measured first: it runs an upload of its own
    procedures.ensure_plan(t, plans.mission(4, variant=11), MISSION)
    old = procedures.stored(t, MISSION)
    items = plans.mission(3, variant=12)
    _reach(t, items, 2)
    t.send(m.ack_message(MissionResult.ERROR, MISSION, t.target))
    t.mark()
    t.expect_silence(request(mission_type=MT), for_=window)
    procedures.require_same_plan(procedures.stored(t, MISSION), old,
                                 "after the GCS ended an upload with ERROR at item 2 of 3", t.form)


@check("MIS.UP.13")
def refused_count_keeps_plan(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=13), MISSION)
    old = procedures.stored(t, MISSION)
    t.mark()
    t.send(m.count_message(65535, MISSION, t.target))
    frame = t.expect(request(mission_type=MT) | ack(mission_type=MT))
    if frame.msg._type != "MISSION_ACK":
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
        raise NotApplicable("the vehicle accepted a count of 65535 items; no count it refuses was found")
    if frame.msg.type == MissionResult.ACCEPTED:
        raise ClauseFailed("a MISSION_COUNT of 65535 was answered ACCEPTED before any item was sent")
    procedures.require_same_plan(procedures.stored(t, MISSION), old,
                                 f"after the vehicle refused a count with {procedures.result_name(frame.msg.type)}", t.form)


@check("MIS.UP.14")
def float_items_are_accepted(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=14)
    _reach(t, items, 0)
    _answer(t, items, 0, as_int=False)
    # the clause itself: is the float item taken (the next item asked for, or the end)?
    nxt = t.expect(request(mission_type=MT) | ack(mission_type=MT))
    if nxt.msg._type != "MISSION_ACK" and nxt.msg.seq == 0:
        again = t.poll_for(request(mission_type=MT) | ack(mission_type=MT), t.timings.default_timeout)
        if again is None or (again.msg._type != "MISSION_ACK" and again.msg.seq == 0):
            t.decided_by_frame(nxt if again is None else again)   # item 0 asked for again
            t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
            raise ClauseFailed("item 0 sent as MISSION_ITEM was not taken: the vehicle asked for item 0 "
                               "again; expected it to go on to item 1 as it does for MISSION_ITEM_INT")
        nxt = again
    if nxt.msg._type == "MISSION_ACK":
        final = nxt
    else:
        _answer(t, items, nxt.msg.seq, as_int=False)
        with beyond_the_clause("serving the rest of the upload"):
            final = _serve(t, items, as_int=False)
    if final.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"an upload in MISSION_ITEM messages ended with "
                           f"{procedures.result_name(final.msg.type)}, expected ACCEPTED")
    got = procedures.stored(t, MISSION)
    read = t.decided_by   # the verdict below is about this download, not the one after it
    if len(got) == len(items) and all(_close(g, w, t.form) for g, w in zip(got, items)):
        return
    procedures.ensure_plan(t, items, MISSION)
    as_int = procedures.stored(t, MISSION)
    if len(got) == len(as_int) and all(_close(g, w, t.form) for g, w in zip(got, as_int)):
        return   # stored as the same items sent as MISSION_ITEM_INT are (MIS.UP.04 judges those)
    t.decided_by = read
    raise ClauseFailed(f"after a MISSION_ITEM upload the vehicle holds {got}, expected {items} "
                       "(positions within float32 precision), as it does after a MISSION_ITEM_INT upload")


def _close(got: MissionItem, want: MissionItem, form: StoredForm) -> bool:
    """Equal but for the float32 rounding MISSION_ITEM's x/y imposes (< 1e-5 degrees)."""
    return form.same([got], [want]) or (
        abs(got.x - want.x) <= 100 and abs(got.y - want.y) <= 100
        and form.same([replace(got, x=want.x, y=want.y)], [want]))


@check("MIS.UP.15")
def requests_use_int_form(s: Session) -> None:
    t = s.t
    _start(t, plans.mission(2, variant=15))
    frame = t.expect(request(mission_type=MT))
    if frame.msg._type != "MISSION_REQUEST_INT":
        raise ClauseFailed(f"the vehicle requested item 0 with {frame.msg._type}, expected MISSION_REQUEST_INT")


@check("MIS.UP.16")
def count_zero_clears(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=16), MISSION)
    t.mark()
    t.send(m.count_message(0, MISSION, t.target))
    frame = t.expect(ack(mission_type=MT))
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_COUNT 0 was answered {procedures.result_name(frame.msg.type)}, expected ACCEPTED")
    left = procedures.stored(t, MISSION)
    if left:
        raise ClauseFailed(f"after an upload of 0 items the vehicle still holds {len(left)} items")
