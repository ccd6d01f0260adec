"""The cancellation clause (MIS.G.CN.01): the vehicle's OPERATION_CANCELLED ends the operation."""

from __future__ import annotations

from mavconform.reference_impl.mission.constants import MissionResult

from ..harness import GcsHarness
from . import check
from .common import download_ended_by


@check("MIS.G.CN.01")
def cancel_honoured(h: GcsHarness) -> str:
    return download_ended_by(h, MissionResult.OPERATION_CANCELLED)
