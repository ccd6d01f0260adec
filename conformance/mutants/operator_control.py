"""Mutants that break the operator-control clauses (HO.CTL.*): one system-manager bug each.

Each is the suite's `builtin:spec` vehicle (`target_uri.SUITE_CONTROL`: the reference
`ControlManager`, open while no GCS is in control) with one behaviour of the manager changed,
by a subclass plugged in through `VehicleNode(manager_class=...)` or by one `ManagerConfig`
knob. The bugs are ones a system manager plausibly has (a cached status message, the wrong
MAV_RESULT, a takeover flag that is set but not honoured, a HEARTBEAT taken from anyone), and
none moves the manager outside its transition table, so a mutant fails clauses, never crashes.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_manager import FREE_COMMANDS, ControlManager
from mavconform.reference_impl.handover.control_results import Refusal
from mavconform.reference_impl.handover.control_transitions import ControlState
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.wire.frame import Frame

from ..target_uri import SUITE_CONTROL
from . import mutant


def control_mutant(manager_cls: type[ControlManager] = ControlManager,
                   **knobs: Any) -> Callable[[VehicleConfig], VehicleNode]:
    """A builder for the suite's system-manager vehicle with `manager_cls` as its manager and
    `ManagerConfig` knobs changed."""
    def build(config: VehicleConfig) -> VehicleNode:
        control = dataclasses.replace(SUITE_CONTROL, **knobs)
        return VehicleNode(dataclasses.replace(config, control=control), manager_class=manager_cls)
    return build


def _is_status(action: Any) -> bool:
    return isinstance(action, Send) and action.msg._type == "CONTROL_STATUS"


# --- HO.CTL.02: a request while nobody is in control ------------------------------------------------

class _RefusesWhileUncontrolled(ControlManager):
    """Takes an uncontrolled vehicle for one that needs the owner's permission."""

    def _on_request(self, msg: Any, src: Any, now: float) -> list:
        if self.state is ControlState.UNOWNED and msg.param1 == cm.ACTION_REQUEST:
            return [self._ack(src, _d.MAV_RESULT_FAILED)]
        return super()._on_request(msg, src, now)


# --- HO.CTL.03: release -------------------------------------------------------------------------

class _IgnoresRelease(ControlManager):
    """Acknowledges the owner's release and keeps it in control."""

    def _on_release(self, src: Any, now: float) -> list:
        if src[0] != self.owner:
            return super()._on_release(src, now)
        self._heard(now)
        return [self._ack(src, _d.MAV_RESULT_ACCEPTED)]


# --- HO.CTL.04 / 05 / 01: the CONTROL_STATUS stream ---------------------------------------------------

class _StaleStream(ControlManager):
    """The 1 Hz CONTROL_STATUS is the one built at start-up (nobody in control) and never
    updated; only the message sent on a change says who is in control."""

    def poll(self, now: float) -> list:
        stale = cm.control_status(0, takeover_allowed=False, system_manager=self.config.system_manager)
        return [Send(stale) if _is_status(a) else a for a in super().poll(now)]


class _SilentOnChange(ControlManager):
    """Announces a change only with the stream's next CONTROL_STATUS, not at once."""

    def _change(self, apply: Any, reason: str, now: float) -> list:
        due = self._next_status
        out = [a for a in super()._change(apply, reason, now) if not _is_status(a)]
        self._next_status = due
        return out


# --- HO.CTL.06 / 07: a request while another GCS is in control ----------------------------------------

class _RefusesBusyWithDenied(ControlManager):
    """Refuses a request that needs permission with MAV_RESULT_DENIED (and forwards it)."""

    def _refuse(self, src: Any, allow: bool, timeout: float, now: float) -> list:
        out = super()._refuse(src, allow, timeout, now)
        return [self._ack(src, _d.MAV_RESULT_DENIED), *out[1:]]


class _DoesNotForward(ControlManager):
    """Refuses a request that needs permission and never tells the owner."""

    def _refuse(self, src: Any, allow: bool, timeout: float, now: float) -> list:
        out = super()._refuse(src, allow, timeout, now)
        if self._pending is not None:
            self._pending.notify_at = None   # no resends either
        return [a for a in out if not (isinstance(a, Send) and a.to == self.owner_peer)]


# --- HO.CTL.08 / 09: the takeover flag -------------------------------------------------------------

class _NeverGrantsTakeover(ControlManager):
    """Shows the takeover flag the owner sets, but refuses every request while controlled."""

    def _on_request(self, msg: Any, src: Any, now: float) -> list:
        if (msg.param1 == cm.ACTION_REQUEST and self.owner and src[0] != self.owner
                and self.takeover_allowed):
            return [self._ack(src, _d.MAV_RESULT_FAILED)]   # no state change: no table move
        return super()._on_request(msg, src, now)


class _TakeoverFlagSticks(ControlManager):
    """Once the owner allows takeover, its re-request disallowing it is acknowledged and ignored."""

    def _on_owner_request(self, src: Any, allow: bool, now: float) -> list:
        return super()._on_owner_request(src, allow or self.takeover_allowed, now)


# --- HO.CTL.10 / 11 / 12: the filter in front of commands and mission writes ----------------------------

class _DeniesCommands(ControlManager):
    """Refuses a command from a GCS not in control with MAV_RESULT_DENIED, the pre-operator-
    control habit, not MAV_RESULT_NOT_IN_CONTROL."""

    def screen(self, frame: Frame) -> Refusal | None:
        refusal = super().screen(frame)
        msg, src = frame.msg, frame.source
        if refusal is not None and msg._type in ("COMMAND_LONG", "COMMAND_INT"):
            ack = cm.command_ack(msg.command, _d.MAV_RESULT_DENIED, src)
            return Refusal(refusal.reason, (Send(ack, src),))
        return refusal


class _ScreensCommandsOnly(ControlManager):
    """Filters commands from GCSs not in control, but lets their mission writes through."""

    def screen(self, frame: Frame) -> Refusal | None:
        if frame.msg._type in ("COMMAND_LONG", "COMMAND_INT"):
            return super().screen(frame)
        return None


class _LocksOutReads(ControlManager):
    """Refuses everything from a GCS not in control, downloads and telemetry requests too."""

    READS = ("MISSION_REQUEST_LIST", "MISSION_REQUEST", "MISSION_REQUEST_INT")

    def screen(self, frame: Frame) -> Refusal | None:
        msg, src = frame.msg, frame.source
        if self.may_command(src[0]) or not cm.addressed_to(msg, self.system, self.component):
            return None
        if msg._type in ("COMMAND_LONG", "COMMAND_INT") and msg.command in FREE_COMMANDS:
            ack = cm.command_ack(msg.command, _d.MAV_RESULT_NOT_IN_CONTROL, src)
            return Refusal(f"{msg._type} {msg.command}: not in control", (Send(ack, src),))
        if msg._type in self.READS:
            ack = cm.mission_ack(_d.MAV_MISSION_DENIED, msg.mission_type, src)
            return Refusal(f"{msg._type}: not in control", (Send(ack, src),))
        return super().screen(frame)


# --- HO.CTL.13: owner loss -------------------------------------------------------------------------

class _AnyHeartbeatKeepsOwner(ControlManager):
    """Keeps the owner alive on any GCS's HEARTBEAT, not only its own."""

    def handle(self, frame: Frame, now: float) -> list:
        if frame.msg._type == "HEARTBEAT" and self.owner and frame.msg.type == _d.MAV_TYPE_GCS:
            self._heard(now)
        return super().handle(frame, now)


mutant("control-status-slow", "streams CONTROL_STATUS every 3 s, not at about 1 Hz",
       {"HO.CTL.01"}, control_mutant(status_period=3.0))
mutant("refuses-control-when-free", "refuses a request for control with MAV_RESULT_FAILED "
       "while no GCS is in control", {"HO.CTL.02"}, control_mutant(_RefusesWhileUncontrolled))
mutant("ignores-control-release", "acknowledges the owner's release and keeps it in control",
       {"HO.CTL.03"}, control_mutant(_IgnoresRelease))
mutant("control-status-stale-stream", "its 1 Hz CONTROL_STATUS always says nobody is in control; only "
       "the one sent on a change is current", {"HO.CTL.04"}, control_mutant(_StaleStream))
mutant("control-status-not-on-change", "announces a change of control only with the stream's next "
       "CONTROL_STATUS", {"HO.CTL.05"}, control_mutant(_SilentOnChange))
mutant("busy-control-request-denied", "refuses a request that needs the owner's permission with "
       "MAV_RESULT_DENIED, not FAILED", {"HO.CTL.06"}, control_mutant(_RefusesBusyWithDenied))
mutant("request-not-forwarded", "refuses a request that needs the owner's permission and never "
       "tells the owner", {"HO.CTL.07"}, control_mutant(_DoesNotForward))
mutant("never-grants-takeover", "shows the takeover flag the owner sets but refuses every request while "
       "controlled", {"HO.CTL.08"}, control_mutant(_NeverGrantsTakeover))
mutant("takeover-flag-sticks", "ignores the owner's re-request disallowing takeover once it was allowed",
       {"HO.CTL.09"}, control_mutant(_TakeoverFlagSticks))
mutant("denies-foreign-commands", "refuses commands from a GCS not in control with "
       "MAV_RESULT_DENIED, not NOT_IN_CONTROL", {"HO.CTL.10"}, control_mutant(_DeniesCommands))
mutant("screens-commands-only", "lets mission writes from a GCS not in control through",
       {"HO.CTL.11"}, control_mutant(_ScreensCommandsOnly))
mutant("locks-out-reads", "refuses downloads and telemetry requests from a GCS not in control",
       {"HO.CTL.12"}, control_mutant(_LocksOutReads))
mutant("any-heartbeat-keeps-owner", "keeps the owner in control on any GCS's HEARTBEAT",
       {"HO.CTL.13"}, control_mutant(_AnyHeartbeatKeepsOwner))
