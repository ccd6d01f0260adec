"""Transition tables of the operator-control engines: state -> event -> new state, as data.

MAV_CMD_REQUEST_OPERATOR_CONTROL and CONTROL_STATUS (MAVLink development.xml). The engines
move only through these tables (an unlisted move raises `LocalProtocolError`), so a test can
walk them and a report can draw them, as for the mission engines (mission/transitions.py).

Single-owner mode only: one `gcs_main`, `gcs_secondary` all zero ("All values should be zero
for single-owner mode").
"""

from __future__ import annotations

from enum import Enum


class ControlState(Enum):
    """The system manager's view of who owns `gcs_main`."""

    UNOWNED = "unowned"                                 # gcs_main = 0: requests are granted
    OWNED = "owned"                                     # takeover needs the owner's permission
    OWNED_TAKEOVER_ALLOWED = "owned, takeover allowed"  # requests are granted
    REQUEST_PENDING = "owned, a refused request forwarded to the owner"
    WINDOW_OPEN = "owned, takeover allowed for a while after a forwarded request"


class ControlEvent(Enum):
    GRANT = "request granted; the new owner disallows takeover"
    GRANT_ALLOWING = "request granted; the new owner allows takeover"
    REFUSE_AND_FORWARD = "request refused (FAILED), forwarded to the owner"
    REFUSE_REPEAT = "repeated request refused, already forwarded"
    NOTIFY_RETRY = "forwarded request resent: the owner has not acknowledged it"
    OWNER_ALLOWS = "owner re-requested with takeover allowed"
    OWNER_DISALLOWS = "owner re-requested with takeover disallowed"
    RELEASE = "owner released control"
    REQUEST_EXPIRED = "the owner did not answer within the request timeout"
    WINDOW_CLOSED = "the takeover window elapsed"
    OWNER_LOST = "no HEARTBEAT from the owner for the loss timeout"


_S, _E = ControlState, ControlEvent
_OWNED = (_S.OWNED, _S.OWNED_TAKEOVER_ALLOWED, _S.REQUEST_PENDING, _S.WINDOW_OPEN)

MANAGER_TRANSITIONS: dict[tuple[ControlState, ControlEvent], ControlState] = {
    # "should grant control ... if the system does not require takeover permission (or is uncontrolled)"
    (_S.UNOWNED, _E.GRANT): _S.OWNED,
    (_S.UNOWNED, _E.GRANT_ALLOWING): _S.OWNED_TAKEOVER_ALLOWED,
    (_S.OWNED_TAKEOVER_ALLOWED, _E.GRANT): _S.OWNED,
    (_S.OWNED_TAKEOVER_ALLOWED, _E.GRANT_ALLOWING): _S.OWNED_TAKEOVER_ALLOWED,
    (_S.WINDOW_OPEN, _E.GRANT): _S.OWNED,
    (_S.WINDOW_OPEN, _E.GRANT_ALLOWING): _S.OWNED_TAKEOVER_ALLOWED,
    # "rejected with MAV_RESULT_FAILED ... then send this same command to the owning GCS"
    (_S.OWNED, _E.REFUSE_AND_FORWARD): _S.REQUEST_PENDING,
    (_S.REQUEST_PENDING, _E.REFUSE_AND_FORWARD): _S.REQUEST_PENDING,
    (_S.REQUEST_PENDING, _E.REFUSE_REPEAT): _S.REQUEST_PENDING,
    (_S.REQUEST_PENDING, _E.NOTIFY_RETRY): _S.REQUEST_PENDING,
    (_S.REQUEST_PENDING, _E.REQUEST_EXPIRED): _S.OWNED,
    # the owner's answer: "may choose to release control ..., or re-request control with the
    # takeover bit set to allow permission"
    (_S.OWNED, _E.OWNER_ALLOWS): _S.OWNED_TAKEOVER_ALLOWED,
    (_S.OWNED_TAKEOVER_ALLOWED, _E.OWNER_ALLOWS): _S.OWNED_TAKEOVER_ALLOWED,
    (_S.REQUEST_PENDING, _E.OWNER_ALLOWS): _S.WINDOW_OPEN,
    (_S.WINDOW_OPEN, _E.OWNER_ALLOWS): _S.WINDOW_OPEN,
    (_S.OWNED, _E.OWNER_DISALLOWS): _S.OWNED,
    (_S.OWNED_TAKEOVER_ALLOWED, _E.OWNER_DISALLOWS): _S.OWNED,
    (_S.REQUEST_PENDING, _E.OWNER_DISALLOWS): _S.OWNED,
    (_S.WINDOW_OPEN, _E.OWNER_DISALLOWS): _S.OWNED,
    # "the requester GCS will only have 10 seconds to get control"
    (_S.WINDOW_OPEN, _E.WINDOW_CLOSED): _S.OWNED,
    **{(s, _E.RELEASE): _S.UNOWNED for s in _OWNED},
    # "If all owning GCS are disconnected the vehicle should GCS loss failsafe, and broadcast
    # a CONTROL_STATUS indicating that it has no owner(s)."
    **{(s, _E.OWNER_LOST): _S.UNOWNED for s in _OWNED},
}

# CONTROL_STATUS flag GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED: "requests for control will be granted".
GRANTING_STATES = frozenset({_S.UNOWNED, _S.OWNED_TAKEOVER_ALLOWED, _S.WINDOW_OPEN})


class ClientState(Enum):
    """The GCS side: one operator-control command at a time."""

    IDLE = "idle"
    COMMAND_SENT = "MAV_CMD_REQUEST_OPERATOR_CONTROL sent, waiting for COMMAND_ACK"
    WAITING_FOR_OWNER = "request refused; waiting for the owner to release or allow takeover"


class ClientEvent(Enum):
    SEND = "command sent"
    TIMEOUT_RETRY = "no COMMAND_ACK: command resent"
    REFUSED_WAITING = "request refused (FAILED): waiting for the owner's answer"
    CHANCE = "CONTROL_STATUS shows control free or takeover allowed: request sent again"
    FINISH = "operation ended (granted, released, refused, not in control, rejected, timeout)"


_C, _V = ClientState, ClientEvent
CLIENT_TRANSITIONS: dict[tuple[ClientState, ClientEvent], ClientState] = {
    (_C.IDLE, _V.SEND): _C.COMMAND_SENT,
    (_C.COMMAND_SENT, _V.TIMEOUT_RETRY): _C.COMMAND_SENT,
    (_C.COMMAND_SENT, _V.REFUSED_WAITING): _C.WAITING_FOR_OWNER,
    (_C.WAITING_FOR_OWNER, _V.CHANCE): _C.COMMAND_SENT,
    (_C.COMMAND_SENT, _V.FINISH): _C.IDLE,
    (_C.WAITING_FOR_OWNER, _V.FINISH): _C.IDLE,
}
