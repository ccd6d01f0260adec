"""Operator control (development.xml, MAV_CMD_REQUEST_OPERATOR_CONTROL and CONTROL_STATUS): HO.CTL.*

The target is the system manager: the component whose HEARTBEAT the run found, addressed by
both GCSs (`s.t`, system 245, and `s.second()`, 246). Only what the XML says that component
does is judged; its open choices (how long a takeover window lasts, whether an uncontrolled
vehicle takes commands from anyone, which MISSION_ACK code refuses a write, how long a silent
owner is kept) are not.

Applicability. Operator control is optional (and work in progress upstream). A target that
has sent no CONTROL_STATUS since the run began, nor within `PROBE_WAIT` more, has no system
manager: every clause is not-applicable (looked for once per run). A target that answers the
request with MAV_RESULT_UNSUPPORTED is not-applicable too. PX4 and ArduPilot without
operator control, and `builtin:px4` / `builtin:ardupilot`, come out so. A system manager on
another component than the one whose HEARTBEAT the run found (a companion computer) is not
heard either: the suite talks to that component only.

What is sent. The non-owner's command (HO.CTL.10) is MAV_CMD_DO_SET_MISSION_CURRENT -1, 0
("the current item", no reset): state-changing, yet a no-op should a broken target act on it;
a target that answers it UNSUPPORTED to the owner too leaves the clause undecided. The
telemetry request (HO.CTL.12) is MAV_CMD_REQUEST_MESSAGE HEARTBEAT; any answer but
NOT_IN_CONTROL is served (the command's own result is another matter).

Setup and cleanup. A clause starts from an uncontrolled target: if the last CONTROL_STATUS
names one of our GCSs, that GCS releases first; if it names another GCS, the clause is
undecided (a real operator holds the vehicle: the suite does not take it from them). Steps a
clause builds on but does not judge (taking control for the clause, the owner allowing
takeover) make it undecided when they fail, never failed: the clause that owns the step
judges it. Whatever happens, a clause ends with both GCSs releasing control and beating
again (`restoring`), so the target is left as it was found; HO.CTL.11, which writes a plan
as the owner, puts the plan back first. Every wait is bounded.

Evidence. The exchange keeps mission traffic, COMMAND_LONG and COMMAND_ACK only, so the
1 Hz CONTROL_STATUS stream cannot make mission clauses' reports differ between runs; a
CONTROL_STATUS a clause judges is added to its exchange by the check (`shown`).

Owner loss (HO.CTL.13). The owner (GCS 246) stops its HEARTBEATs and sends nothing else; GCS
245 keeps beating, so a manager that takes any GCS's HEARTBEAT for the owner's keeps it. The
XML does not say when an owner is "disconnected" (seed 001: how many heartbeats may be missed
"depends on the channel alone"). The clause waits for the
target's own time: for an in-process vehicle, its configured owner-loss time and
`STATUS_WAIT`; for any other target at most `OWNER_LOSS_WAIT` (15 s: stock GCS-loss
timeouts are 5 s on ArduPilot, FS_GCS_TIMEOUT, and 10 s on PX4, COM_DL_LOSS_T; then the next
CONTROL_STATUS and a margin), stretched by --time-scale. It ends as soon as the
CONTROL_STATUS comes.
"""

from __future__ import annotations


from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult
from mavconform.reference_impl.mission.items import MissionType

from ..harness import plans, procedures
from ..harness.match import ack, msg, request
from ..harness.measured import Measured
from ..harness.tester import Tester
from ..outcome import ClauseFailed, PreconditionFailed
from ..session import Session
from . import check
from .control_exchange import (FORWARDED, REQUEST_CONTROL, REQUEST_TIMEOUT, STATUS, STATUS_WAIT, TAKEOVER, ask_control,
                               gcs_id, latest_status, next_status, refuse_if_unsupported, restoring, result_text,
                               send_command, shown, start_uncontrolled, status_text, system_manager, take_control)

MISSION = MissionType.MISSION
MT = int(MISSION)

ON_CHANGE = 0.5             # s after the COMMAND_ACK: "emitted when ... change", not the stream's next
STREAM_COUNT = 3            # CONTROL_STATUS timed to measure the stream (two gaps)
STREAM_PERIOD = (0.5, 2.0)  # s between CONTROL_STATUS accepted as "nominally 1 Hz" (as MIS.CUR.06)
OWNER_LOSS_WAIT = 15.0      # s an external target is given to announce a silent owner's loss


# --- the stream --------------------------------------------------------------------------------

@check("HO.CTL.01")
def status_streamed(s: Session) -> None:
    system_manager(s)
    t = s.t
    t.mark()
    times: list[float] = []
    for _ in range(STREAM_COUNT):
        frame = t.poll_for(STATUS, STATUS_WAIT, forced=True)
        if frame is None:
            break
        shown(t, frame)
        times.append(next(at for at, f in reversed(t.node.inbox) if f is frame))
    if len(times) < 2:
        raise ClauseFailed(f"after {len(times)} CONTROL_STATUS, none came within {STATUS_WAIT * s.scale:g} s; "
                           "expected one about every second")
    gaps = sorted(b - a for a, b in zip(times, times[1:]))
    median = gaps[len(gaps) // 2]   # the target's own period: --time-scale only widens the bound
    low, high = STREAM_PERIOD
    high *= s.scale
    if not low <= median <= high:
        raise ClauseFailed(Measured(f"CONTROL_STATUS came every <median> s (median of {len(gaps)} gaps); "
                                    f"expected about 1 s (accepted: {low:g}-{high:g} s)", median=f"{median:.2f}"))


# --- requests ----------------------------------------------------------------------------------

@check("HO.CTL.02")
def granted_when_uncontrolled(s: Session) -> None:
    t, _ = start_uncontrolled(s)
    with restoring(s):
        t.mark()
        t.note(f"nobody is in control; GCS {gcs_id(t)} asks for control (takeover not allowed)")
        frame = ask_control(t, cm.ACTION_REQUEST)
        refuse_if_unsupported(frame)
        if frame is None:
            raise ClauseFailed(f"MAV_CMD_REQUEST_OPERATOR_CONTROL (request, nobody in control) drew no "
                               f"COMMAND_ACK within {t.reply_timeout:g} s; expected MAV_RESULT_ACCEPTED")
        if frame.msg.result != CommandResult.ACCEPTED:
            raise ClauseFailed(f"a request for control while nobody was in control was answered "
                               f"{result_text(frame)}; expected MAV_RESULT_ACCEPTED")


@check("HO.CTL.03")
def release_frees_control(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t.mark()
        t.note(f"GCS {gcs_id(t)}, in control, releases it")
        frame = ask_control(t, cm.ACTION_RELEASE)
        if frame is None or frame.msg.result != CommandResult.ACCEPTED:
            raise ClauseFailed(f"the owner's release of control was answered {result_text(frame)}; expected "
                               "MAV_RESULT_ACCEPTED")
        free = t.poll_for(msg("CONTROL_STATUS", gcs_main=0), STATUS_WAIT, forced=True)
        if free is None:
            last = latest_status(t)
            if last is not None:
                shown(t, last)
            raise ClauseFailed(f"after GCS {gcs_id(t)} released control (MAV_RESULT_ACCEPTED), no CONTROL_STATUS "
                               f"with gcs_main=0 came within {STATUS_WAIT * s.scale:g} s"
                               + (f"; the last was {status_text(last)}" if last is not None else "")
                               + "; expected the vehicle uncontrolled")
        shown(t, free)
        t2.mark()
        t2.note(f"GCS {gcs_id(t2)} asks for control of the uncontrolled vehicle")
        frame = ask_control(t2, cm.ACTION_REQUEST)
        if frame is None or frame.msg.result != CommandResult.ACCEPTED:
            raise ClauseFailed(f"after GCS {gcs_id(t)} released control, GCS {gcs_id(t2)}'s request was answered "
                               f"{result_text(frame)}; expected MAV_RESULT_ACCEPTED (nobody in control)")


@check("HO.CTL.04")
def stream_names_the_owner(s: Session) -> None:
    t, _ = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t.mark()
        me = gcs_id(t)
        for n in (1, 2):   # the change's own CONTROL_STATUS (if sent at once), then the stream's
            frame = t.poll_for(STATUS, STATUS_WAIT, forced=True)
            if frame is None:
                if n == 1:
                    raise ClauseFailed(f"after GCS {me} was granted control, no CONTROL_STATUS came within "
                                       f"{STATUS_WAIT * s.scale:g} s; expected one naming it")
                return   # one CONTROL_STATUS named it; how often the stream comes is HO.CTL.01's
            shown(t, frame)
            if frame.msg.gcs_main != me:
                raise ClauseFailed(f"after GCS {me} was granted control (MAV_RESULT_ACCEPTED), CONTROL_STATUS "
                                   f"#{n} said gcs_main={frame.msg.gcs_main}; expected {me}")


@check("HO.CTL.05")
def status_sent_on_change(s: Session) -> None:
    t, _ = start_uncontrolled(s)
    me = gcs_id(t)
    with restoring(s):
        synced = next_status(t, "the stream's next CONTROL_STATUS, to time the change by")
        if synced.msg.gcs_main != 0:
            raise PreconditionFailed(f"control was not free: {status_text(synced)} (HO.CTL.03 judges release)")
        take_control(t, what=f"right after a streamed CONTROL_STATUS, GCS {me} asks for control: the stream's next "
                      "is about a second away")
        got = t.poll_for(msg("CONTROL_STATUS", gcs_main=me), ON_CHANGE)
        if got is None:
            raise ClauseFailed(f"after GCS {me} was granted control (MAV_RESULT_ACCEPTED), no CONTROL_STATUS "
                               f"naming it came within {ON_CHANGE * s.scale:g} s; expected one at once, when "
                               "ownership changed")
        shown(t, got)
        next_status(t, "the stream's next CONTROL_STATUS, to time the change by")
        take_control(t, True, what=f"right after a streamed CONTROL_STATUS, GCS {me}, in control, re-requests it "
                            "with takeover allowed", judged_by=None)
        got = t.poll_for(msg("CONTROL_STATUS", gcs_main=me, flags=lambda f: bool(f & TAKEOVER)), ON_CHANGE)
        if got is None:
            raise ClauseFailed(f"after GCS {me}, in control, allowed takeover (MAV_RESULT_ACCEPTED), no "
                               f"CONTROL_STATUS with GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED came within "
                               f"{ON_CHANGE * s.scale:g} s; expected one at once, when the takeover status changed")
        shown(t, got)


@check("HO.CTL.06")
def busy_request_refused(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t2.mark()
        t2.note(f"GCS {gcs_id(t)} is in control (takeover not allowed); GCS {gcs_id(t2)} asks for control")
        frame = ask_control(t2, cm.ACTION_REQUEST)
        if frame is None:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request for control, while GCS {gcs_id(t)} held it, drew no "
                               f"COMMAND_ACK within {t2.reply_timeout:g} s; expected MAV_RESULT_FAILED")
        if frame.msg.result == CommandResult.ACCEPTED:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request was granted (MAV_RESULT_ACCEPTED) while GCS {gcs_id(t)} "
                               "held control with takeover not allowed; expected MAV_RESULT_FAILED")
        if frame.msg.result != CommandResult.FAILED:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request for control, while GCS {gcs_id(t)} held it with takeover "
                               f"not allowed, was answered {result_text(frame)}; expected MAV_RESULT_FAILED")


@check("HO.CTL.07")
def refused_request_forwarded(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t.mark()
        t2.mark()
        sent = (cm.ACTION_REQUEST, 0.0, REQUEST_TIMEOUT, float(gcs_id(t2)))
        t2.note(f"GCS {gcs_id(t)} is in control (takeover not allowed); GCS {gcs_id(t2)} asks for control")
        refusal = ask_control(t2, cm.ACTION_REQUEST)
        if refusal is not None and refusal.msg.result == CommandResult.ACCEPTED:
            raise PreconditionFailed(f"GCS {gcs_id(t2)}'s request was granted while GCS {gcs_id(t)} held control "
                                     "(HO.CTL.06 judges that)")
        forwarded = t.poll_for(FORWARDED, t.timings.default_timeout)
        if forwarded is None:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request for control (answered {result_text(refusal)}) did not reach "
                               f"the owner, GCS {gcs_id(t)}, within {t.reply_timeout:g} s; expected the same "
                               "MAV_CMD_REQUEST_OPERATOR_CONTROL sent on to it")
        t.send(cm.command_ack(REQUEST_CONTROL, CommandResult.ACCEPTED, (forwarded.src_system,
                                                                        forwarded.src_component)))
        have = tuple(getattr(forwarded.msg, f"param{i}") for i in (1, 2, 3, 4))
        wrong = [f"param{i}={h:g} (sent {w:g})" for i, (h, w) in enumerate(zip(have, sent), 1) if h != w]
        if wrong:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request reached the owner, GCS {gcs_id(t)}, changed: "
                               f"{', '.join(wrong)}; expected the same command")


@check("HO.CTL.08")
def allowed_takeover_granted(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t2.note(f"GCS {gcs_id(t)} is in control (takeover not allowed); GCS {gcs_id(t2)} asks for control")
        first = ask_control(t2, cm.ACTION_REQUEST)
        if first is not None and first.msg.result == CommandResult.ACCEPTED:
            raise PreconditionFailed(f"GCS {gcs_id(t2)}'s request was granted while GCS {gcs_id(t)} held control "
                                     "(HO.CTL.06 judges that)")
        forwarded = t.poll_for(FORWARDED, t.timings.default_timeout)   # HO.CTL.07 judges it
        if forwarded is not None:   # "That owning GCS must ACK with MAV_RESULT_ACCEPTED"
            t.send(cm.command_ack(REQUEST_CONTROL, CommandResult.ACCEPTED,
                                  (forwarded.src_system, forwarded.src_component)))
        take_control(t, True, what=f"GCS {gcs_id(t)}, the owner, re-requests control with takeover allowed",
              judged_by=None)
        t2.mark()
        t2.note(f"GCS {gcs_id(t2)} asks again")
        frame = ask_control(t2, cm.ACTION_REQUEST)
        if frame is None or frame.msg.result != CommandResult.ACCEPTED:
            raise ClauseFailed(f"after the owner, GCS {gcs_id(t)}, re-requested control with takeover allowed, "
                               f"GCS {gcs_id(t2)}'s request was answered {result_text(frame)}; expected "
                               "MAV_RESULT_ACCEPTED")


@check("HO.CTL.09")
def disallowed_takeover_refused(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        take_control(t, True, what=f"GCS {gcs_id(t)}, the owner, re-requests control with takeover allowed",
              judged_by=None)
        take_control(t, False, what=f"GCS {gcs_id(t)} re-requests control with takeover disallowed again",
              judged_by=None)
        t2.mark()
        t2.note(f"GCS {gcs_id(t2)} asks for control")
        frame = ask_control(t2, cm.ACTION_REQUEST)
        if frame is None:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request drew no COMMAND_ACK within {t2.reply_timeout:g} s; "
                               "expected it refused")
        if frame.msg.result == CommandResult.ACCEPTED:
            raise ClauseFailed(f"GCS {gcs_id(t2)}'s request was granted (MAV_RESULT_ACCEPTED) after the owner, GCS "
                               f"{gcs_id(t)}, had allowed takeover and then disallowed it again; expected it refused")


# --- what a GCS not in control may do ------------------------------------------------------------

@check("HO.CTL.10")
def command_from_non_owner_not_in_control(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t2.mark()
        # param 1 = -1, param 2 = 0: "the current mission item", no reset; a state-changing
        # command that changes nothing should a target act on it
        t2.note(f"GCS {gcs_id(t)} is in control; GCS {gcs_id(t2)} sends MAV_CMD_DO_SET_MISSION_CURRENT -1 (the "
                "current item, no reset)")
        frame = send_command(t2, Cmd.DO_SET_MISSION_CURRENT, -1.0, 0.0)
        if frame is None:
            raise ClauseFailed(f"a command from GCS {gcs_id(t2)}, not in control, drew no COMMAND_ACK within "
                               f"{t2.reply_timeout:g} s; expected MAV_RESULT_NOT_IN_CONTROL")
        if frame.msg.result == CommandResult.UNSUPPORTED:
            # a command the target does not have controls nothing: is it one it has?
            t.note(f"GCS {gcs_id(t)}, in control, sends the same command")
            own = send_command(t, Cmd.DO_SET_MISSION_CURRENT, -1.0, 0.0)
            if own is None or own.msg.result == CommandResult.UNSUPPORTED:
                raise PreconditionFailed(f"the target answers MAV_CMD_DO_SET_MISSION_CURRENT {result_text(own)} even "
                                         "from the GCS in control: the clause has no command of the target's "
                                         "to send")
            t2.decided_by_frame(frame)
        if frame.msg.result != CommandResult.NOT_IN_CONTROL:
            raise ClauseFailed(f"MAV_CMD_DO_SET_MISSION_CURRENT from GCS {gcs_id(t2)}, not in control (GCS "
                               f"{gcs_id(t)} is), was answered {result_text(frame)}; expected MAV_RESULT_NOT_IN_CONTROL")


@check("HO.CTL.11")
def mission_write_from_non_owner_refused(s: Session) -> str:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        before = procedures.stored(t, MISSION)
        mine = plans.mission(2, variant=60)
        try:
            procedures.ensure_plan(t, mine, MISSION)
            return _judge_foreign_writes(t, t2, mine)
        finally:
            keep = t.decided_by
            t.note(f"afterwards: GCS {gcs_id(t)}, still in control, puts back the plan it found")
            if before:
                procedures.upload(t, before, MISSION)
            else:
                procedures.clear(t, MISSION)
            t.decided_by = keep


def _judge_foreign_writes(t: Tester, t2: Tester, mine: list) -> str:
    theirs = plans.mission(3, variant=61)
    answers = []
    t2.mark()
    t2.note(f"GCS {gcs_id(t)} is in control and holds a 2-item plan; GCS {gcs_id(t2)} sends MISSION_COUNT 3")
    t2.send(m.count_message(len(theirs), MISSION, t2.target))
    reply = t2.poll_for(request(mission_type=MT) | ack(mission_type=MT), t2.timings.default_timeout)
    if reply is not None and reply.msg._type != "MISSION_ACK":
        t2.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t2.target))
        raise ClauseFailed(f"MISSION_COUNT from GCS {gcs_id(t2)}, not in control, started an upload "
                           f"({reply.msg._type} {reply.msg.seq}); expected it refused")
    if reply is not None and reply.msg.type == MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_COUNT from GCS {gcs_id(t2)}, not in control, was answered "
                           "MAV_MISSION_ACCEPTED; expected it refused")
    answers.append(f"MISSION_COUNT: {'no answer' if reply is None else procedures.result_name(reply.msg.type)}")
    t2.note(f"GCS {gcs_id(t2)} sends MISSION_CLEAR_ALL for the mission plan")
    t2.send(m.clear_all_message(MISSION, t2.target))
    reply = t2.poll_for(ack(mission_type=MT), t2.timings.default_timeout)
    if reply is not None and reply.msg.type == MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_CLEAR_ALL from GCS {gcs_id(t2)}, not in control, was answered "
                           "MAV_MISSION_ACCEPTED; expected it refused")
    answers.append(f"MISSION_CLEAR_ALL: {'no answer' if reply is None else procedures.result_name(reply.msg.type)}")
    procedures.require_same_plan(procedures.stored(t, MISSION), mine,
                                 f"after mission writes from GCS {gcs_id(t2)}, not in control", t.form)
    return "refused: " + "; ".join(answers)


@check("HO.CTL.12")
def reads_from_non_owner_answered(s: Session) -> str | None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t)
        t2.note(f"GCS {gcs_id(t)} is in control; GCS {gcs_id(t2)} downloads the mission plan")
        t2.mark()
        t2.send(m.request_list_message(MISSION, t2.target))
        reply = t2.poll_for(msg("MISSION_COUNT", mission_type=MT) | ack(mission_type=MT),
                            t2.timings.default_timeout)
        if reply is None or reply.msg._type == "MISSION_ACK":
            said = "nothing" if reply is None else f"MISSION_ACK {procedures.result_name(reply.msg.type)}"
            raise ClauseFailed(f"MISSION_REQUEST_LIST from GCS {gcs_id(t2)}, not in control, was answered {said}; "
                               "expected MISSION_COUNT (a download changes nothing)")
        t2.send(m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, t2.target))
        t2.note(f"GCS {gcs_id(t2)} sends MAV_CMD_REQUEST_MESSAGE (HEARTBEAT), a telemetry request")
        frame = send_command(t2, Cmd.REQUEST_MESSAGE)
        if frame is None:   # unanswered: is it answered to anyone?
            keep = t2.decided_by
            t.note(f"GCS {gcs_id(t)}, in control, sends the same request")
            if send_command(t, Cmd.REQUEST_MESSAGE) is None:
                return ("MAV_CMD_REQUEST_MESSAGE is acknowledged to no GCS, in control or not: judged by the "
                        "download alone")
            t2.decided_by = keep
        if frame is None or frame.msg.result == CommandResult.NOT_IN_CONTROL:
            raise ClauseFailed(f"MAV_CMD_REQUEST_MESSAGE from GCS {gcs_id(t2)}, not in control, was answered "
                               f"{result_text(frame)}" + ("" if frame is not None else
                                                      f" (the GCS in control, GCS {gcs_id(t)}, got an answer)")
                               + "; expected an answer as to any GCS (not MAV_RESULT_NOT_IN_CONTROL)")
        return None


# --- owner loss -------------------------------------------------------------------------------

def _loss_wait(s: Session) -> float:
    """How long (unscaled) a silent owner is given: an in-process vehicle's own owner-loss
    time and the stream's next CONTROL_STATUS; `OWNER_LOSS_WAIT` for anything else."""
    control = getattr(s.vehicle, "control", None)
    if control is not None:
        return control.config.owner_loss_timeout + STATUS_WAIT
    return OWNER_LOSS_WAIT


@check("HO.CTL.13")
def owner_loss_announced(s: Session) -> None:
    t, t2 = start_uncontrolled(s)
    with restoring(s):
        take_control(t2)
        wait = _loss_wait(s)
        t2.node.heartbeats = False
        t.mark()
        t.note(f"GCS {gcs_id(t2)}, in control, falls silent: no HEARTBEAT or anything else from it (watched for at "
               f"most {wait * s.scale:g} s)")
        frame = t.poll_for(msg("CONTROL_STATUS", gcs_main=0), wait, forced=True)
        if frame is None:
            last = latest_status(t)
            if last is not None:
                shown(t, last)
            raise ClauseFailed(f"GCS {gcs_id(t2)}, in control, sent nothing for {wait * s.scale:g} s, and no "
                               "CONTROL_STATUS with gcs_main=0 came"
                               + (f" (the last was {status_text(last)})" if last is not None else "")
                               + "; expected one saying the vehicle has no owner")
        shown(t, frame)
