"""The server's behaviour knobs: everything a profile may change, as data.

The spec profile is the default of every field. PX4-like and ArduPilot-like profiles (a
later issue) are instances of this class with each changed knob citing its VARIANTS.md
row; engine code reads knobs and never asks which autopilot it is imitating.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .constants import MissionResult
from .items import PLAN_TYPES, MissionType
from .timing import Timings
from .validation import SPEC_RULES, ItemRule


def _default_capacity() -> dict[MissionType, int]:
    return {MissionType.MISSION: 1000, MissionType.FENCE: 256, MissionType.RALLY: 64}


@dataclass(frozen=True)
class ServerBehaviour:
    timings: Timings = Timings()
    # Most items each plan type can hold; a larger MISSION_COUNT gets MAV_MISSION_NO_SPACE.
    capacity: dict[MissionType, int] = field(default_factory=_default_capacity)
    # Plan types this vehicle stores; others get MAV_MISSION_UNSUPPORTED.
    supported_types: frozenset[MissionType] = frozenset(PLAN_TYPES)
    # Request items with MISSION_REQUEST_INT (spec) rather than MISSION_REQUEST.
    request_int: bool = True
    # Acceptance rules for uploaded items (validation.py).
    item_rules: tuple[ItemRule, ...] = SPEC_RULES
    # What a stray ITEM or REQUEST gets while no transfer of its type runs; None: silence.
    # Seed 000: the idle recipient "may respond with an appropriate error for that state".
    idle_reply: MissionResult | None = MissionResult.OPERATION_CANCELLED
    # Repeat ACCEPTED when an item of the upload just accepted arrives again from the same
    # sender: its final ACK was lost or overtaken (lost-ack recovery).
    reack_last_item: bool = True
    # Give up a silent upload with MISSION_ACK OPERATION_CANCELLED to the sender
    # (seed 000: after the retries "the client must cancel the operation").
    notify_upload_give_up: bool = True
    # MISSION_CURRENT stream period (upstream: "streamed all the time (nominally at 1Hz)").
    current_period: float = 1.0

    @property
    def download_idle_timeout(self) -> float:
        """How long a download stays open without a request from the GCS (it drives retries)."""
        t = self.timings
        return t.default_timeout * (t.max_retries + 1)
