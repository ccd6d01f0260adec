"""The upload side of the vehicle's mission engine, so server.py stays readable: how a slot
receives a plan (server.py gives the theory of operation). MISSION_COUNT and
MISSION_WRITE_PARTIAL_LIST open an upload, items arrive in sequence (or are dropped and
re-requested), the slot timer re-requests and gives up (and drops a download whose GCS went
quiet), the last item commits; an item with no upload running is a stray (or, on some
vehicles, a late copy or the continuation of an upload). A mixin of `server.MissionServer`;
server.py keeps the slots, downloads, clearing, set-current and the routing."""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable

from . import messages as m
from .actions import Peer, Send
from .behaviour import ServerBehaviour
from .constants import MissionResult, Severity
from .items import MISSION_PLAN, MissionItem, MissionType
from .progress import MissionProgress
from .store import MissionStore
from .transitions import SlotEvent, SlotState
from .upload_counters import UploadCounters
from .validation import first_defect

if TYPE_CHECKING:
    from .server import ServerStats, _Transfer

# Enum members read on every frame, bound once (server.py imports them too): on Python 3.11
# each read of a member off its class (`SlotState.IDLE`) goes through the enum metaclass's
# slow attribute hook.
_IDLE, _RECEIVING, _SENDING = SlotState.IDLE, SlotState.RECEIVING, SlotState.SENDING
_REQUEST_VALID, _ITEM_NEXT = SlotEvent.REQUEST_VALID, SlotEvent.ITEM_NEXT
_TIMEOUT_RETRY, _ITEM_OUT_OF_SEQUENCE = SlotEvent.TIMEOUT_RETRY, SlotEvent.ITEM_OUT_OF_SEQUENCE


@dataclass
class _LastAccepted:
    partner: Peer
    items: tuple[MissionItem, ...]
    opaque_id: int
    until: float


class ServerUploads:
    """The upload handlers and timers; `MissionServer` supplies the attributes below and
    `_slot_for`, `_leave`, `_move`, `_warn_legacy` and `_opaque_id`."""

    behaviour: ServerBehaviour
    store: MissionStore
    progress: MissionProgress
    stats: ServerStats
    _keep: Callable[[MissionItem], MissionItem]
    _counters: UploadCounters | None
    _slots: dict[MissionType, _Transfer]
    _slot_list: tuple[_Transfer, ...]
    _last_accepted: dict[MissionType, _LastAccepted]

    # --- message handlers -----------------------------------------------------------------
    def _on_count(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is not _IDLE:
            self._leave(slot)  # the partner moved on: its old transfer is void
        # A new upload begins: late copies of the previous one's items no longer prove
        # anything about what is stored, so they must not draw a repeated ACCEPTED.
        self._last_accepted.pop(t, None)
        count = msg.count
        if count > self.behaviour.capacity.get(t, 0):
            self._move(slot, SlotEvent.COUNT_REJECTED)
            return [Send(m.ack_message(MissionResult.NO_SPACE, t, src), src)]
        if self._counters is not None:
            self._counters.opened(count)
        if count == 0 and not self.behaviour.count0_opens_upload:
            # Seed 000: an empty upload "has the same effect as clearing the mission".
            self._move(slot, SlotEvent.COUNT_ZERO)
            return self._commit(t, [], src, now)
        if not self.behaviour.atomic_upload and not self.behaviour.item0_clears_plan:
            self._write(t, list(self.store.items(t)[:count]))   # truncated at once (A2)
        self._open_upload(slot, src, count, 0, now, partial=False)
        self._move(slot, SlotEvent.COUNT)
        return self._request(slot, now)

    def _on_write_partial(self, msg: Any, src: Peer, now: float) -> list[Send]:
        """MISSION_WRITE_PARTIAL_LIST: rewrite items start..end (inclusive) of the stored
        plan; end may be one past it (an append). Anything else: STATUSTEXT + ERROR."""
        slot, refusal = self._slot_for(msg, src, read=True)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is not _IDLE:
            self._leave(slot)
        stored = self.store.count(t)
        start, end = msg.start_index, msg.end_index
        if not 0 <= start <= end <= stored or end >= self.behaviour.capacity.get(t, 0):
            return [Send(m.statustext_message(Severity.WARNING, "Flight plan update rejected")),
                    Send(m.ack_message(MissionResult.ERROR, t, src), src)]
        self._last_accepted.pop(t, None)
        self._open_upload(slot, src, end - start + 1, start, now, partial=True)
        self._move(slot, SlotEvent.PARTIAL_WRITE)
        return self._request(slot, now)

    def _open_upload(self, slot: _Transfer, src: Peer, count: int, start: int, now: float, *,
                     partial: bool) -> None:
        slot.partner, slot.count, slot.expected, slot.received, slot.retries = src, count, start, [], 0
        slot.start, slot.partial, slot.last_heard = start, partial, now
        slot.as_int, slot.warned = self.behaviour.request_int, frozenset()

    def _on_item(self, msg: Any, src: Peer, now: float) -> list[Send]:
        slot, refusal = self._slot_for(msg, src)
        if refusal is not None:
            return refusal
        t = slot.mission_type
        if slot.state is _IDLE:
            return self._stray_item(msg, t, src, now)
        if slot.state is not _RECEIVING:
            return []  # an item from our own download partner means nothing; ignore it
        b = self.behaviour
        slot.last_heard = now
        is_int = msg._type == m.ITEM_INT
        out = [] if is_int else self._warn_legacy(slot, "item", "got MISSION_ITEM; GCS should send MISSION_ITEM_INT")
        if b.follow_gcs_int_mode:
            slot.as_int = is_int
        if msg.seq != slot.expected:
            return out + self._out_of_sequence(slot, msg.seq, now)
        item = m.item_from_message(msg)
        if item is None:
            code = (MissionResult.INVALID_PARAM5_X if m.float_xy_defect(msg) == 5
                    else MissionResult.INVALID_PARAM6_Y)
            return out + self._reject(slot, code, src)
        if b.mission_type_ignored and item.mission_type is not t:
            item = replace(item, mission_type=t)
        defect = first_defect(item, b.item_rules)
        if defect is not None:
            return out + self._reject(slot, defect.code, src)
        item = self._keep(item)
        slot.received.append(item)
        if self._counters is not None:
            self._counters.took(msg.seq)
        if not b.atomic_upload:   # written as it arrives (A2); item 0 clears the plan (item0_clears_plan)
            self._write(t, list(slot.received) if b.item0_clears_plan and not slot.partial
                        else self._spliced(t, item.seq, [item]))
        if len(slot.received) < slot.count:
            slot.expected += 1
            self._move(slot, _ITEM_NEXT)
            return out + self._request(slot, now)
        items = slot.received
        if slot.partial:
            items = self._spliced(t, slot.start, items)
        self._move(slot, SlotEvent.ITEM_LAST)
        self._leave(slot)
        return out + self._commit(t, items, src, now)

    # --- timers ---------------------------------------------------------------------------
    def _on_timeout(self, slot: _Transfer, now: float) -> list[Send]:
        if slot.state is _SENDING:
            self._move(slot, SlotEvent.TIMEOUT_GIVE_UP)  # the GCS went quiet; it drives retries
            self._leave(slot)
            return []
        b = self.behaviour
        protocol = b.timings.protocol_timeout
        expired = protocol is not None and now >= slot.last_heard + protocol
        if not expired and (not b.retry_cap or slot.retries < b.timings.max_retries):
            slot.retries += 1
            self.stats.retries += 1
            self.stats.max_consecutive_retries = max(self.stats.max_consecutive_retries, slot.retries)
            self._move(slot, _TIMEOUT_RETRY)
            return self._request(slot, now, reset_retries=False)
        partner, t = slot.partner, slot.mission_type
        self._move(slot, SlotEvent.TIMEOUT_GIVE_UP)
        self.stats.uploads_failed += 1
        self._leave(slot)
        out = []
        if b.notify_upload_give_up:
            out.append(Send(m.ack_message(MissionResult.OPERATION_CANCELLED, t, partner), partner))
        if b.give_up_statustext:
            out.append(Send(m.statustext_message(Severity.WARNING, b.give_up_statustext)))
        return out

    def _out_of_sequence(self, slot: _Transfer, seq: int, now: float) -> list[Send]:
        """Seed 000: an out-of-sequence item is dropped and the expected one re-requested.

        A copy of an item already received (seq < expected) is dropped without a new
        request: our request for the expected item is already out and its timer covers a
        loss, while answering every stale duplicate would start a second request/item
        stream for the rest of the transfer, then a third, and so on. An item beyond the
        expected one (a gap) is re-requested at once. Neither moves the deadline or resets
        the retry count: only progress does, so a peer that keeps sending the wrong item
        cannot hold the transfer open."""
        self._move(slot, _ITEM_OUT_OF_SEQUENCE)
        b = self.behaviour
        out = []
        if b.out_of_sequence_reply is not None:
            out.append(Send(m.ack_message(b.out_of_sequence_reply, slot.mission_type, slot.partner), slot.partner))
        if seq < slot.expected or not b.rerequest_gap:
            return out
        self.stats.rerequests += 1
        return out + [Send(self._request_msg(slot), slot.partner)]

    # --- helpers -------------------------------------------------------------------------
    def _request_msg(self, slot: _Transfer) -> Any:
        return m.request_message(slot.expected, slot.mission_type, slot.partner, as_int=slot.as_int)

    def _request(self, slot: _Transfer, now: float, *, reset_retries: bool = True) -> list[Send]:
        if reset_retries:
            slot.retries = 0
        timings = self.behaviour.timings
        if not self.behaviour.upload_timers:   # no timer: never re-requested, never given up
            slot.deadline = None
            return [Send(self._request_msg(slot), slot.partner)]
        slot.deadline = now + timings.item_timeout
        if timings.protocol_timeout is not None:
            slot.deadline = min(slot.deadline, slot.last_heard + timings.protocol_timeout)
        return [Send(self._request_msg(slot), slot.partner)]

    def _write(self, t: MissionType, items: list[MissionItem]) -> None:
        """Store `items` at once (non-atomic uploads); the final ACK still commits."""
        self.store.commit(t, items)

    def _spliced(self, t: MissionType, start: int, items: list[MissionItem]) -> list[MissionItem]:
        """The stored plan with `items` written from seq `start` on."""
        plan = list(self.store.items(t))
        return plan[:start] + list(items) + plan[start + len(items):]

    def _commit(self, t: MissionType, items: list[MissionItem], src: Peer, now: float) -> list[Send]:
        self.store.commit(t, items)
        opaque_id = self._opaque_id(t)
        self.stats.uploads_accepted += 1
        if items and self.behaviour.reack_last_item:
            until = now + self.behaviour.download_idle_timeout
            self._last_accepted[t] = _LastAccepted(src, tuple(items), opaque_id, until)
        else:
            self._last_accepted.pop(t, None)
        out = [Send(m.ack_message(MissionResult.ACCEPTED, t, src, opaque_id), src)]
        if t is MISSION_PLAN:
            out += self.progress.plan_replaced(now)
        return out

    def _reject(self, slot: _Transfer, code: MissionResult, src: Peer) -> list[Send]:
        if not self.behaviour.nack_ends_upload:   # A3: the NACK is sent, the upload goes on
            self._move(slot, SlotEvent.ITEM_REFUSED_GOES_ON)
            return [Send(m.ack_message(code, slot.mission_type, src), src)]
        self._move(slot, SlotEvent.ITEM_REJECTED)
        self.stats.uploads_failed += 1
        self._leave(slot)
        return [Send(m.ack_message(code, slot.mission_type, src), src)]

    def _stray_item(self, msg: Any, t: MissionType, src: Peer, now: float) -> list[Send]:
        if self._counters is not None:
            return self._continued_upload(msg, t, src)
        code = self.behaviour.foreign_type_item_reply
        if code is not None:
            running = next((s for s in self._slot_list if s.state is _RECEIVING
                            and s.partner == src), None)
            if running is not None:   # P7: an item of another type than the partner's upload
                running.last_heard = now
                self._move(self._slots[t], SlotEvent.STRAY)
                return [Send(m.ack_message(code, running.mission_type, src), src)]
        last = self._last_accepted.get(t)
        if last is not None and last.partner == src and now <= last.until:
            # A late copy of an item of the upload we just accepted: that GCS has not seen
            # our final ACK yet (it was lost, or a delayed duplicate request drew this item).
            item = m.item_from_message(msg)
            if item is not None:
                item = self._keep(item)   # compared in the form it was stored in
            if item is not None and item.seq < len(last.items) and item == last.items[item.seq]:
                return [Send(m.ack_message(MissionResult.ACCEPTED, t, src, last.opaque_id), src)]
        return self._stray(t, src)

    def _continued_upload(self, msg: Any, t: MissionType, src: Peer) -> list[Send]:
        """An item with no upload running, on a vehicle whose upload counters outlive the
        upload (upload_counters_persist, INAV 9.1: upload_counters.py)."""
        item = m.item_from_message(msg)
        if item is None:
            return self._stray(t, src)
        if self.behaviour.mission_type_ignored and item.mission_type is not t:
            item = replace(item, mission_type=t)
        defect = first_defect(item, self.behaviour.item_rules)
        if defect is not None:
            return [Send(m.ack_message(defect.code, t, src), src)]
        stored = list(self.store.items(t))
        verdict = self._counters.stray(item.seq, len(stored))
        if verdict.store is not None:
            self.stats.stray_items_stored += 1
            self._write(t, [self._keep(item)] if verdict.store == "replace" else stored + [self._keep(item)])
        if verdict.reply is None:
            return [Send(m.request_message(verdict.request, t, src, as_int=self.behaviour.request_int), src)]
        return [Send(m.ack_message(verdict.reply, t, src), src)]

    def _stray(self, t: MissionType, src: Peer) -> list[Send]:
        self.stats.stray += 1
        self._move(self._slots[t], SlotEvent.STRAY)
        code = self.behaviour.idle_reply
        return [] if code is None else [Send(m.ack_message(code, t, src), src)]
