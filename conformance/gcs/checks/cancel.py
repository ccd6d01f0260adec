"""The cancellation clause (MIS.G.CN.01): the vehicle's OPERATION_CANCELLED ends the operation."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult

from ..harness import GcsHarness
from ..scripted_vehicle import ITEMS, Swap, named
from . import check
from .common import (MISSION, WATCH_AFTER, download_job, ended_by, stored)


@check("MIS.G.CN.01")
def cancel_honoured(h: GcsHarness) -> str:
    op = h.run(download_job(), plans=stored(), after=WATCH_AFTER, rules=[Swap(
        named(*ITEMS, seq=1), what="MISSION_ACK OPERATION_CANCELLED",
        instead=lambda reply, v: [m.ack_message(MissionResult.OPERATION_CANCELLED, MISSION, v.target)])])
    return ended_by(h, op, MissionResult.OPERATION_CANCELLED)
