"""The one result every client operation ends with.

Success carries its data; a failure says precisely what happened. `outcome_unknown` is the
honest answer to the two-generals corner: when the last item (or MISSION_CLEAR_ALL) was
sent but no ACCEPTED came back (silence, or a generic error that may be the idle vehicle's
reply to a late duplicate), the vehicle may or may not have applied it. A failure with
`outcome_unknown=False` guarantees the vehicle's plan is unchanged (on an atomic vehicle;
against a vehicle known not to be atomic, every failed upload that may have written
something says `outcome_unknown`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .constants import MissionResult
from .items import MissionItem, MissionType


class Operation(Enum):
    UPLOAD = "upload"
    DOWNLOAD = "download"
    CLEAR = "clear"
    SET_CURRENT = "set_current"


class Outcome(Enum):
    SUCCESS = "success"
    TIMEOUT = "timeout"              # no answer after every retry
    NACK = "nack"                    # the vehicle answered MISSION_ACK with an error code
    CANCELLED = "cancelled"          # we cancelled it
    PROTOCOL_ERROR = "protocol_error"  # the vehicle did something the protocol forbids
    REJECTED = "rejected"            # set-current refused (STATUSTEXT / COMMAND_ACK)


@dataclass(frozen=True)
class OperationResult:
    operation: Operation
    mission_type: MissionType
    outcome: Outcome
    items: tuple[MissionItem, ...] | None = None   # download: the plan received (`current` cleared)
    current_seq: int | None = None                  # download: the plan seq the vehicle flagged current
    opaque_id: int = 0                              # upload: id in the final ACK; download: from COUNT
    nack: MissionResult | int | None = None         # the error code of a NACK
    retries: int = 0                                # timeout-driven resends during the operation
    max_consecutive_retries: int = 0                # the most resends of any one message
    outcome_unknown: bool = False                   # see the module docstring
    detail: str = ""
    started: float = 0.0
    finished: float = 0.0
    adaptations: tuple[str, ...] = ()               # ids of the adaptations that acted (adaptations.py)

    @property
    def ok(self) -> bool:
        return self.outcome is Outcome.SUCCESS

    def summary(self) -> str:
        head = f"{self.operation.value} {self.mission_type.label}: {self.outcome.value}"
        if self.nack is not None:
            head += f" ({MissionResult.describe(int(self.nack))})"
        if self.items is not None and self.ok:
            head += f", {len(self.items)} items"
        if self.detail:
            head += f" - {self.detail}"
        return head
