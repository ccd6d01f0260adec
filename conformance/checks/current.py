"""Set current (seed 000, "Set Current Mission Item"; upstream MISSION_CURRENT and
MAV_CMD_DO_SET_MISSION_CURRENT): MIS.CUR.*"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult
from mavconform.reference_impl.mission.items import MissionType

from ..harness import plans, procedures
from ..harness.match import msg
from ..harness.measured import Measured
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
CURRENT = msg("MISSION_CURRENT")
STATUSTEXT = msg("STATUSTEXT")
PLAN_SIZE = 3
BAD_SEQ = 10                   # beyond the 3-item plan
STREAM_WAIT = 3.5              # s: long enough for the next streamed MISSION_CURRENT
BROADCAST_LAG = 0.5            # s: how much later than the requester another GCS may see it
STREAM_WINDOW = 2.2            # s watched to measure the stream's rate
STREAM_PERIOD = (0.5, 2.0)     # s between MISSION_CURRENTs accepted as "about 1 Hz"


def _current_is(seq: int):
    return msg("MISSION_CURRENT", seq=seq)



def _text(statustext) -> str:
    text = statustext.text
    if isinstance(text, (bytes, bytearray)):
        text = bytes(text).decode("utf-8", "replace")
    return text.strip("\0 ")


def _recent_texts(t: Tester, seconds: float) -> set[str]:
    """The STATUSTEXTs the vehicle sent in the last `seconds` (scaled): texts it repeats on
    its own (INAV 9.1 says "UNABLE TO ARM" every second) answer no request."""
    since = t.now() - seconds * t.scale
    return {_text(f.msg) for when, f in t.node.inbox if when >= since and f.msg._type == "STATUSTEXT"}


def _set_current(t: Tester, seq: int) -> None:
    t.mark()
    t.send(m.set_current_message(seq, t.target))


def _plan(t: Tester, variant: int) -> None:
    """A fresh 3-item plan, which the vehicle must report holding: a set-current is only
    judged against a plan the vehicle has."""
    accepted = procedures.ensure_plan(t, plans.mission(PLAN_SIZE, variant), MISSION)
    procedures.await_plan_taken(t, accepted)
    t.mark()
    frame = procedures.open_download(t, MISSION, resends=0)
    if frame is not None:   # every download opened is ended, an empty one too
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t.target))
    if frame is None or frame.msg.count != PLAN_SIZE:
        raise PreconditionFailed(f"setup: after accepting a {PLAN_SIZE}-item plan the vehicle "
                                 + ("did not answer MISSION_REQUEST_LIST" if frame is None else
                                    f"reports {frame.msg.count} items"))


@check("MIS.CUR.01")
def set_current_draws_mission_current(s: Session) -> str:
    t = s.t
    _plan(t, variant=31)
    frame, remark = procedures.set_current(t, 2)
    if frame is None:
        t.check_alive()
        raise ClauseFailed(f"neither MISSION_SET_CURRENT 2 nor its resend drew a MISSION_CURRENT{{seq=2}} "
                           f"within {t.reply_timeout:g} s; {t.last_seen()}")
    return remark


@check("MIS.CUR.02")
def invalid_set_current_draws_statustext(s: Session) -> None:
    t = s.t
    _plan(t, variant=32)
    streamed = _recent_texts(t, STREAM_WAIT)
    _set_current(t, BAD_SEQ)
    frame = t.poll_for(msg("STATUSTEXT", where=lambda f: _text(f.msg) not in streamed), t.timings.default_timeout)
    if frame is None:
        raise ClauseFailed(f"MISSION_SET_CURRENT {BAD_SEQ} (the plan has {PLAN_SIZE} items) drew no "
                           f"STATUSTEXT within {t.reply_timeout:g} s; expected one stating the problem")
    if not _text(frame.msg).strip():
        raise ClauseFailed("the STATUSTEXT answering an invalid MISSION_SET_CURRENT was empty; "
                           "expected a string stating the problem")


@check("MIS.CUR.03")
def failed_set_current_keeps_current(s: Session) -> None:
    t = s.t
    _plan(t, variant=33)
    before = 1 if procedures.set_current(t, 1)[0] is not None else None
    if before is None:   # the vehicle did not move to 1 (MIS.CUR.01 judges that): read where it is
        t.mark()
        frame = t.poll_for(CURRENT, STREAM_WAIT, forced=True)
        if frame is None:
            raise NotApplicable("the vehicle sends no MISSION_CURRENT to read the current item from "
                                "(MIS.CUR.06 judges the stream)")
        before = frame.msg.seq
    _set_current(t, BAD_SEQ)
    t.poll_for(STATUSTEXT, t.timings.default_timeout)   # the vehicle has handled it
    t.mark()
    frame = t.poll_for(CURRENT, STREAM_WAIT, forced=True)
    if frame is None:
        raise NotApplicable(f"no MISSION_CURRENT came within {STREAM_WAIT * t.scale:g} s of the failed "
                            "set-current: the vehicle does not stream it, so the current item cannot be "
                            "read (MIS.CUR.06 judges the stream)")
    if frame.msg.seq != before:
        raise ClauseFailed(f"after a failed MISSION_SET_CURRENT {BAD_SEQ} (the plan has {PLAN_SIZE} "
                           f"items) MISSION_CURRENT reported seq {frame.msg.seq}; expected it to stay "
                           f"at {before}")


@check("MIS.CUR.04")
def set_current_is_broadcast(s: Session) -> None:
    t, t2 = s.t, s.second()
    _plan(t, variant=34)
    t2.mark()
    mine, remark = procedures.set_current(t, 2)
    if mine is None:
        t.check_alive()
        raise ClauseFailed("neither MISSION_SET_CURRENT 2 nor its resend drew a MISSION_CURRENT{seq=2}, "
                           "for the requesting GCS or any other; expected one broadcast")
    other = t2.poll_for(_current_is(2), BROADCAST_LAG)
    if other is None:
        raise ClauseFailed(f"the requesting GCS got MISSION_CURRENT seq {mine.msg.seq}, but another "
                           f"GCS did not within {BROADCAST_LAG * s.scale:g} s; expected it broadcast")
    return remark


@check("MIS.CUR.05")
def set_current_command_acked(s: Session) -> None:
    t = s.t
    _plan(t, variant=35)
    t.mark()
    t.send(m.set_current_command(2, t.target))
    reply = t.expect(msg("COMMAND_ACK", command=int(Cmd.DO_SET_MISSION_CURRENT)))
    if reply.msg.result != CommandResult.ACCEPTED:
        raise ClauseFailed(f"MAV_CMD_DO_SET_MISSION_CURRENT 2 was answered "
                           f"{procedures.command_result_name(reply.msg.result)}; expected MAV_RESULT_ACCEPTED")
    t.expect(_current_is(2))


@check("MIS.CUR.06")
def mission_current_streamed(s: Session) -> None:
    t = s.t
    t.mark()
    seen = [dt for dt, _ in t.collect(CURRENT, STREAM_WINDOW)]
    low, high = STREAM_PERIOD
    if len(seen) < 2:
        raise ClauseFailed(f"{len(seen)} MISSION_CURRENT in {STREAM_WINDOW * s.scale:g} s; expected "
                           "one about every second")
    gaps = sorted(b - a for a, b in zip(seen, seen[1:]))
    median = gaps[len(gaps) // 2]   # the target's own period: --time-scale only widens the bound
    high *= s.scale
    if not low <= median <= high:
        raise ClauseFailed(Measured(f"MISSION_CURRENT came every <median> s (median of {len(gaps)} "
                                    f"gaps); expected about 1 s (accepted: {low:g}-{high:g} s)",
                                    median=f"{median:.2f}"))
