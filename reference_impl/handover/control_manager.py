"""The vehicle's system manager for operator control, as a sans-IO state machine.

MAVLink development.xml, MAV_CMD_REQUEST_OPERATOR_CONTROL and CONTROL_STATUS. Two rules,
after h11's `_state.py`:
- Every change of `state` goes through `_move`, which consults `MANAGER_TRANSITIONS`; a move
  the table does not list is a bug here and raises at once.
- No I/O, no clock: frames and the time come in through `handle(frame, now)` / `poll(now)`;
  messages go out as `Send` actions, happenings as `OwnerLost` / `ControlChanged`.

Theory of operation. One GCS may own `gcs_main` (single-owner mode). A request is granted
with ACCEPTED when no one owns control or the owner allows takeover; otherwise it is refused
with FAILED and the same command goes to the owner (resent until the owner's COMMAND_ACK,
a bounded number of times). The owner answers by releasing (control becomes free) or by
re-requesting with takeover allowed, which opens a window of `takeover_window` seconds
(the XML's "10 seconds") in which requests are granted; unanswered, the request counts as
refused after its param 3 timeout. CONTROL_STATUS goes out every `status_period` and at
once on every change. An owner silent for `owner_loss_timeout` is dropped and reported
(`OwnerLost`); the failsafe itself is the caller's.

`screen(frame)` is the filter the vehicle puts in front of its command and mission
handlers: a pure function of the current owner, returning what to answer a GCS not in
control, or None to let the message through.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import common as _bundled

from ..state_table import next_state
from ..mission.actions import Peer, Send
from ..wire.dialect import mavlink as _d
from ..wire.frame import Frame
from . import control_messages as cm
from .control_results import ControlChanged, OwnerLost, Refusal
from .control_transitions import MANAGER_TRANSITIONS, ControlEvent, ControlState

Action = Send | OwnerLost | ControlChanged

_S, _E = ControlState, ControlEvent


def _command_ids(*names: str) -> frozenset[int]:
    """Command ids by name, from our dialect or else pymavlink's common (ours is narrow)."""
    return frozenset(v for v in (getattr(_d, n, getattr(_bundled, n, None)) for n in names) if v is not None)


# "Messages and commands that don't control or change vehicle movement or functionality,
# such as telemetry requests, may still be send from (and to) a controlled system."
FREE_COMMANDS = frozenset({cm.REQUEST_CONTROL}) | _command_ids(
    "MAV_CMD_REQUEST_MESSAGE", "MAV_CMD_SET_MESSAGE_INTERVAL", "MAV_CMD_GET_MESSAGE_INTERVAL",
    "MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES", "MAV_CMD_REQUEST_PROTOCOL_VERSION",
    "MAV_CMD_GET_HOME_POSITION", "MAV_CMD_REQUEST_CAMERA_INFORMATION")
# Mission writes: refused with MISSION_ACK MAV_MISSION_DENIED (downloads stay free: reads).
MISSION_WRITES = frozenset({"MISSION_COUNT", "MISSION_WRITE_PARTIAL_LIST", "MISSION_ITEM",
                            "MISSION_ITEM_INT", "MISSION_CLEAR_ALL"})
# State-changing messages with no answer of their own: dropped.
SILENT_STATE_CHANGES = frozenset({
    "SET_MODE", "PARAM_SET", "PARAM_EXT_SET", "MANUAL_CONTROL", "RC_CHANNELS_OVERRIDE",
    "SET_POSITION_TARGET_LOCAL_NED", "SET_POSITION_TARGET_GLOBAL_INT", "SET_ATTITUDE_TARGET",
    "SET_HOME_POSITION", "SET_GPS_GLOBAL_ORIGIN", "SET_ACTUATOR_CONTROL_TARGET"})


def refuse_state_change(msg: Any, src: Peer, who: str, command_result: int, why: str) -> Refusal | None:
    """The answer to a state-changing message from `src` that may not change state now (`who`
    says why, for the log), or None for one that moves nothing: commands get COMMAND_ACK
    `command_result` (telemetry requests and 32100 itself pass), mission writes MISSION_ACK
    MAV_MISSION_DENIED, a set-current a STATUSTEXT (as the mission protocol reports a refused
    one, "Set current refused: `why`"), streams such as MANUAL_CONTROL are dropped unanswered."""
    name = msg._type
    if name in ("COMMAND_LONG", "COMMAND_INT"):
        if msg.command in FREE_COMMANDS:
            return None
        ack = cm.command_ack(msg.command, command_result, src)
        return Refusal(f"{name} {msg.command}: {who}", (Send(ack, src),))
    if name in MISSION_WRITES:
        ack = cm.mission_ack(_d.MAV_MISSION_DENIED, msg.mission_type, src)
        return Refusal(f"{name}: {who}", (Send(ack, src),))
    if name == "MISSION_SET_CURRENT":
        text = cm.statustext(_d.MAV_SEVERITY_WARNING, f"Set current refused: {why}")
        return Refusal(f"{name}: {who}", (Send(text, src),))
    if name in SILENT_STATE_CHANGES:
        return Refusal(f"{name}: {who}", ())
    return None


@dataclass(frozen=True)
class ManagerConfig:
    status_period: float = 1.0            # "nominally 1 Hz"
    owner_loss_timeout: float = 5.0       # s without the owner's HEARTBEAT before it is lost
    takeover_window: float = cm.TAKEOVER_WINDOW
    notify_timeout: float = 1.5           # s to wait for the owner's ACK of a forwarded request
    notify_retries: int = 3               # resends of a forwarded request
    # Unowned, may any GCS command? The XML binds only "a controlled system"; the handover
    # design refuses commands from every GCS without authority, so the default is no.
    open_when_unowned: bool = False
    system_manager: bool = True           # set GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER

    def __post_init__(self) -> None:
        if min(self.status_period, self.owner_loss_timeout, self.takeover_window, self.notify_timeout) <= 0:
            raise ValueError("periods and timeouts must be positive")
        if self.notify_retries < 0:
            raise ValueError("notify_retries must be >= 0")


@dataclass
class _Pending:
    """A refused request forwarded to the owner, waiting for its answer."""

    requester: Peer
    allow_takeover: bool
    timeout: float                # the request's param 3, clamped
    until: float                  # refused after this
    notify_at: float | None       # next resend; None once acknowledged or resends spent
    notify_left: int
    sent: int = 0                 # forwards sent so far (the resend's `confirmation`)

    def notify(self, owner: Peer) -> Any:
        """"this same command", to the owner; resends count up `confirmation`."""
        msg = cm.request_command(owner, cm.ACTION_REQUEST, self.allow_takeover, self.timeout,
                                 self.requester[0], confirmation=min(self.sent, 255))
        self.sent += 1
        return msg


@dataclass
class ManagerStats:
    granted: int = 0
    refused: int = 0
    forwarded: int = 0
    notify_resends: int = 0
    released: int = 0
    owners_lost: int = 0
    history: list[tuple[ControlState, ControlEvent, ControlState]] = field(default_factory=list)


class ControlManager:
    """Vehicle-side operator control: `handle` frames, `poll` timers, send what it returns."""

    def __init__(self, system: int, component: int, config: ManagerConfig | None = None, *,
                 record_history: bool = False) -> None:
        self.system = system
        self.component = component
        self.config = config or ManagerConfig()
        self.state = ControlState.UNOWNED
        self.owner = 0                         # gcs_main
        self.owner_peer: Peer | None = None    # where forwarded requests go
        self.window_for = 0                    # the requester a WINDOW_OPEN was opened for
        self.stats = ManagerStats()
        self.recent: deque[tuple[ControlState, ControlEvent, ControlState]] = deque(maxlen=256)
        self._record = record_history
        self._last_heard = 0.0
        self._pending: _Pending | None = None
        self._window_until: float | None = None
        self._next_status = 0.0                # the first poll sends CONTROL_STATUS

    # --- public surface -------------------------------------------------------------------
    @property
    def takeover_allowed(self) -> bool:
        """GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED: the owner lets requests be granted."""
        return self.state in (_S.OWNED_TAKEOVER_ALLOWED, _S.WINDOW_OPEN)

    @property
    def pending_requester(self) -> int:
        return 0 if self._pending is None else self._pending.requester[0]

    def may_command(self, sysid: int) -> bool:
        """"A controlled system should only accept MAVLink operations that change the state of
        the vehicle ... sent by its controlling GCS(s) (or from other components in its own
        system/with the same system id, such as a companion computer).\""""
        if sysid == self.system:
            return True
        if self.owner:
            return sysid == self.owner
        return self.config.open_when_unowned

    def consumes(self, msg: Any) -> bool:
        """Messages that are the manager's alone (the vehicle routes them nowhere else)."""
        return cm.is_request_control(msg) or (msg._type == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL)

    def status_message(self) -> Any:
        return cm.control_status(self.owner, takeover_allowed=self.takeover_allowed,
                                 system_manager=self.config.system_manager)

    def handle(self, frame: Frame, now: float) -> list[Action]:
        """Any frame may come in: HEARTBEATs keep the owner alive, requests and the owner's
        ACKs of forwarded requests drive the machine, the rest is ignored."""
        msg, src = frame.msg, frame.source
        name = msg._type
        if name == "HEARTBEAT":
            if src[0] == self.owner:
                self._heard(now)
            return []
        if not cm.addressed_to(msg, self.system, self.component):
            return []
        if name == "COMMAND_ACK":
            if msg.command == cm.REQUEST_CONTROL and src[0] == self.owner:
                self._heard(now)
                if self._pending is not None:
                    self._pending.notify_at = None   # "That owning GCS must ACK"
            return []
        if cm.is_request_control(msg):
            return self._on_request(msg, src, now)
        return []

    def poll(self, now: float) -> list[Action]:
        out: list[Action] = []
        cfg = self.config
        if self.owner and now >= self._last_heard + cfg.owner_loss_timeout:
            out += self._lose_owner(now)
        p = self._pending
        if p is not None:
            if now >= p.until:
                # param 3: "Timeout in seconds before a request to a GCS to allow takeover is
                # assumed to be rejected."
                self._pending = None
                self._move(_E.REQUEST_EXPIRED)
            elif p.notify_at is not None and now >= p.notify_at:
                p.notify_left -= 1
                p.notify_at = now + cfg.notify_timeout if p.notify_left > 0 else None
                self.stats.notify_resends += 1
                self._move(_E.NOTIFY_RETRY)
                out.append(Send(p.notify(self.owner_peer), self.owner_peer))
        if self._window_until is not None and now >= self._window_until:
            out += self._change(self._close_window, "takeover window closed", now)
        if now >= self._next_status:
            out.append(Send(self.status_message()))
            self._next_status = now + cfg.status_period
        return out

    def next_deadline(self) -> float:
        """Always defined: CONTROL_STATUS is streamed whatever the state."""
        best = self._next_status
        if self.owner:
            best = min(best, self._last_heard + self.config.owner_loss_timeout)
        p = self._pending
        if p is not None:
            best = min(best, p.until if p.notify_at is None else min(p.until, p.notify_at))
        if self._window_until is not None:
            best = min(best, self._window_until)
        return best

    def screen(self, frame: Frame) -> Refusal | None:
        """The refusal for a message from a GCS not in control, or None to let it through.

        Pure (no state change): the vehicle calls it before its own handlers. "Commands to
        control the vehicle from other systems should be rejected with MAV_RESULT_NOT_IN_CONTROL
        (except for this command ...)"; mission writes get MISSION_ACK MAV_MISSION_DENIED;
        "telemetry requests, may still be send"."""
        src, msg = frame.source, frame.msg
        if self.may_command(src[0]) or not cm.addressed_to(msg, self.system, self.component):
            return None
        return refuse_state_change(msg, src, f"GCS {src[0]} is not in control (gcs_main {self.owner})",
                                   _d.MAV_RESULT_NOT_IN_CONTROL, "not in control")

    def withdraw(self, requester: int, now: float) -> list[Action]:
        """End a forwarded request from `requester`, or a takeover window opened for it, now,
        as if it had timed out (the table's REQUEST_EXPIRED / WINDOW_CLOSED): the vehicle's
        mission computer gave up a handover, which must not complete later."""
        if self._pending is not None and self._pending.requester[0] == requester:
            self._pending = None
            self._move(_E.REQUEST_EXPIRED)
            return []
        if self._window_until is not None and self.window_for == requester:
            return self._change(self._close_window, f"takeover window for GCS {requester} withdrawn", now)
        return []

    # --- requests -------------------------------------------------------------------------
    def _on_request(self, msg: Any, src: Peer, now: float) -> list[Action]:
        sysid = src[0]
        action, allow, requested_for = msg.param1, msg.param2, msg.param4
        # param 1 "0: Release control, 1: Request control"; param 2 "0: Ask current owner and
        # reject request, 1: Allow automatic takeover": anything else is an invalid param.
        if action not in (0, 1) or allow not in (0, 1):
            return [self._ack(src, _d.MAV_RESULT_DENIED)]
        # param 4 and "the sender of the command must have a system id that is in the
        # requested range"; single-owner mode holds one id, so param 4 is 0 or the sender.
        if requested_for not in (0, sysid) or sysid == 0:
            return [self._ack(src, _d.MAV_RESULT_DENIED)]
        if sysid == self.owner:
            self._heard(now)
        if action == 0:
            return self._on_release(src, now)
        if sysid == self.owner:
            return self._on_owner_request(src, allow == 1, now)
        if self.state is _S.UNOWNED or self.takeover_allowed:
            return self._grant(src, allow == 1, now)
        return self._refuse(src, allow == 1, cm.clamp_timeout(msg.param3), now)

    def _grant(self, src: Peer, allow: bool, now: float) -> list[Action]:
        """"should grant control to the requested GCS(s) if the system does not require
        takeover permission (or is uncontrolled) and ACK the request with MAV_RESULT_ACCEPTED\""""
        self.stats.granted += 1

        def apply() -> None:
            self._move(_E.GRANT_ALLOWING if allow else _E.GRANT)
            self.owner, self.owner_peer, self._last_heard = src[0], src, now
            self._clear_request()
        return [self._ack(src, _d.MAV_RESULT_ACCEPTED), *self._change(apply, f"granted to GCS {src[0]}", now)]

    def _refuse(self, src: Peer, allow: bool, timeout: float, now: float) -> list[Action]:
        """"the request should be rejected with MAV_RESULT_FAILED. The system manager component
        should then send this same command to the owning GCS ... in order to notify of the
        request." A repeat of the request being forwarded is refused, not forwarded again."""
        self.stats.refused += 1
        refusal = self._ack(src, _d.MAV_RESULT_FAILED)
        if self._pending is not None and self._pending.requester[0] == src[0]:
            self._move(_E.REFUSE_REPEAT)
            return [refusal]
        self._move(_E.REFUSE_AND_FORWARD)
        self.stats.forwarded += 1
        retries = self.config.notify_retries
        p = self._pending = _Pending(src, allow, timeout, now + timeout,
                                     now + self.config.notify_timeout if retries else None, retries)
        return [refusal, Send(p.notify(self.owner_peer), self.owner_peer)]

    def _on_owner_request(self, src: Peer, allow: bool, now: float) -> list[Action]:
        """The owner re-requests: it sets the takeover flag ("re-request control with the
        takeover bit set to allow permission"). Allowing while a forwarded request waits
        opens the takeover window for it."""
        def apply() -> None:
            pending = self._pending
            if allow:
                self._move(_E.OWNER_ALLOWS)
                if self.state is _S.WINDOW_OPEN and pending is not None:
                    self.window_for = pending.requester[0]
                    self._window_until = now + self.config.takeover_window
                    self._pending = None
            else:
                self._move(_E.OWNER_DISALLOWS)
                self._clear_request()
        what = "takeover allowed" if allow else "takeover disallowed"
        return [self._ack(src, _d.MAV_RESULT_ACCEPTED), *self._change(apply, f"{what} by GCS {src[0]}", now)]

    def _on_release(self, src: Peer, now: float) -> list[Action]:
        """Release (param 1 = 0). Only the owner holds something to release; anyone else is
        told MAV_RESULT_NOT_IN_CONTROL."""
        if src[0] != self.owner:
            return [self._ack(src, _d.MAV_RESULT_NOT_IN_CONTROL)]
        self.stats.released += 1
        return [self._ack(src, _d.MAV_RESULT_ACCEPTED),
                *self._change(lambda: self._drop_owner(_E.RELEASE), f"released by GCS {src[0]}", now)]

    def _lose_owner(self, now: float) -> list[Action]:
        """"If all owning GCS are disconnected the vehicle should GCS loss failsafe, and
        broadcast a CONTROL_STATUS indicating that it has no owner(s).\""""
        self.stats.owners_lost += 1
        lost = OwnerLost(self.owner, self._last_heard, now)
        return [lost, *self._change(lambda: self._drop_owner(_E.OWNER_LOST), f"GCS {self.owner} lost", now)]

    # --- internals ------------------------------------------------------------------------
    def _change(self, apply: Any, reason: str, now: float) -> list[Action]:
        """Run `apply`; if gcs_main or the takeover flag changed, say so: CONTROL_STATUS now
        ("emitted when ownership or takeover status change") and a ControlChanged event."""
        before = (self.owner, self.takeover_allowed)
        apply()
        if (self.owner, self.takeover_allowed) == before:
            return []
        self._next_status = now + self.config.status_period
        return [Send(self.status_message()),
                ControlChanged(self.owner, before[0], self.takeover_allowed, reason)]

    def _close_window(self) -> None:
        self._move(_E.WINDOW_CLOSED)
        self._clear_request()

    def _drop_owner(self, event: ControlEvent) -> None:
        self._move(event)
        self.owner, self.owner_peer = 0, None
        self._clear_request()

    def _clear_request(self) -> None:
        self._pending, self._window_until, self.window_for = None, None, 0

    def _heard(self, now: float) -> None:
        self._last_heard = now

    def _ack(self, to: Peer, result: int) -> Send:
        return Send(cm.command_ack(cm.REQUEST_CONTROL, result, to), to)

    def _move(self, event: ControlEvent) -> None:
        old = self.state
        new = next_state(MANAGER_TRANSITIONS, old, event, "operator control")
        self.state = new
        self.recent.append((old, event, new))
        if self._record:
            self.stats.history.append((old, event, new))
