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

Every departure from that (PX4-like and ArduPilot-like profiles) is a `ServerBehaviour`
knob read here; moves only a knob makes are in `PROFILE_TRANSITIONS`. How a slot receives
an upload is in server_uploads.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from ..state_table import next_state
from ..wire.frame import Frame
from . import messages as m
from .actions import Peer, Send
from .behaviour import ServerBehaviour
from .constants import Cmd, CommandResult, MissionResult, Severity
from .items import MISSION_PLAN, PLAN_TYPE_BY_VALUE, PLAN_TYPES, MissionItem, MissionType
from .progress import MissionProgress
from .store import STORAGE_FORMS, MissionStore
from .transitions import ALL_SERVER_TRANSITIONS, SlotEvent, SlotState
from .server_uploads import _IDLE, _RECEIVING, _REQUEST_VALID, _SENDING, ServerUploads, _LastAccepted
from .upload_counters import UploadCounters


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
    start: int = 0                 # first seq written (MISSION_WRITE_PARTIAL_LIST), else 0
    partial: bool = False
    last_heard: float = 0.0        # last message from the partner (protocol timeout)
    as_int: bool = True            # form of the vehicle's requests
    warned: frozenset[str] = frozenset()   # legacy-message warnings sent in this transfer
    # SENDING
    next_seq: int = 0              # sequential downloads: the seq the GCS should ask for next


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
    stray_items_stored: int = 0   # upload_counters_persist: stray items the plan took
    history: list[tuple[MissionType, SlotState, SlotEvent, SlotState]] = field(default_factory=list)


# The engine each slot's moves are said to be made by (made once: `_move` runs every frame).
_ENGINE_NAMES = {t: f"server {t.label}" for t in PLAN_TYPES}

# Where the vehicle is when no one has said otherwise (home_at_seq0 serves it as item 0).
DEFAULT_HOME = MissionItem(0, 0, Cmd.NAV_WAYPOINT, x=473977420, y=85455940, z=0.0)


class MissionServer(ServerUploads):
    """Vehicle-side mission engine: `handle` frames, `poll` timers, send what it returns."""

    def __init__(self, system: int, component: int, behaviour: ServerBehaviour | None = None,
                 store: MissionStore | None = None, *, record_history: bool = False) -> None:
        self.system = system
        self.component = component
        self.behaviour = b = behaviour or ServerBehaviour()
        self.store = store or MissionStore()
        self.progress = MissionProgress(self.store, b.current_period, home_at_seq0=b.home_at_seq0,
                                        report_ids=b.opaque_id_fields,
                                        reached_repeats=b.item_reached_repeats,
                                        reached_one_slot=b.item_reached_one_slot,
                                        unreported=b.item_reached_unreported)
        self.home = DEFAULT_HOME     # the vehicle sets its own (home_at_seq0 serves it)
        self._keep = STORAGE_FORMS[b.item_storage]
        self._frame_version = 2
        self.stats = ServerStats()
        self._record = record_history
        self._slots = {t: _Transfer(t) for t in PLAN_TYPES}
        self._slot_list = tuple(self._slots.values())
        self._last_accepted: dict[MissionType, _LastAccepted] = {}
        self._counters = UploadCounters() if b.upload_counters_persist else None
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
        if b.partial_write:
            self._handlers["MISSION_WRITE_PARTIAL_LIST"] = self._on_write_partial

    # --- public surface -------------------------------------------------------------------
    def state(self, mission_type: MissionType) -> SlotState:
        return self._slots[mission_type].state

    def partner(self, mission_type: MissionType) -> Peer | None:
        return self._slots[mission_type].partner

    def is_idle(self) -> bool:
        return all(s.state is _IDLE for s in self._slots.values())

    def handles(self, name: str) -> bool:
        return name in self._handlers

    def handle(self, frame: Frame, now: float) -> list[Send]:
        """React to one decoded frame addressed to us (others are ignored)."""
        msg = frame.msg
        handler = self._handlers.get(msg._type)
        if handler is None or not self._addressed_to_us(msg):
            return []
        self._frame_version = frame.version
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
        if slot.state is _IDLE:
            return []
        partner = slot.partner
        self._abort(slot, SlotEvent.CANCEL)
        return [Send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, partner), partner)]

    def command_set_current(self, seq_param: float, source: Peer, now: float) -> list[Send]:
        """MAV_CMD_DO_SET_MISSION_CURRENT: COMMAND_ACK, then MISSION_CURRENT or STATUSTEXT."""
        seq = self.progress.seq if seq_param == -1 else seq_param
        count = self.store.count(MISSION_PLAN)
        if not math.isfinite(seq) or seq != int(seq) or not 0 <= seq < count:
            return [Send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, CommandResult.FAILED, source), source),
                    *self._set_current_failed(seq_param, count)]
        return [Send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, CommandResult.ACCEPTED, source), source),
                *self.progress.set_current(int(seq), now)]

    # --- message handlers -----------------------------------------------------------------
    def _on_request_list(self, msg: Any, src: Peer, now: float) -> list[Send]:
        if self.behaviour.unknown_type_count0 and msg.mission_type not in PLAN_TYPE_BY_VALUE:
            return [Send(m.count_message(0, msg.mission_type, src), src)]
        slot, refusal = self._slot_for(msg, src, read=True)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is not _IDLE:
            self._leave(slot)
        count = self.store.count(t)
        reply = Send(m.count_message(count, t, src, self._opaque_id(t)), src)
        slot.warned = frozenset()
        if count == 0:
            self._move(slot, SlotEvent.REQUEST_LIST_EMPTY)
            return [reply]
        if not self.behaviour.stateful_download:
            self._move(slot, SlotEvent.REQUEST_LIST_UNTRACKED)
            return [reply]
        slot.partner, slot.next_seq = src, 0
        slot.deadline = now + self.behaviour.download_idle_timeout
        self._move(slot, SlotEvent.REQUEST_LIST)
        return [reply]

    def _on_request(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src, read=True)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        b = self.behaviour
        as_int = msg.get_type() == m.REQUEST_INT
        out = [] if as_int else self._warn_legacy(slot, "request", "got MISSION_REQUEST; use MISSION_REQUEST_INT!")
        if slot.state is _IDLE:
            if b.stateful_download:
                return self._stray(t, src)
            # no download state (A14): any request is answered from the stored plan
            self._move(slot, SlotEvent.REQUEST_UNTRACKED)
            if msg.seq >= self.store.count(t):
                return out + [Send(m.ack_message(MissionResult.INVALID_SEQUENCE, t, src), src)]
            return out + [Send(m.item_message(self._download_item(t, msg.seq), src, as_int=as_int), src)]
        if slot.state is not _SENDING:
            return []  # our own upload partner asking for items: meaningless, ignore
        seq = msg.seq
        if seq >= self.store.count(t) or (b.sequential_download and seq not in (slot.next_seq, slot.next_seq - 1)):
            code = MissionResult.ERROR if b.sequential_download else MissionResult.INVALID_SEQUENCE
            self._move(slot, SlotEvent.REQUEST_INVALID)
            self._leave(slot)
            return out + [Send(m.ack_message(code, t, src), src)]
        if seq == slot.next_seq:
            slot.next_seq += 1
        slot.deadline = now + b.download_idle_timeout
        self._move(slot, _REQUEST_VALID)
        return out + [Send(m.item_message(self._download_item(t, seq), src, as_int=as_int), src)]

    def _on_ack(self, msg: Any, src: Peer, now: float) -> list[Send]:
        t = self._plan_type(msg.mission_type)
        if t is None:
            return []
        slot = self._slots[t]
        if slot.state is _IDLE or slot.partner != src:
            return []  # an ACK is never answered: no ACK storms
        if slot.state is _SENDING:
            self._move(slot, SlotEvent.ACK)  # the GCS ends its download, whatever the code
            self.stats.downloads_served += 1
            self._leave(slot)
        elif self.behaviour.follow_gcs_int_mode and msg.type == MissionResult.UNSUPPORTED:
            # The GCS cannot take this request form: flip int/float and ask again (P8).
            slot.as_int = not slot.as_int
            self._move(slot, SlotEvent.FORM_FLIPPED)
            return [Send(self._request_msg(slot), slot.partner)]
        elif msg.type != MissionResult.ACCEPTED and self.behaviour.honour_cancel_upload and (
                msg.type == MissionResult.OPERATION_CANCELLED or self.behaviour.error_ack_ends_upload):
            # Seed 000: an error ACK "must cancel the operation and restore the mission".
            self._move(slot, SlotEvent.ACK)
            self.stats.uploads_failed += 1
            self._leave(slot)
        return []

    def _on_clear_all(self, msg: Any, src: Peer, now: float) -> list[Send]:
        raw = msg.mission_type
        b = self.behaviour
        everything = raw == MissionType.ALL and not b.mission_type_ignored
        if everything:
            if not b.clear_all_supported:
                return self._unsupported(raw, src)
            types: tuple[MissionType, ...] = tuple(t for t in PLAN_TYPES if t in b.supported_types)
        else:
            t = self._plan_type(raw)
            if t is None:
                return self._unsupported(raw, src)
            types = (t,)
        reply_type = MissionType.ALL if everything else types[0]
        if any(self._busy_with_other(self._slots[t], src) for t in types):
            self.stats.denied += 1
            return [Send(m.ack_message(MissionResult.DENIED, reply_type, src), src)]
        if MISSION_PLAN in types and self.progress.running and not b.clear_while_flying:
            return [Send(m.ack_message(MissionResult.ERROR, reply_type, src), src)]   # A12
        refused = self._v1_refusal(types[0] if len(types) == 1 else MISSION_PLAN, src)
        if refused is not None:
            return refused
        out: list[Send] = []
        for t in types:
            slot = self._slots[t]
            if slot.state is not _IDLE:
                self._leave(slot)
            self._move(slot, SlotEvent.CLEAR)
            self.store.clear(t)
            self._last_accepted.pop(t, None)
        if MISSION_PLAN in types:
            out += self.progress.plan_replaced(now)
        return [Send(m.ack_message(MissionResult.ACCEPTED, reply_type, src), src)] + out

    def _on_set_current(self, msg: Any, src: Peer, now: float) -> list[Send]:
        if self.behaviour.set_current_only_idle and not self.is_idle():
            return [Send(m.statustext_message(Severity.WARNING, "Set current refused: a transfer is in progress"))]
        count = self.store.count(MISSION_PLAN)
        if not 0 <= msg.seq < count:
            return self._set_current_failed(msg.seq, count) if self.behaviour.set_current_failure_text else []
        return self.progress.set_current(msg.seq, now)

    # --- helpers --------------------------------------------------------------------------
    def _download_item(self, t: MissionType, seq: int) -> MissionItem:
        """Stored item `seq` as a download serves it: item 0 of a mission is the vehicle's
        home when the plan holds it there (A1); `current` says whether it is the current
        mission item (seed 000 field table), whatever the uploading GCS put there."""
        if seq == 0 and t is MISSION_PLAN and self.behaviour.home_at_seq0:
            item = self._keep(self.home)
        else:
            item = self.store.items(t)[seq]
        current = int(t is MISSION_PLAN and seq == self.progress.seq
                      and self.behaviour.download_current_flag)
        return item if item.current == current else replace(item, current=current)

    def _opaque_id(self, t: MissionType) -> int:
        return self.store.opaque_id(t) if self.behaviour.opaque_id_fields else 0

    def _warn_legacy(self, slot: _Transfer, kind: str, text: str) -> list[Send]:
        """A7: one STATUSTEXT per transfer for a GCS that uses the float forms."""
        if not self.behaviour.legacy_warnings or kind in slot.warned:
            return []
        slot.warned = slot.warned | {kind}
        return [Send(m.statustext_message(Severity.WARNING, text))]


    def _slot_for(self, msg: Any, src: Peer, *, read: bool = False) -> tuple[_Transfer, list[Send] | None]:
        """The transfer slot a message is about, or the refusal to send instead: UNSUPPORTED
        for a plan type we do not store (or, for some, over MAVLink 1), DENIED while another
        GCS's transfer holds it (or, with `deny_reads_during_upload`, a read while it uploads)."""
        t = self._plan_type(msg.mission_type)
        if t is None:
            return None, self._unsupported(msg.mission_type, src)  # type: ignore[return-value]
        if self._frame_version == 1:   # only a MAVLink 1 frame can be refused for its version
            refused = self._v1_refusal(t, src)
            if refused is not None:
                return None, refused  # type: ignore[return-value]
        slot = self._slots[t]
        if not self.behaviour.transfer_owner and slot.state is not _IDLE:
            slot.partner = src   # no owner: the transfer answers whoever spoke last
        if self._busy_with_other(slot, src) or (
                read and slot.state is _RECEIVING and self.behaviour.deny_reads_during_upload):
            return slot, self._deny(t, src)
        return slot, None

    def _v1_refusal(self, t: MissionType, src: Peer) -> list[Send] | None:
        """A11: transfers of some plan types need MAVLink 2."""
        if self._frame_version != 1 or t not in self.behaviour.mavlink2_types:
            return None
        return [Send(m.statustext_message(Severity.WARNING, "Need mavlink2 for item transfer")),
                Send(m.ack_message(MissionResult.UNSUPPORTED, t, src), src)]

    def _deny(self, t: MissionType, src: Peer) -> list[Send]:
        self.stats.denied += 1
        return [Send(m.ack_message(self.behaviour.busy_reply, t, src), src)]

    def _unsupported(self, raw_type: int, src: Peer) -> list[Send]:
        return [Send(m.ack_message(MissionResult.UNSUPPORTED, raw_type, src), src)]

    def _set_current_failed(self, seq: float, count: int) -> list[Send]:
        text = f"Set current failed: seq {seq:g} not in mission of {count}"
        return [Send(m.statustext_message(Severity.WARNING, text))]

    def _plan_type(self, raw: int) -> MissionType | None:
        if self.behaviour.mission_type_ignored:
            return MISSION_PLAN
        t = PLAN_TYPE_BY_VALUE.get(raw)
        if t is None or t not in self.behaviour.supported_types:
            return None
        return t

    def _busy_with_other(self, slot: _Transfer, src: Peer) -> bool:
        return slot.state is not _IDLE and slot.partner != src

    def _addressed_to_us(self, msg: Any) -> bool:
        ts = getattr(msg, "target_system", 0)
        if self.behaviour.target_system_only:
            return ts == self.system
        tc = getattr(msg, "target_component", 0)
        return ts in (0, self.system) and tc in (0, self.component)

    def _abort(self, slot: _Transfer, event: SlotEvent) -> None:
        if slot.state is _RECEIVING:
            self.stats.uploads_failed += 1
        self._move(slot, event)
        self._leave(slot)

    def _leave(self, slot: _Transfer) -> None:
        """Forget the transfer's bookkeeping (the stored plan is untouched)."""
        if slot.state is not _IDLE:
            self._move(slot, SlotEvent.SUPERSEDED)
        slot.partner, slot.deadline, slot.received, slot.count, slot.expected = None, None, [], 0, 0

    def _move(self, slot: _Transfer, event: SlotEvent) -> None:
        new_state = next_state(ALL_SERVER_TRANSITIONS, slot.state, event, _ENGINE_NAMES[slot.mission_type])
        if self._record:
            self.stats.history.append((slot.mission_type, slot.state, event, new_state))
        slot.state = new_state
