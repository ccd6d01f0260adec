"""What a tester does and reads in operator control (MAV_CMD_REQUEST_OPERATOR_CONTROL,
CONTROL_STATUS), for the HO.CTL clauses (operator_control.py) and the HO.SEQ ones
(handover_sequence.py, handover_flight.py): is the target a system manager, its latest and
next CONTROL_STATUS, a request and its COMMAND_ACK, taking control as a setup step, leaving
the target uncontrolled afterwards."""

from __future__ import annotations

from contextlib import contextmanager
from typing import Iterator

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import CommandResult
from mavconform.reference_impl.wire.frame import Frame

from ..harness import procedures
from ..harness.exchange import message_fields
from ..harness.match import msg
from ..harness.tester import Tester
from ..outcome import NotApplicable, PreconditionFailed
from ..session import Session

REQUEST_CONTROL = cm.REQUEST_CONTROL
STATUS = msg("CONTROL_STATUS")
REQUEST_ACK = msg("COMMAND_ACK", command=REQUEST_CONTROL)
FORWARDED = msg(("COMMAND_LONG", "COMMAND_INT"), command=REQUEST_CONTROL)
TAKEOVER = cm.FLAG_TAKEOVER_ALLOWED
PROBE_WAIT = 3.0            # s: three periods of the nominal 1 Hz stream, on top of the run so far
STATUS_WAIT = 3.5           # s: the stream's next CONTROL_STATUS, at the slowest a vehicle may still be judged
REQUEST_TIMEOUT = 10.0      # param 3 of our requests (s; the XML's bounds are 3-60)
PROBE_KEY = "ho.control_status"


def gcs_id(t: Tester) -> int:
    return t.node.endpoint.system


def result_text(frame: Frame | None) -> str:
    return "no COMMAND_ACK" if frame is None else procedures.command_result_name(frame.msg.result)


def latest_status(t: Tester) -> Frame | None:
    """The last CONTROL_STATUS the target sent, whatever the floor."""
    for _, frame in reversed(t.node.inbox):
        if frame.msg._type == "CONTROL_STATUS":
            return frame
    return None


def system_manager(s: Session) -> None:
    """Not-applicable unless the target streams CONTROL_STATUS (looked for once per run)."""
    seen = s.cache.get(PROBE_KEY)
    if seen is None:
        t = s.t
        seen = latest_status(t) is not None or t.poll_for(STATUS, PROBE_WAIT, forced=True) is not None
        s.cache[PROBE_KEY] = seen
    if not seen:
        raise NotApplicable(f"the target sent no CONTROL_STATUS (none since the run began, nor in "
                            f"{PROBE_WAIT * s.scale:g} s more): it has no system manager for operator control")


def shown(t: Tester, frame: Frame) -> Frame:
    """Put a CONTROL_STATUS the clause judges into its exchange (which keeps mission traffic
    only) and mark it as what decided, so the report shows the message the verdict is about."""
    ex = t.exchange
    if ex is not None:
        when = next((at for at, f in reversed(t.node.inbox) if f is frame), t.now())
        index = ex.add(when, "rx", t.node.name, frame.msg._type, message_fields(frame.msg))
        if index is not None:
            t.decided_by = index
    return frame


def status_text(frame: Frame) -> str:
    flags = frame.msg.flags
    names = [n for bit, n in ((cm.FLAG_SYSTEM_MANAGER, "SYSTEM_MANAGER"), (TAKEOVER, "TAKEOVER_ALLOWED"))
             if flags & bit]
    return f"CONTROL_STATUS{{gcs_main={frame.msg.gcs_main}, flags={'|'.join(names) or 0}}}"


def ask_control(t: Tester, action: float, allow: bool = False) -> Frame | None:
    """MAV_CMD_REQUEST_OPERATOR_CONTROL from `t` for itself (param 4 = its own id); the
    COMMAND_ACK addressed to it, or None after the reply timeout."""
    t.send(cm.request_command(t.target, action, allow, REQUEST_TIMEOUT, gcs_id(t)))
    return t.poll_for(REQUEST_ACK, t.timings.default_timeout)


def send_command(t: Tester, command: int, *params: float) -> Frame | None:
    """COMMAND_LONG `command` from `t`; its COMMAND_ACK, or None after the reply timeout."""
    t.send(m.command_long_message(command, t.target, *params))
    return t.poll_for(msg("COMMAND_ACK", command=int(command)), t.timings.default_timeout)


def refuse_if_unsupported(frame: Frame | None) -> None:
    if frame is not None and frame.msg.result == CommandResult.UNSUPPORTED:
        raise NotApplicable("MAV_CMD_REQUEST_OPERATOR_CONTROL was answered MAV_RESULT_UNSUPPORTED: the "
                            "target has no operator control")


def take_control(t: Tester, allow: bool = False, *, what: str = "", judged_by: str | None = "HO.CTL.02") -> Frame:
    """A request by `t` that the clause builds on: ACCEPTED, or the clause is undecided.
    `judged_by`: the clause that judges this step, if one does (the owner's re-requests
    that set the takeover flag are steps no clause judges on their own)."""
    takeover = "allowed" if allow else "not allowed"
    t.note(what or f"GCS {gcs_id(t)} asks for control (takeover {takeover})")
    frame = ask_control(t, cm.ACTION_REQUEST, allow)
    refuse_if_unsupported(frame)
    if frame is None or frame.msg.result != CommandResult.ACCEPTED:
        raise PreconditionFailed(f"setup: GCS {gcs_id(t)}'s request for control (takeover {takeover}) got "
                                 f"{result_text(frame)}" + (f" ({judged_by} judges that)" if judged_by else ""))
    return frame


def start_uncontrolled(s: Session) -> tuple[Tester, Tester]:
    """Both GCSs, with the target uncontrolled as far as the suite can make it: a GCS of ours
    in control releases; another GCS in control leaves the clause undecided."""
    system_manager(s)
    t, t2 = s.t, s.second()
    release_if_ours(t, [t, t2])
    return t, t2


def release_if_ours(t: Tester, ours: list[Tester]) -> None:
    """A GCS of `ours` that the last CONTROL_STATUS names releases control; another
    operator's control leaves the clause undecided (the suite never takes it from them)."""
    by_id = {gcs_id(x): x for x in ours}
    last = latest_status(t)
    owner = last.msg.gcs_main if last is not None else 0
    if owner and owner not in by_id:
        raise PreconditionFailed(f"GCS {owner} is in control of the target (CONTROL_STATUS gcs_main): the "
                                 "clause needs it uncontrolled, and the suite does not take it from another "
                                 "operator; release it and run again")
    if owner:
        by_id[owner].note(f"the last CONTROL_STATUS names GCS {owner}: it releases control first")
        ask_control(by_id[owner], cm.ACTION_RELEASE)


@contextmanager
def restoring(s: Session) -> Iterator[None]:
    """Leave the target as found: both GCSs beat again and release control (a GCS not in
    control is told so, which is harmless). What decided the verdict stays marked."""
    try:
        yield
    finally:
        t = s.t
        keep = t.decided_by
        for tester in s.testers():
            tester.node.heartbeats = True
        t.note("afterwards: both GCSs release control, leaving the target uncontrolled")
        for tester in s.testers():
            ask_control(tester, cm.ACTION_RELEASE)
        t.decided_by = keep


def next_status(t: Tester, what: str) -> Frame:
    """The stream's next CONTROL_STATUS (a setup step: none, and the clause is undecided)."""
    t.mark()
    frame = t.poll_for(STATUS, STATUS_WAIT, forced=True)
    if frame is None:
        raise PreconditionFailed(f"setup: {what}: no CONTROL_STATUS within {STATUS_WAIT * t.scale:g} s "
                                 "(HO.CTL.01 judges the stream)")
    return frame
