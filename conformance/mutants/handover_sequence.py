"""Mutants that break the handover-sequence clauses (HO.SEQ.*): one handover bug each.

Each is the suite's `builtin:spec` vehicle (the reference system manager, `SUITE_CONTROL`,
and the thesis's mission computer loaded from the conformance scenario, `suite_handover()`)
with one behaviour changed: a `MissionComputer` subclass plugged in through
`VehicleNode(mission_computer_class=...)`, a `ControlManager` subclass through
`manager_class`, or a `VehicleNode` subclass where the bug is in how the vehicle wires the two
together. The bugs are ones a handover implementation plausibly has (the wrong GCS named in a
field, a relay dropped while busy, a commander's silence taken for consent, a region that
re-arms itself), and none moves an engine outside its transition tables, so a mutant fails
clauses, never crashes. Outside a handover each behaves as the spec vehicle does, so the
HO.CTL and mission clauses pass on them.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_manager import ControlManager
from mavconform.reference_impl.handover.control_results import Refusal
from mavconform.reference_impl.handover.mission_computer import (HandoverStarted, MissionComputer,
                                                                 WithdrawTakeover)
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.frame import Frame

from ..target_uri import SUITE_CONTROL, suite_handover
from . import mutant


def handover_mutant(*, vehicle_cls: type[VehicleNode] = VehicleNode,
                    computer_cls: type[MissionComputer] = MissionComputer,
                    manager_cls: type[ControlManager] = ControlManager) -> Callable[[VehicleConfig], VehicleNode]:
    """A builder for the suite's handover vehicle with one part swapped for a broken one."""
    def build(config: VehicleConfig) -> VehicleNode:
        config = dataclasses.replace(config, control=SUITE_CONTROL, handover=suite_handover())
        return vehicle_cls(config, manager_class=manager_cls, mission_computer_class=computer_cls)
    return build


def _is_ack(action: Any) -> bool:
    return isinstance(action, Send) and action.msg._type == "COMMAND_ACK"


def _allow_for_commander(vehicle: VehicleNode, now: float) -> None:
    """The vehicle re-requests control with takeover allowed in the commander's name, as if
    the commander had (its ACK, which nobody asked for, is not sent)."""
    control = vehicle.control
    if control.owner_peer is not None:
        actions = control._on_owner_request(control.owner_peer, True, now)
        vehicle._on_control([a for a in actions if not _is_ack(a)], now)


# --- HO.SEQ.01: the invitation ----------------------------------------------------------------------

class _InvitesForTheCommander(MissionComputer):
    """Invites the partner with param4 naming the commander (the GCS in control) instead of the
    partner, the GCS the request is for."""

    def _notice(self, a: Any, now: float) -> Send:
        send = super()._notice(a, now)
        if not a.committed:
            send.msg.param4 = float(a.commander)
        return send


# --- HO.SEQ.02: the relay to the commander ------------------------------------------------------------

class _DropsRelayWhileHandingOver(VehicleNode):
    """While a handover waits for its grant, drops the system manager's relay of the partner's
    request to the commander (and its resends): the commander never hears of it."""

    def _on_control(self, actions: list[Any], now: float) -> None:
        attempt = self.mission_computer.attempt if self.mission_computer is not None else None
        if attempt is not None and not attempt.committed:
            owner = self.control.owner_peer
            actions = [x for x in actions if not (isinstance(x, Send) and x.to == owner
                                                   and cm.is_request_control(x.msg))]
        super()._on_control(actions, now)


# --- HO.SEQ.03: no switch before the commander's word -------------------------------------------------

class _AllowsOnInvitation(VehicleNode):
    """Allows takeover in the commander's name as soon as it invites the partner: the partner's
    first request is granted without the commander's authorisation."""

    def _on_handover(self, actions: list[Any], now: float) -> None:
        super()._on_handover(actions, now)
        if any(isinstance(x, HandoverStarted) for x in actions):
            _allow_for_commander(self, now)


# --- HO.SEQ.04: the grant after the commander's word --------------------------------------------------

class _WithdrawsOnAuthorisation(MissionComputer):
    """Takes the commander's allow-takeover for the end of the handover and withdraws the
    partner's takeover window at once: the partner's request is refused again."""

    def control_changed(self, change: Any, now: float) -> list[Any]:
        a = self.attempt
        out = super().control_changed(change, now)
        if (a is not None and self.attempt is a and not a.committed and change.owner == a.commander
                and change.takeover_allowed):
            out.append(WithdrawTakeover(a.partner, "the commander authorised: handover done"))
        return out


# --- HO.SEQ.05: the connect notice -------------------------------------------------------------------

class _NoConnectNotice(MissionComputer):
    """Commits the handover on the grant but never sends the partner the connect notice."""

    def _commit(self, now: float) -> list[Any]:
        super()._commit(now)
        self.attempt.resend_at = None
        return []


# --- HO.SEQ.06: only the new commander ---------------------------------------------------------------

class _ParentAlwaysCommands(ControlManager):
    """Lets the parent GCS's commands through whoever is in control: the GCS the mission was
    loaded from keeps command rights after it handed the vehicle over."""

    PARENT = 0

    def screen(self, frame: Frame) -> Refusal | None:
        if frame.source[0] == self.PARENT and frame.msg._type in ("COMMAND_LONG", "COMMAND_INT"):
            return None
        return super().screen(frame)


def _parent_commands() -> type[ControlManager]:
    return type("_ParentAlwaysCommands", (_ParentAlwaysCommands,), {"PARENT": suite_handover().parent})


# --- HO.SEQ.07: a commander that never answers ---------------------------------------------------------

class _SilenceIsConsent(VehicleNode):
    """Ends a handover the commander did not authorise in time by handing control to the
    partner anyway, instead of withdrawing its request: silence taken for consent."""

    def _on_handover(self, actions: list[Any], now: float) -> None:
        rest = []
        for x in actions:
            if isinstance(x, WithdrawTakeover):
                self._hand_over(x.requester, now)
            else:
                rest.append(x)
        super()._on_handover(rest, now)

    def _hand_over(self, partner: int, now: float) -> None:
        peer = next((p for p in self.endpoint.peers if p[0] == partner), None)
        if peer is None:
            return
        _allow_for_commander(self, now)
        self._on_control([a for a in self.control._grant(peer, False, now) if not _is_ack(a)], now)


# --- HO.SEQ.08: one handover per entry ----------------------------------------------------------------

class _RearmsRegion(MissionComputer):
    """Re-arms the region when a handover ends, so a vehicle that stays inside is handed
    straight back (and forth)."""

    def _finish(self, *args: Any, **kwargs: Any) -> list[Any]:
        if self.attempt is not None:
            self.attempt.watch.used = False
        return super()._finish(*args, **kwargs)


mutant("invitation-names-commander", "invites the partner with param4 naming the commander, not the partner",
       {"HO.SEQ.01"}, handover_mutant(computer_cls=_InvitesForTheCommander))
mutant("handover-request-not-relayed", "during a handover, drops the relay of the partner's request to the "
       "commander", {"HO.SEQ.02"}, handover_mutant(vehicle_cls=_DropsRelayWhileHandingOver))
mutant("handover-without-authorisation", "allows takeover in the commander's name when it invites the partner",
       {"HO.SEQ.03"}, handover_mutant(vehicle_cls=_AllowsOnInvitation))
mutant("handover-window-withdrawn", "withdraws the partner's takeover window as soon as the commander "
       "authorises", {"HO.SEQ.04"}, handover_mutant(computer_cls=_WithdrawsOnAuthorisation))
mutant("no-connect-notice", "grants the partner control but never sends it the connect notice",
       {"HO.SEQ.05"}, handover_mutant(computer_cls=_NoConnectNotice))


def _build_parent_commands(config: VehicleConfig) -> VehicleNode:
    return handover_mutant(manager_cls=_parent_commands())(config)


mutant("parent-keeps-command", "lets the parent GCS command after it handed the vehicle over",
       {"HO.SEQ.06"}, _build_parent_commands)
mutant("silent-commander-consents", "hands control to the partner anyway when the commander does not "
       "answer a handover in time", {"HO.SEQ.07"}, handover_mutant(vehicle_cls=_SilenceIsConsent))
mutant("handover-region-rearmed", "re-arms the handover region when a handover ends, handing the vehicle "
       "straight back while it stays inside", {"HO.SEQ.08"}, handover_mutant(computer_cls=_RearmsRegion))
