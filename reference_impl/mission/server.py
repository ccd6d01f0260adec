"""The vehicle side of the Mission Protocol as a sans-IO state machine.

Two rules, after h11's `_state.py`:
- Everything that changes a transfer's state goes through `_move`, which consults the
  transition table in `transitions.py`; a move the table does not list is a bug here and
  raises at once.
- The server never does I/O and never reads a clock: frames and the time come in through
  `handle(frame, now)` / `poll(now)`, messages to send go out as `Send` actions.

Theory of operation. Each plan type (mission, fence, rally) has its own `_Transfer` slot
(seed 000: types "stored and handled separately/independently"), so a fence upload and a
mission download can run side by side. A slot is IDLE, RECEIVING (an upload: the vehicle
requests items and retries on its 250 ms item timeout) or SENDING (a download: the GCS
drives, the vehicle answers requests and drops the transfer after a long silence). A slot
belongs to one GCS (its partner) while busy; any other GCS touching it gets DENIED.
An upload collects items aside and commits them whole after the last one, so a failed or
cancelled upload leaves the stored plan exactly as it was.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from ..errors import LocalProtocolError
from ..wire.frame import Frame
from . import messages as m
from .actions import Peer, Send
from .behaviour import ServerBehaviour
from .constants import Cmd, CommandResult, MissionResult, Severity
from .items import PLAN_TYPE_BY_VALUE, PLAN_TYPES, MissionItem, MissionType
from .progress import MissionProgress
from .store import MissionStore
from .transitions import SERVER_TRANSITIONS, SlotEvent, SlotState
from .validation import first_defect


@dataclass
class _Transfer:
    mission_type: MissionType
    state: SlotState = SlotState.IDLE
    partner: Peer | None = None
    deadline: float | None = None
    # RECEIVING
    count: int = 0
    expected: int = 0
    received: list[MissionItem] = field(default_factory=list)
    retries: int = 0


@dataclass
class _LastAccepted:
    partner: Peer
    items: tuple[MissionItem, ...]
    opaque_id: int
    until: float


@dataclass
class ServerStats:
    retries: int = 0           # item re-requests sent because the item timeout expired
    max_consecutive_retries: int = 0  # the most timeout resends of any one request
    rerequests: int = 0        # re-requests sent because an item arrived out of sequence
    uploads_accepted: int = 0
    uploads_failed: int = 0
    downloads_served: int = 0  # downloads the GCS ended with a MISSION_ACK (any code)
    denied: int = 0
    stray: int = 0
    history: list[tuple[MissionType, SlotState, SlotEvent, SlotState]] = field(default_factory=list)


class MissionServer:
    """Vehicle-side mission engine: `handle` frames, `poll` timers, send what it returns."""

    def __init__(self, system: int, component: int, behaviour: ServerBehaviour | None = None,
                 store: MissionStore | None = None, *, record_history: bool = False) -> None:
        self.system = system
        self.component = component
        self.behaviour = behaviour or ServerBehaviour()
        self.store = store or MissionStore()
        self.progress = MissionProgress(self.store, self.behaviour.current_period)
        self.stats = ServerStats()
        self._record = record_history
        self._slots = {t: _Transfer(t) for t in PLAN_TYPES}
        self._slot_list = tuple(self._slots.values())
        self._last_accepted: dict[MissionType, _LastAccepted] = {}
        self._handlers = {
            "MISSION_COUNT": self._on_count,
            "MISSION_ITEM_INT": self._on_item,
            "MISSION_ITEM": self._on_item,
            "MISSION_REQUEST_LIST": self._on_request_list,
            "MISSION_REQUEST_INT": self._on_request,
            "MISSION_REQUEST": self._on_request,
            "MISSION_ACK": self._on_ack,
            "MISSION_CLEAR_ALL": self._on_clear_all,
            "MISSION_SET_CURRENT": self._on_set_current,
        }

    # --- public surface -------------------------------------------------------------------
    def state(self, mission_type: MissionType) -> SlotState:
        return self._slots[mission_type].state

    def partner(self, mission_type: MissionType) -> Peer | None:
        return self._slots[mission_type].partner

    def is_idle(self) -> bool:
        return all(s.state is SlotState.IDLE for s in self._slots.values())

    def handles(self, name: str) -> bool:
        return name in self._handlers

    def handle(self, frame: Frame, now: float) -> list[Send]:
        """React to one decoded frame addressed to us (others are ignored)."""
        msg = frame.msg
        handler = self._handlers.get(msg._type)
        if handler is None or not self._addressed_to_us(msg):
            return []
        return handler(msg, (frame.src_system, frame.src_component), now)

    def poll(self, now: float) -> list[Send]:
        out: list[Send] = []
        for slot in self._slots.values():
            if slot.deadline is not None and now >= slot.deadline:
                out += self._on_timeout(slot, now)
        out += self.progress.poll(now)
        return out

    def next_deadline(self) -> float | None:
        best = self.progress.next_deadline()
        for slot in self._slot_list:
            d = slot.deadline
            if d is not None and (best is None or d < best):
                best = d
        return best

    def cancel(self, mission_type: MissionType, now: float) -> list[Send]:
        """Vehicle-initiated cancel: tell the partner OPERATION_CANCELLED, go idle."""
        slot = self._slots[mission_type]
        if slot.state is SlotState.IDLE:
            return []
        partner = slot.partner
        self._abort(slot, SlotEvent.CANCEL)
        return [Send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, partner), partner)]

    def command_set_current(self, seq_param: float, source: Peer, now: float) -> list[Send]:
        """MAV_CMD_DO_SET_MISSION_CURRENT: COMMAND_ACK, then MISSION_CURRENT or STATUSTEXT."""
        seq = self.progress.seq if seq_param == -1 else seq_param
        count = self.store.count(MissionType.MISSION)
        if not math.isfinite(seq) or seq != int(seq) or not 0 <= seq < count:
            return [Send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, CommandResult.FAILED, source), source),
                    *self._set_current_failed(seq_param, count)]
        return [Send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, CommandResult.ACCEPTED, source), source),
                *self.progress.set_current(int(seq), now)]

    # --- message handlers -----------------------------------------------------------------
    def _on_count(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is not SlotState.IDLE:
            self._leave(slot)  # the partner moved on: its old transfer is void
        # A new upload begins: late copies of the previous one's items no longer prove
        # anything about what is stored, so they must not draw a repeated ACCEPTED.
        self._last_accepted.pop(t, None)
        count = msg.count
        if count > self.behaviour.capacity.get(t, 0):
            self._move(slot, SlotEvent.COUNT_REJECTED)
            return [Send(m.ack_message(MissionResult.NO_SPACE, t, src), src)]
        if count == 0:
            # Seed 000: an empty upload "has the same effect as clearing the mission".
            self._move(slot, SlotEvent.COUNT_ZERO)
            return self._commit(t, [], src, now)
        slot.partner, slot.count, slot.expected, slot.received, slot.retries = src, count, 0, [], 0
        self._move(slot, SlotEvent.COUNT)
        return self._request(slot, now)

    def _on_item(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is SlotState.IDLE:
            return self._stray_item(msg, t, src, now)
        if slot.state is not SlotState.RECEIVING:
            return []  # an item from our own download partner means nothing; ignore it
        if msg.seq != slot.expected:
            return self._out_of_sequence(slot, msg.seq, now)
        item = m.item_from_message(msg)
        if item is None:
            code = (MissionResult.INVALID_PARAM5_X if m.float_xy_defect(msg) == 5
                    else MissionResult.INVALID_PARAM6_Y)
            return self._reject(slot, code, src)
        defect = first_defect(item, self.behaviour.item_rules)
        if defect is not None:
            return self._reject(slot, defect.code, src)
        slot.received.append(item)
        if len(slot.received) < slot.count:
            slot.expected += 1
            self._move(slot, SlotEvent.ITEM_NEXT)
            return self._request(slot, now)
        items = slot.received
        self._move(slot, SlotEvent.ITEM_LAST)
        self._leave(slot)
        return self._commit(t, items, src, now)

    def _on_request_list(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is not SlotState.IDLE:
            self._leave(slot)
        count = self.store.count(t)
        reply = Send(m.count_message(count, t, src, self.store.opaque_id(t)), src)
        if count == 0:
            self._move(slot, SlotEvent.REQUEST_LIST_EMPTY)
            return [reply]
        slot.partner = src
        slot.deadline = now + self.behaviour.download_idle_timeout
        self._move(slot, SlotEvent.REQUEST_LIST)
        return [reply]

    def _on_request(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is SlotState.IDLE:
            return self._stray(t, src)
        if slot.state is not SlotState.SENDING:
            return []  # our own upload partner asking for items: meaningless, ignore
        items = self.store.items(t)
        if msg.seq >= len(items):
            self._move(slot, SlotEvent.REQUEST_INVALID)
            self._leave(slot)
            return [Send(m.ack_message(MissionResult.INVALID_SEQUENCE, t, src), src)]
        slot.deadline = now + self.behaviour.download_idle_timeout
        self._move(slot, SlotEvent.REQUEST_VALID)
        as_int = msg.get_type() == m.REQUEST_INT
        return [Send(m.item_message(items[msg.seq], src, as_int=as_int), src)]

    def _on_ack(self, msg: Any, src: Peer, now: float) -> list[Send]:
        t = self._plan_type(msg.mission_type)
        if t is None:
            return []
        slot = self._slots[t]
        if slot.state is SlotState.IDLE or slot.partner != src:
            return []  # an ACK is never answered: no ACK storms
        if slot.state is SlotState.SENDING:
            self._move(slot, SlotEvent.ACK)  # the GCS ends its download, whatever the code
            self.stats.downloads_served += 1
            self._leave(slot)
        elif msg.type != MissionResult.ACCEPTED:
            # Seed 000: an error ACK "must cancel the operation and restore the mission".
            self._move(slot, SlotEvent.ACK)
            self.stats.uploads_failed += 1
            self._leave(slot)
        return []

    def _on_clear_all(self, msg: Any, src: Peer, now: float) -> list[Send]:
        raw = msg.mission_type
        if raw == MissionType.ALL:
            types: tuple[MissionType, ...] = PLAN_TYPES
        else:
            t = self._plan_type(raw)
            if t is None:
                return self._unsupported(raw, src)
            types = (t,)
        reply_type = MissionType.ALL if raw == MissionType.ALL else types[0]
        if any(self._busy_with_other(self._slots[t], src) for t in types):
            self.stats.denied += 1
            return [Send(m.ack_message(MissionResult.DENIED, reply_type, src), src)]
        out: list[Send] = []
        for t in types:
            slot = self._slots[t]
            if slot.state is not SlotState.IDLE:
                self._leave(slot)
            self._move(slot, SlotEvent.CLEAR)
            self.store.clear(t)
            self._last_accepted.pop(t, None)
        if MissionType.MISSION in types:
            out += self.progress.plan_replaced(now)
        return [Send(m.ack_message(MissionResult.ACCEPTED, reply_type, src), src)] + out

    def _on_set_current(self, msg: Any, src: Peer, now: float) -> list[Send]:
        count = self.store.count(MissionType.MISSION)
        if not 0 <= msg.seq < count:
            return self._set_current_failed(msg.seq, count)
        return self.progress.set_current(msg.seq, now)

    # --- timers ---------------------------------------------------------------------------
    def _on_timeout(self, slot: _Transfer, now: float) -> list[Send]:
        if slot.state is SlotState.SENDING:
            self._move(slot, SlotEvent.TIMEOUT_GIVE_UP)  # the GCS went quiet; it drives retries
            self._leave(slot)
            return []
        if slot.retries < self.behaviour.timings.max_retries:
            slot.retries += 1
            self.stats.retries += 1
            self.stats.max_consecutive_retries = max(self.stats.max_consecutive_retries, slot.retries)
            self._move(slot, SlotEvent.TIMEOUT_RETRY)
            return self._request(slot, now, reset_retries=False)
        partner, t = slot.partner, slot.mission_type
        self._move(slot, SlotEvent.TIMEOUT_GIVE_UP)
        self.stats.uploads_failed += 1
        self._leave(slot)
        if not self.behaviour.notify_upload_give_up:
            return []
        return [Send(m.ack_message(MissionResult.OPERATION_CANCELLED, t, partner), partner)]

    def _out_of_sequence(self, slot: _Transfer, seq: int, now: float) -> list[Send]:
        """Seed 000: an out-of-sequence item is dropped and the expected one re-requested.

        A copy of an item already received (seq < expected) is dropped without a new
        request: our request for the expected item is already out and its timer covers a
        loss, while answering every stale duplicate would start a second request/item
        stream for the rest of the transfer, then a third, and so on. An item beyond the
        expected one (a gap) is re-requested at once. Neither moves the deadline or resets
        the retry count: only progress does, so a peer that keeps sending the wrong item
        cannot hold the transfer open."""
        self._move(slot, SlotEvent.ITEM_OUT_OF_SEQUENCE)
        if seq < slot.expected:
            return []
        self.stats.rerequests += 1
        return [Send(self._request_msg(slot), slot.partner)]

    # --- helpers --------------------------------------------------------------------------
    def _request_msg(self, slot: _Transfer) -> Any:
        return m.request_message(slot.expected, slot.mission_type, slot.partner,
                                 as_int=self.behaviour.request_int)

    def _request(self, slot: _Transfer, now: float, *, reset_retries: bool = True) -> list[Send]:
        if reset_retries:
            slot.retries = 0
        slot.deadline = now + self.behaviour.timings.item_timeout
        return [Send(self._request_msg(slot), slot.partner)]

    def _commit(self, t: MissionType, items: list[MissionItem], src: Peer, now: float) -> list[Send]:
        opaque_id = self.store.commit(t, items)
        self.stats.uploads_accepted += 1
        if items and self.behaviour.reack_last_item:
            until = now + self.behaviour.download_idle_timeout
            self._last_accepted[t] = _LastAccepted(src, tuple(items), opaque_id, until)
        else:
            self._last_accepted.pop(t, None)
        out = [Send(m.ack_message(MissionResult.ACCEPTED, t, src, opaque_id), src)]
        if t is MissionType.MISSION:
            out += self.progress.plan_replaced(now)
        return out

    def _reject(self, slot: _Transfer, code: MissionResult, src: Peer) -> list[Send]:
        self._move(slot, SlotEvent.ITEM_REJECTED)
        self.stats.uploads_failed += 1
        self._leave(slot)
        return [Send(m.ack_message(code, slot.mission_type, src), src)]

    def _stray_item(self, msg: Any, t: MissionType, src: Peer, now: float) -> list[Send]:
        last = self._last_accepted.get(t)
        if last is not None and last.partner == src and now <= last.until:
            # A late copy of an item of the upload we just accepted: that GCS has not seen
            # our final ACK yet (it was lost, or a delayed duplicate request drew this item).
            item = m.item_from_message(msg)
            if item is not None and item.seq < len(last.items) and item == last.items[item.seq]:
                return [Send(m.ack_message(MissionResult.ACCEPTED, t, src, last.opaque_id), src)]
        return self._stray(t, src)

    def _stray(self, t: MissionType, src: Peer) -> list[Send]:
        self.stats.stray += 1
        self._move(self._slots[t], SlotEvent.STRAY)
        code = self.behaviour.idle_reply
        return [] if code is None else [Send(m.ack_message(code, t, src), src)]

    def _slot_for(self, msg: Any, src: Peer) -> tuple[_Transfer, list[Send] | None]:
        """The transfer slot a message is about, or the refusal to send instead: UNSUPPORTED
        for a plan type we do not store, DENIED while another GCS's transfer holds it."""
        t = self._plan_type(msg.mission_type)
        if t is None:
            return None, self._unsupported(msg.mission_type, src)  # type: ignore[return-value]
        slot = self._slots[t]
        if self._busy_with_other(slot, src):
            return slot, self._deny(t, src)
        return slot, None

    def _deny(self, t: MissionType, src: Peer) -> list[Send]:
        self.stats.denied += 1
        return [Send(m.ack_message(MissionResult.DENIED, t, src), src)]

    def _unsupported(self, raw_type: int, src: Peer) -> list[Send]:
        return [Send(m.ack_message(MissionResult.UNSUPPORTED, raw_type, src), src)]

    def _set_current_failed(self, seq: float, count: int) -> list[Send]:
        text = f"Set current failed: seq {seq:g} not in mission of {count}"
        return [Send(m.statustext_message(Severity.WARNING, text))]

    def _plan_type(self, raw: int) -> MissionType | None:
        t = PLAN_TYPE_BY_VALUE.get(raw)
        if t is None or t not in self.behaviour.supported_types:
            return None
        return t

    def _busy_with_other(self, slot: _Transfer, src: Peer) -> bool:
        return slot.state is not SlotState.IDLE and slot.partner != src

    def _addressed_to_us(self, msg: Any) -> bool:
        ts = getattr(msg, "target_system", 0)
        tc = getattr(msg, "target_component", 0)
        return ts in (0, self.system) and tc in (0, self.component)

    def _abort(self, slot: _Transfer, event: SlotEvent) -> None:
        if slot.state is SlotState.RECEIVING:
            self.stats.uploads_failed += 1
        self._move(slot, event)
        self._leave(slot)

    def _leave(self, slot: _Transfer) -> None:
        """Forget the transfer's bookkeeping (the stored plan is untouched)."""
        if slot.state is not SlotState.IDLE:
            self._move(slot, SlotEvent.SUPERSEDED)
        slot.partner, slot.deadline, slot.received, slot.count, slot.expected = None, None, [], 0, 0

    def _move(self, slot: _Transfer, event: SlotEvent) -> None:
        key = (slot.state, event)
        try:
            new_state = SERVER_TRANSITIONS[key]
        except KeyError:
            raise LocalProtocolError(
                f"server {slot.mission_type.label}: no transition for {event.name} in {slot.state.name}"
            ) from None
        if self._record:
            self.stats.history.append((slot.mission_type, slot.state, event, new_state))
        slot.state = new_state
