"""The addressing clauses (MIS.G.RT.*): a GCS answers to its own address only, and addresses the vehicle.

On a shared link (a radio, a router, several GCSs) the vehicle's replies to another GCS reach
this one too; only target_system and target_component say whose they are (seed 001's routing
rules). The scripted vehicle puts its reply to another GCS, MISSION_ACK DENIED (what a vehicle
busy with one GCS tells another, MIS.GCS.01), just before the ACCEPTED the GCS waits for: a GCS
that takes it for its own reports its upload or clear refused.
"""

from __future__ import annotations

from typing import Any, Callable

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd, MissionResult

from ...outcome import ClauseFailed, PreconditionFailed
from ..harness import GcsHarness, Operation
from ..job import Job
from ..scripted_vehicle import VEHICLE, ScriptedVehicle, Swap, named
from . import check
from .common import (MISSION, clean_clear, clean_download, clean_upload, fail, scripted, short, stored,
                     upload_job)
from .current import set_current_op

DECOY_DELAY = 0.1   # s from the ACK to another GCS to the GCS's own
Peer = tuple[int, int]


def other_system(gcs: Peer) -> Peer:
    """Another GCS: the next system id down, or up from 1 and 2 (so never 0, nor the
    vehicle's 1), same component."""
    return (gcs[0] - 1 if gcs[0] > 2 else gcs[0] + 1), gcs[1]


def other_component(gcs: Peer) -> Peer:
    """Another component of the GCS's own system (never 0, the broadcast address)."""
    return gcs[0], gcs[1] % 255 + 1


def _decoy(address: Callable[[Peer], Peer], *, heard: bool) -> Callable[[Any, ScriptedVehicle], list[Any]]:
    """The vehicle's reply to another GCS at `address(gcs)` in place of the GCS's own ACK;
    `heard`: that GCS's HEARTBEAT is passed on first, so the GCS knows it is on the link
    (seed 001:98 lets a component take a message for a component it has never heard of)."""
    def instead(reply: Any, v: ScriptedVehicle) -> list[Any]:
        to = address(v.target)
        if heard:
            v.relay(m.gcs_heartbeat_message(), to)
        return [m.ack_message(MissionResult.DENIED, reply.mission_type, to)]
    return instead


def _ack_elsewhere_ignored(h: GcsHarness, address: Callable[[Peer], Peer], whom: str, *, heard: bool) -> str:
    """An upload and a clear, each with the vehicle's DENIED to another GCS just before the
    ACCEPTED: the GCS must not report either refused."""
    for job, plans in ((upload_job(), None), (Job("clear", MISSION), stored())):
        op = h.run(job, plans=plans, rules=[Swap(
            named("MISSION_ACK", type=MissionResult.ACCEPTED), then_after=DECOY_DELAY,
            what=f"MISSION_ACK DENIED to {whom}; this GCS's ACCEPTED {DECOY_DELAY * 1000:.0f} ms later",
            instead=_decoy(address, heard=heard))])
        decoy = scripted(op, f"its MISSION_ACK to {whom}", "MISSION_ACK", type=MissionResult.DENIED)
        to = (decoy.msg.target_system, decoy.msg.target_component)
        if not op.result.ok:
            clean = clean_upload(h) if job.op == "upload" else clean_clear(h)
            if not clean.result.ok:   # not the decoy's doing: other clauses judge that
                raise PreconditionFailed(f"the {job.op} failed, but so does one with no ACK to another GCS "
                                         f"({clean.result.line()})")
            raise fail(h, op, decoy, f"the {job.op} failed after MISSION_ACK DENIED addressed to {to[0]}/{to[1]} "
                                     f"({whom}), not to this GCS ({op.gcs[0]}/{op.gcs[1]}): {op.result.line()}")
        h.decide(op, decoy)
    return f"upload and clear: the DENIED to {whom} was ignored, each succeeded on its own ACCEPTED"


@check("MIS.G.RT.01")
def ack_to_another_system(h: GcsHarness) -> str:
    return _ack_elsewhere_ignored(h, other_system, "another GCS's system", heard=False)


@check("MIS.G.RT.02")
def ack_to_another_component(h: GcsHarness) -> str:
    return _ack_elsewhere_ignored(h, other_component, "another component of the GCS's system", heard=True)


def _judged(msg: Any) -> bool:
    """A Mission Protocol message, or the set-current command (not the GCS's other commands)."""
    if msg._type == "COMMAND_LONG":
        return msg.command == Cmd.DO_SET_MISSION_CURRENT
    return msg._type.startswith("MISSION_") and hasattr(msg, "target_component")


def _misaddressed(msg: Any) -> str | None:
    """How a message to the vehicle is addressed wrong (None: it is not). Mission messages go
    to the vehicle's system and component; the command may go to component 0, as COMMAND_LONG's
    target_component says ("0 for all components")."""
    to = (msg.target_system, msg.target_component)
    components = (0, VEHICLE[1]) if msg._type == "COMMAND_LONG" else (VEHICLE[1],)
    if to[0] == VEHICLE[0] and to[1] in components:
        return None
    return f"{short(msg)} went to {to[0]}/{to[1]}, not to the vehicle's {VEHICLE[0]}/{VEHICLE[1]}"


@check("MIS.G.RT.03")
def addressed_to_the_vehicle(h: GcsHarness) -> str:
    ops: list[Operation] = [clean_upload(h), clean_download(h), clean_clear(h), set_current_op(h)]
    checked = 0
    for op in ops:
        for e in op.sent():
            if not _judged(e.msg):
                continue
            wrong = _misaddressed(e.msg)
            if wrong is not None:
                raise fail(h, op, e, f"{wrong} (its HEARTBEAT came from {VEHICLE[0]}/{VEHICLE[1]}; "
                                     f"in the {op.job.op})")
            checked += 1
    if not checked:
        raise ClauseFailed("the GCS sent the vehicle no mission message")
    h.decide(ops[-1], ops[-1].sent()[-1])
    return f"upload, download, clear, set-current: all {checked} messages to the vehicle's {VEHICLE[0]}/{VEHICLE[1]}"
