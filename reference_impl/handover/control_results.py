"""What the operator-control engines report besides messages to send.

Events are frozen dataclasses, not tuples, on purpose: a node that unpacks every action as
`(msg, to)` (a `Send`) fails loudly on one instead of sending garbage.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum


# --- vehicle side --------------------------------------------------------------------------
@dataclass(frozen=True)
class OwnerLost:
    """The controlling GCS fell silent: "If all owning GCS are disconnected the vehicle should
    GCS loss failsafe". The manager has already dropped it; the failsafe is the caller's."""

    sysid: int
    last_heard: float
    at: float


@dataclass(frozen=True)
class ControlChanged:
    """`gcs_main` or the takeover flag changed (CONTROL_STATUS was sent at once)."""

    owner: int               # 0: none
    previous: int
    takeover_allowed: bool
    reason: str


@dataclass(frozen=True)
class Refusal:
    """Why the filter stopped a message from a GCS not in control, and what to answer."""

    reason: str
    actions: tuple           # Send actions (empty: the message has no answer, it is dropped)


# --- GCS side ------------------------------------------------------------------------------
class ControlOperation(Enum):
    REQUEST = "request control"
    RELEASE = "release control"
    ALLOW_TAKEOVER = "allow takeover"
    DISALLOW_TAKEOVER = "disallow takeover"
    ANSWER_ALLOW = "answer a forwarded request: allow takeover"
    ANSWER_RELEASE = "answer a forwarded request: release"
    CLOSE_WINDOW = "takeover window over: disallow takeover"


class ControlOutcome(Enum):
    GRANTED = "granted"                # ACCEPTED: we hold control (request / takeover flag set)
    RELEASED = "released"              # ACCEPTED to a release
    REFUSED = "refused"                # FAILED: takeover needs the owner's permission, none came
    NOT_IN_CONTROL = "not_in_control"  # MAV_RESULT_NOT_IN_CONTROL
    REJECTED = "rejected"              # any other result (DENIED, UNSUPPORTED, ...)
    TIMEOUT = "timeout"                # no COMMAND_ACK after every retry: outcome unknown


@dataclass(frozen=True)
class ControlResult:
    operation: ControlOperation
    outcome: ControlOutcome
    result: int | None = None          # the MAV_RESULT of the last COMMAND_ACK
    retries: int = 0
    detail: str = ""
    started: float = 0.0
    finished: float = 0.0

    @property
    def ok(self) -> bool:
        return self.outcome in (ControlOutcome.GRANTED, ControlOutcome.RELEASED)


class Decision(Enum):
    """The owner's answer to a forwarded request ("may choose to release control of the
    vehicle, or re-request control with the takeover bit set to allow permission")."""

    ALLOW = "allow takeover"
    RELEASE = "release control"
    REFUSE = "refuse (no answer: the request times out)"


@dataclass(frozen=True)
class TakeoverRequested:
    """Another GCS asked for control and the vehicle forwarded it to us, the owner."""

    requester: int
    allow_takeover: bool     # the requester's own param 2
    timeout: float           # param 3 (s): when the request counts as refused
    at: float


@dataclass(frozen=True)
class StatusChanged:
    """CONTROL_STATUS from the vehicle says something new about who is in control."""

    owner: int
    previous: int
    takeover_allowed: bool
