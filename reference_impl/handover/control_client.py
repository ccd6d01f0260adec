"""The GCS side of operator control, as a sans-IO state machine.

MAVLink development.xml, MAV_CMD_REQUEST_OPERATOR_CONTROL and CONTROL_STATUS. Like the
mission client: moves only through `CLIENT_TRANSITIONS`, no I/O, no clock, one command in
flight, every operation ends with exactly one `Finished(ControlResult)`.

Theory of operation. The client follows the system manager's CONTROL_STATUS (who owns
`gcs_main`, whether takeover is allowed, and which component to address: "address the
MAV_CMD_REQUEST_OPERATOR_CONTROL to its component id"). Commands are resent with a rising
`confirmation` until their COMMAND_ACK, `max_retries` times at most. A refused request
(FAILED) may wait, at most its own param 3 timeout, for the owner's answer: when
CONTROL_STATUS shows control free or takeover allowed, the request goes out again.

As the owner, the client answers a request the vehicle forwards: it ACKs it at once ("That
owning GCS must ACK with MAV_RESULT_ACCEPTED"), reports `TakeoverRequested`, and applies
the injected policy (allow, release, refuse, or None to let the operator `answer` later).
Allowing re-requests control with takeover allowed and, `takeover_window` later, with it
disallowed again ("the requester GCS will only have 10 seconds to get control, otherwise
owning GCS will re-request control with takeover bit set to disallow permission").
Answers run as operations of their own, queued behind the one in flight.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import LocalProtocolError
from ..state_table import next_state
from ..mission.actions import Finished, Peer, Send
from ..wire.dialect import mavlink as _d
from ..wire.frame import Frame
from . import control_messages as cm
from .control_results import (ControlOperation, ControlOutcome, ControlResult, Decision, StatusChanged,
                              TakeoverRequested)
from .control_transitions import CLIENT_TRANSITIONS, ClientEvent, ClientState

Action = Send | Finished | TakeoverRequested | StatusChanged
Policy = Callable[[TakeoverRequested], "Decision | None"]

_C, _V = ClientState, ClientEvent
_O = ControlOperation
_RELEASES = frozenset({_O.RELEASE, _O.ANSWER_RELEASE})


def always(decision: Decision | None) -> Policy:
    """A policy that gives the same answer to every forwarded request."""
    return lambda request: decision


@dataclass(frozen=True)
class ClientConfig:
    ack_timeout: float = 1.5              # s to wait for a COMMAND_ACK
    max_retries: int = 4                  # resends of one command
    request_timeout: float = cm.DEFAULT_REQUEST_TIMEOUT   # param 3 of our requests
    takeover_window: float = cm.TAKEOVER_WINDOW

    def __post_init__(self) -> None:
        if self.ack_timeout <= 0 or self.takeover_window <= 0:
            raise ValueError("timeouts must be positive")
        if self.max_retries < 0:
            raise ValueError("max_retries must be >= 0")
        _check_timeout(self.request_timeout)


def _check_timeout(value: float) -> None:
    if not cm.TIMEOUT_MIN <= value <= cm.TIMEOUT_MAX:
        raise LocalProtocolError(f"request timeout {value} s is outside the XML's "
                                 f"{cm.TIMEOUT_MIN:g}..{cm.TIMEOUT_MAX:g} s (param 3)")


@dataclass
class _Op:
    operation: ControlOperation
    allow: bool
    timeout: float
    wait: bool
    user: bool
    started: float = 0.0
    msg: Any = None
    retries: int = 0            # resends in all
    consecutive: int = 0        # resends of the current command
    deadline: float | None = None
    wait_until: float | None = None
    chances: int = 0            # requests sent again while waiting

    @property
    def release(self) -> bool:
        return self.operation in _RELEASES


@dataclass
class _Forwarded:
    requester: int
    until: float
    answered: bool


class ControlClient:
    """GCS-side operator control for one target vehicle."""

    def __init__(self, system: int, component: int, target: Peer, config: ClientConfig | None = None,
                 *, policy: Policy = always(None)) -> None:
        self.system = system
        self.component = component
        self.target = target
        self.config = config or ClientConfig()
        self.policy = policy
        self.state = ClientState.IDLE
        self.history: deque[tuple[ClientState, ClientEvent, ClientState]] = deque(maxlen=256)
        # the system manager's CONTROL_STATUS, as last heard
        self.owner = 0
        self.takeover_allowed = False
        self.manager: Peer | None = None
        self.stray_acks = 0
        self._op: _Op | None = None
        self._queue: deque[_Op] = deque()
        self._forwarded: _Forwarded | None = None
        self._revert_at: float | None = None

    # --- operations -----------------------------------------------------------------------
    @property
    def in_control(self) -> bool:
        return self.owner == self.system

    @property
    def busy(self) -> bool:
        """A user operation is running or queued (answers to forwarded requests do not count)."""
        return any(op.user for op in (self._op, *self._queue) if op is not None)

    def request_control(self, now: float, *, allow_takeover: bool = False, timeout: float | None = None,
                        wait: bool = True) -> list[Action]:
        """Ask for `gcs_main`. `allow_takeover` is param 2 for when we hold it; `timeout` is
        param 3; with `wait`, a refusal waits up to it for the owner to let us in."""
        timeout = self.config.request_timeout if timeout is None else timeout
        _check_timeout(timeout)
        return self._user(_Op(_O.REQUEST, allow_takeover, timeout, wait, True), now)

    def release_control(self, now: float) -> list[Action]:
        self._revert_at = None
        return self._user(_Op(_O.RELEASE, False, self.config.request_timeout, False, True), now)

    def set_takeover(self, allowed: bool, now: float) -> list[Action]:
        """The owner sets the takeover flag by re-requesting control with param 2."""
        if not self.in_control:
            raise LocalProtocolError(f"GCS {self.system} is not in control (gcs_main {self.owner}): "
                                     "setting the takeover flag would request control")
        self._revert_at = None
        operation = _O.ALLOW_TAKEOVER if allowed else _O.DISALLOW_TAKEOVER
        return self._user(_Op(operation, allowed, self.config.request_timeout, False, True), now)

    def answer(self, decision: Decision, now: float) -> list[Action]:
        """The operator's answer to the last forwarded request (a policy that returned None).
        Too late (its timeout passed) or already answered: nothing happens."""
        f = self._forwarded
        if f is None or f.answered or now >= f.until:
            return []
        f.answered = True
        return self._apply(decision, now)

    # --- events ---------------------------------------------------------------------------
    def handle(self, frame: Frame, now: float) -> list[Action]:
        msg, src = frame.msg, frame.source
        if src[0] != self.target[0]:
            return []
        name = msg._type
        if name == "CONTROL_STATUS":
            return self._on_status(msg, src, now)
        if not cm.addressed_to(msg, self.system, self.component):
            return []
        if name == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL:
            return self._on_ack(msg, now)
        if cm.is_request_control(msg):
            return self._on_forwarded(msg, src, now)
        return []

    def poll(self, now: float) -> list[Action]:
        out: list[Action] = []
        if self._revert_at is not None and now >= self._revert_at:
            self._revert_at = None
            if self.in_control:
                out += self._internal(_O.CLOSE_WINDOW, False, now)
        op = self._op
        if op is None:
            return out
        if self.state is _C.WAITING_FOR_OWNER and now >= op.wait_until:
            return out + self._finish(now, ControlOutcome.REFUSED, _d.MAV_RESULT_FAILED,
                                      f"the owner did not release or allow takeover within {op.timeout:g} s")
        if self.state is _C.COMMAND_SENT and now >= op.deadline:
            if op.consecutive >= self.config.max_retries:
                return out + self._finish(now, ControlOutcome.TIMEOUT, None,
                                          f"no COMMAND_ACK after {op.consecutive} retries")
            op.retries += 1
            op.consecutive += 1
            self._move(_V.TIMEOUT_RETRY)
            out.append(self._send(op, now, confirmation=op.consecutive))
        return out

    def next_deadline(self) -> float | None:
        best = self._revert_at
        op = self._op
        if op is not None:
            d = op.wait_until if self.state is _C.WAITING_FOR_OWNER else op.deadline
            if d is not None and (best is None or d < best):
                best = d
        return best

    # --- handlers -------------------------------------------------------------------------
    def _on_status(self, msg: Any, src: Peer, now: float) -> list[Action]:
        """Follow the system manager ("A GCS that wants to control the system should also
        monitor for the same message and flag")."""
        if not msg.flags & cm.FLAG_SYSTEM_MANAGER:
            return []
        self.manager = src
        previous, was_allowed = self.owner, self.takeover_allowed
        self.owner, self.takeover_allowed = msg.gcs_main, bool(msg.flags & cm.FLAG_TAKEOVER_ALLOWED)
        out: list[Action] = []
        if (self.owner, self.takeover_allowed) != (previous, was_allowed):
            out.append(StatusChanged(self.owner, previous, self.takeover_allowed))
        if not self.in_control:
            self._revert_at = None   # control moved away: nothing left to revert
            self._forwarded = None   # nor to answer: a later forward from the same GCS is a new one
        op = self._op
        if self.state is _C.WAITING_FOR_OWNER and op is not None:
            if self.in_control:
                out += self._finish(now, ControlOutcome.GRANTED, _d.MAV_RESULT_ACCEPTED, "CONTROL_STATUS names us")
            elif self._chance(op):
                op.chances += 1
                op.consecutive = 0
                self._move(_V.CHANCE)
                out.append(self._send(op, now))
        return out

    def _chance(self, op: _Op) -> bool:
        return (self.owner == 0 or self.takeover_allowed) and op.chances <= self.config.max_retries

    def _on_ack(self, msg: Any, now: float) -> list[Action]:
        op = self._op
        if op is None or self.state is not _C.COMMAND_SENT:
            self.stray_acks += 1
            return []
        r = msg.result
        if r == _d.MAV_RESULT_IN_PROGRESS:
            return []
        if r == _d.MAV_RESULT_ACCEPTED:
            return self._accepted(op, now)
        if r == _d.MAV_RESULT_FAILED and op.operation is _O.REQUEST:
            # "If the system manager component cannot grant control because takeover requires
            # permission, the request should be rejected with MAV_RESULT_FAILED."
            if op.wait_until is None:
                op.wait_until = now + op.timeout + self.config.ack_timeout
            if op.wait and now < op.wait_until:
                self._move(_V.REFUSED_WAITING)
                if self._chance(op):      # the way opened before this refusal arrived
                    op.chances += 1
                    op.consecutive = 0
                    self._move(_V.CHANCE)
                    return [self._send(op, now)]
                return []
            return self._finish(now, ControlOutcome.REFUSED, r, "takeover needs the owner's permission")
        if r == _d.MAV_RESULT_NOT_IN_CONTROL:
            return self._finish(now, ControlOutcome.NOT_IN_CONTROL, r, "the vehicle says we are not in control")
        return self._finish(now, ControlOutcome.REJECTED, r, f"COMMAND_ACK result {r}")

    def _accepted(self, op: _Op, now: float) -> list[Action]:
        if op.release:
            if self.owner == self.system:
                self.owner = 0
            self._revert_at = None
            return self._finish(now, ControlOutcome.RELEASED, _d.MAV_RESULT_ACCEPTED)
        self.owner = self.system        # the ACK is the vehicle's word until CONTROL_STATUS
        self.takeover_allowed = op.allow
        if op.operation is _O.ANSWER_ALLOW:
            self._revert_at = now + self.config.takeover_window
        return self._finish(now, ControlOutcome.GRANTED, _d.MAV_RESULT_ACCEPTED)

    def _on_forwarded(self, msg: Any, src: Peer, now: float) -> list[Action]:
        """The vehicle forwards another GCS's refused request to us, the owner."""
        out: list[Action] = [Send(cm.command_ack(cm.REQUEST_CONTROL, _d.MAV_RESULT_ACCEPTED, src), src)]
        requester = int(msg.param4) if msg.param4 == msg.param4 else 0
        if msg.param1 != cm.ACTION_REQUEST or requester in (0, self.system):
            return out
        f = self._forwarded
        if f is not None and f.requester == requester and now < f.until:
            return out    # a resend of a notification we already have
        request = TakeoverRequested(requester, msg.param2 == 1, cm.clamp_timeout(msg.param3), now)
        self._forwarded = _Forwarded(requester, now + request.timeout, answered=False)
        out.append(request)
        decision = self.policy(request)
        if decision is not None:
            self._forwarded.answered = True
            out += self._apply(decision, now)
        return out

    def _apply(self, decision: Decision, now: float) -> list[Action]:
        """"That owning GCS ... may choose to release control of the vehicle, or re-request
        control with the takeover bit set to allow permission." Only an owner answers: a
        non-owner's "allow" would be a request for control."""
        if not self.in_control or decision is Decision.REFUSE:
            return []
        if decision is Decision.ALLOW:
            return self._internal(_O.ANSWER_ALLOW, True, now)
        return self._internal(_O.ANSWER_RELEASE, False, now)

    # --- internals ------------------------------------------------------------------------
    def _user(self, op: _Op, now: float) -> list[Action]:
        if self.busy:
            raise LocalProtocolError("an operator-control operation is already running")
        return self._submit(op, now)

    def _internal(self, operation: ControlOperation, allow: bool, now: float) -> list[Action]:
        if any(op.operation is operation for op in self._queue):
            return []
        return self._submit(_Op(operation, allow, self.config.request_timeout, False, False), now)

    def _submit(self, op: _Op, now: float) -> list[Action]:
        op.started = now
        if self._op is not None:
            self._queue.append(op)
            return []
        self._op = op
        self._move(_V.SEND)
        return [self._send(op, now)]

    def _send(self, op: _Op, now: float, confirmation: int = 0) -> Send:
        """Send (or resend, with `confirmation` > 0) the operation's command to the manager."""
        to = self.manager or self.target
        action = cm.ACTION_RELEASE if op.release else cm.ACTION_REQUEST
        op.msg = cm.request_command(to, action, op.allow, op.timeout, self.system, confirmation)
        op.deadline = now + self.config.ack_timeout
        return Send(op.msg, to)

    def _finish(self, now: float, outcome: ControlOutcome, result: int | None, detail: str = "") -> list[Action]:
        op = self._op
        assert op is not None
        self._move(_V.FINISH)
        self._op = None
        out: list[Action] = [Finished(ControlResult(op.operation, outcome, result, op.retries, detail,
                                                    op.started, now))]
        if self._queue:
            nxt = self._queue.popleft()
            self._op = nxt
            self._move(_V.SEND)
            out.append(self._send(nxt, now))
        return out

    def _move(self, event: ClientEvent) -> None:
        old = self.state
        new = next_state(CLIENT_TRANSITIONS, old, event, "operator control client")
        self.state = new
        self.history.append((old, event, new))
