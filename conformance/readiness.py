"""Before the first clause: the streams the checks read, and a target done booting.

A real vehicle streams only what a GCS asks for (ArduCopter streams nothing by default,
VARIANTS.md L4) and may refuse uploads for a while after boot (ArduPilot answers
MISSION_COUNT with NO_SPACE for about 2 s, L5). A GCS asks for its streams the modern way,
MAV_CMD_SET_MESSAGE_INTERVAL, and falls back to REQUEST_DATA_STREAM where that is refused;
then it finds out whether the target answers the _INT forms at all (harness/float_forms.py:
INAV answers only MISSION_ITEM / MISSION_REQUEST), and waits until an upload is taken. All
are bounded, and what the target answered is one line of the report, so a clause that then
misses a stream says why in the report.
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, CommandResult, MissionResult
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

from .harness import float_forms, plans, procedures
from .harness.match import msg
from .harness.measured import Measured
from .harness.tester import Tester

INTERVAL_US = 1_000_000            # 1 Hz, the rate the spec names for MISSION_CURRENT
# (message, its id, the MAV_DATA_STREAM group that carries it on ArduPilot-era autopilots)
STREAMS = (("MISSION_CURRENT", 42, 2),        # MAV_DATA_STREAM_EXTENDED_STATUS
           ("GLOBAL_POSITION_INT", 33, 6))    # MAV_DATA_STREAM_POSITION
READY_WAIT = 30.0                  # s an upload may be refused as the target boots
READY_RETRY = 1.0                  # s between upload probes


@dataclass
class Readiness:
    streams: list[str]             # how each stream was asked for, and the answer
    forms: str                     # whether the target answers the _INT forms
    ready: str                     # how the upload probe went
    waited_s: float = 0.0          # the target's boot, forced

    def line(self) -> str:
        """One line for the report. How long the target took to boot is measured, so it is a
        `Measured` text: the run document keeps it apart in its volatile section."""
        parts = self.streams + [self.forms, self.ready]
        values: dict[str, str] = {}
        for part in parts:
            values.update(getattr(part, "values", {}))
        return Measured("; ".join(getattr(part, "stable", part) for part in parts), **values)


def prepare(t: Tester) -> Readiness:
    started = t.now()
    streams = [_ask_for_stream(t, *stream) for stream in STREAMS]
    forms = float_forms.probe(t)
    ready = _await_uploads(t)
    return Readiness(streams, forms, ready, round(t.now() - started, 3))


def _ask_for_stream(t: Tester, name: str, msg_id: int, group: int) -> str:
    t.mark()
    t.send(m.command_long_message(Cmd.SET_MESSAGE_INTERVAL, t.target, msg_id, INTERVAL_US))
    reply = t.poll_for(msg("COMMAND_ACK", command=Cmd.SET_MESSAGE_INTERVAL), t.timings.default_timeout)
    if reply is not None and reply.msg.result == CommandResult.ACCEPTED:
        return f"{name} at 1 Hz: MAV_CMD_SET_MESSAGE_INTERVAL accepted"
    said = "no COMMAND_ACK" if reply is None else procedures.command_result_name(reply.msg.result)
    t.send(_d.MAVLink_request_data_stream_message(t.target[0], t.target[1], group, 1, 1))
    return (f"{name}: MAV_CMD_SET_MESSAGE_INTERVAL got {said}, so REQUEST_DATA_STREAM {group} "
            "at 1 Hz was sent (not acknowledged by design)")


def _await_uploads(t: Tester) -> str:
    """Probe with a one-item mission upload until it is not refused for lack of space (the
    run's restore puts back what the target held)."""
    probe = plans.mission(1, variant=99)
    refused = 0
    opened = t.now()
    for _ in range(int(READY_WAIT / READY_RETRY) + 1):
        frame = procedures.upload(t, probe, MissionType.MISSION)
        if frame is None:
            return "upload probe: no MISSION_ACK (the clauses judge that)"
        if frame.msg.type != MissionResult.NO_SPACE:
            said = f"upload probe: {procedures.result_name(frame.msg.type)}"
            if not refused:
                return said
            return Measured(said + " after <boot_refusals> NO_SPACE refusal(s) in <boot_wait>",
                            boot_refusals=str(refused), boot_wait=f"{t.now() - opened:.1f} s")
        refused += 1
        if t.now() - opened > READY_WAIT * t.scale:
            break
        t.wait_until(lambda: False, READY_RETRY)
    return Measured("upload probe: still NO_SPACE after <boot_wait>; the target may not be done booting",
                    boot_wait=f"{t.now() - opened:.1f} s")

