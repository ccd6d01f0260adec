"""The bridge's MAVLink mission engine: the reference MissionServer, whose stored mission is
an MSP flight controller's waypoint list.

Everything the Mission Protocol does between GCS and vehicle (counts, requests, retries,
timeouts, cancels, the INT and float forms) is the reference server's, unchanged. What
differs is where a plan lives:
- each item is checked against what MSP can hold as it arrives (`mapping.to_waypoint`): one
  that does not fit ends the upload with the MISSION_ACK error the mapping table gives, and a
  STATUSTEXT saying why, before anything is written to the flight controller;
- an upload that got every item, a clear, and an empty upload do not commit at once: they
  become `pending`, the bridge writes the waypoints over MSP and reads each one back, and only
  then `finish` sends MISSION_ACK ACCEPTED (storing what the flight controller holds) or an
  error naming the waypoint and field that did not store;
- fence and rally plans are not supported (MSP holds missions only); MISSION_TYPE_ALL clears
  the mission.
Set-current and the download's refresh are the bridge's (bridge.py): they ask the flight
controller too.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ..mission import messages as m
from ..mission.actions import Peer, Send
from ..mission.behaviour import ServerBehaviour
from ..mission.constants import MissionResult, Severity
from ..mission.items import MissionItem, MissionType
from ..mission.server import MissionServer
from ..mission.transitions import SlotState
from .commands import Waypoint
from .jobs import EMPTY, Done, Failed, Result
from .mapping import MAX_WAYPOINTS, Refusal, to_item, to_waypoint

MISSION = MissionType.MISSION
BEHAVIOUR = ServerBehaviour(capacity={MISSION: MAX_WAYPOINTS, MissionType.FENCE: 0, MissionType.RALLY: 0},
                            supported_types=frozenset({MISSION}))


@dataclass(frozen=True)
class Pending:
    """A change waiting for the flight controller: the waypoints to write and who to answer."""

    kind: str                         # "upload" or "clear"
    items: tuple[MissionItem, ...]
    waypoints: tuple[Waypoint, ...]
    partner: Peer
    reply_type: int                   # the MISSION_ACK's mission_type (ALL for a clear of all)


def waypoints_for(items: list[MissionItem]) -> tuple[Waypoint, ...] | Refusal:
    """What MSP stores for a whole mission (an empty one: the MultiWii "no mission" record)."""
    if not items:
        return (EMPTY,)
    out = []
    for item in items:
        wp = to_waypoint(item, len(items))
        if isinstance(wp, Refusal):
            return wp
        out.append(wp)
    return tuple(out)


def items_for(waypoints: tuple[Waypoint, ...]) -> list[MissionItem] | Refusal:
    """The mission a flight controller's list is (the "no mission" record: none)."""
    if waypoints == (EMPTY,) or not waypoints:
        return []
    out = []
    for wp in waypoints:
        item = to_item(wp)
        if isinstance(item, Refusal):
            return item
        out.append(item)
    return out


class BridgeServer(MissionServer):
    def __init__(self, system: int, component: int, behaviour: ServerBehaviour = BEHAVIOUR) -> None:
        super().__init__(system, component, behaviour)
        self.pending: Pending | None = None

    # --- what MSP can hold, checked as each item arrives -------------------------------------
    def _on_item(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot = self._slots.get(self._plan_type(msg.mission_type) or MISSION)
        if (slot is not None and slot.state is SlotState.RECEIVING and slot.partner == src
                and msg.seq == slot.expected and slot.mission_type is MISSION):
            item = m.item_from_message(msg)
            if item is not None:
                wp = to_waypoint(replace(item, mission_type=MISSION), slot.count)
                if isinstance(wp, Refusal):
                    return self._refuse(slot, wp.code, src, wp.why)
                if slot.count == 1 and wp == EMPTY:
                    return self._refuse(slot, MissionResult.UNSUPPORTED, src,
                                        "one plain RTH is MSP's 'no mission' record")
        return super()._on_item(msg, src, now)

    def _refuse(self, slot: Any, code: MissionResult, src: Peer, why: str) -> list[Send]:
        return [Send(m.statustext_message(Severity.WARNING, f"MSP: {why}"[:50]))] + \
            self._reject(slot, code, src)

    # --- changes wait for the flight controller ----------------------------------------------
    def _commit(self, t: MissionType, items: list[MissionItem], src: Peer, now: float) -> list[Send]:
        waypoints = waypoints_for(items)
        assert not isinstance(waypoints, Refusal), waypoints   # every item was checked on arrival
        self.pending = Pending("upload", tuple(items), waypoints, src, int(t))
        return []

    def _on_clear_all(self, msg: Any, src: Peer, now: float) -> list[Send]:
        if msg.mission_type not in (int(MISSION), int(MissionType.ALL)):
            return super()._on_clear_all(msg, src, now)
        slot = self._slots[MISSION]
        if self._busy_with_other(slot, src):
            return [Send(m.ack_message(MissionResult.DENIED, msg.mission_type, src), src)]
        if slot.state is not SlotState.IDLE:
            self._leave(slot)
        self._last_accepted.pop(MISSION, None)
        self.pending = Pending("clear", (), (EMPTY,), src, msg.mission_type)
        return []

    def finish(self, result: Result, now: float) -> list[Send]:
        """The flight controller's answer to the pending change: the MISSION_ACK it earns."""
        pending, self.pending = self.pending, None
        assert pending is not None
        if isinstance(result, Failed):
            self.stats.uploads_failed += 1
            return [Send(m.statustext_message(Severity.ERROR, result.why[:50])),
                    Send(m.ack_message(MissionResult.ERROR, pending.reply_type, pending.partner), pending.partner)]
        held = items_for(result.waypoints)
        assert not isinstance(held, Refusal), held    # it read back what was written
        if pending.kind == "clear":
            self.store.clear(MISSION)
            return [Send(m.ack_message(MissionResult.ACCEPTED, pending.reply_type, pending.partner),
                         pending.partner)] + self.progress.plan_replaced(now)
        return super()._commit(MISSION, held, pending.partner, now)

    def refresh(self, result: Done) -> str | None:
        """Take the flight controller's list as the stored mission (before a download);
        why not, if it cannot be a MAVLink mission (None: taken)."""
        if result.info is not None and not result.info.valid and result.waypoints:
            held: list[MissionItem] | Refusal = []
            why = f"the flight controller's {len(result.waypoints)} waypoints are unfinished (no 0xA5)"
        else:
            held, why = items_for(result.waypoints), None
        if isinstance(held, Refusal):
            return f"waypoint action on the flight controller has no MAVLink command: {held.why}"
        if list(self.store.items(MISSION)) != held:   # unchanged: the same opaque_id
            if held:
                self.store.commit(MISSION, held)
            else:
                self.store.clear(MISSION)
        return why

