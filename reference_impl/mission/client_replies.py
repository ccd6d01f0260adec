"""What the GCS's mission engine does with each reply from the vehicle: the item requests of
an upload, the count and items of a download, MISSION_ACK, and the answers to a set-current
(client.py says who retries what). A mixin of `client.MissionClient`, with the codes these
replies are judged by; client.py keeps the operations, the timer and the bookkeeping."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING, Any

from . import messages as m
from .adaptations import (FINISH_RESTARTED_UPLOAD, HOME_AT_SEQ0, ITEM_INT_FOR_REQUEST, LONG_VEHICLE_TIMEOUT,
                          RETRY_REFUSED_SET_CURRENT, Adaptations, shift_jumps)
from .constants import Cmd, CommandResult, MissionResult, Severity
from .items import PLAN_TYPE_BY_VALUE, PLAN_TYPES, MissionItem, MissionType, renumber
from .results import Operation, Outcome
from .timing import Timings
from .transitions import ClientEvent, ClientState

if TYPE_CHECKING:
    from .actions import Peer
    from .client import Action, _Op

# NACK codes that only a vehicle judging the item it just received sends.
ITEM_DEFECT_CODES = frozenset({
    MissionResult.UNSUPPORTED_FRAME, MissionResult.UNSUPPORTED, MissionResult.INVALID,
    MissionResult.INVALID_PARAM1, MissionResult.INVALID_PARAM2, MissionResult.INVALID_PARAM3,
    MissionResult.INVALID_PARAM4, MissionResult.INVALID_PARAM5_X, MissionResult.INVALID_PARAM6_Y,
    MissionResult.INVALID_PARAM7,
})

# A set-current refusal the vehicle lifts by itself once it is idle again (P12): PX4's
# "WPM: IGN WP CURR CMD: Busy", our P12 vehicle's "... a transfer is in progress", and the
# command's TEMPORARILY_REJECTED. Any other refusal ("Not in list", DENIED, UNSUPPORTED, ...)
# is the vehicle's last word: asking again cannot change it, only a missing answer can.
TRANSIENT_SET_CURRENT_TEXTS = ("busy", "in progress")
TRANSIENT_COMMAND_RESULTS = frozenset({CommandResult.TEMPORARILY_REJECTED})

_S, _E = ClientState, ClientEvent
# Members read on every frame, bound once (client.py imports them too): on Python 3.11 each
# read of an enum member off its class (`_S.UPLOAD_SENDING`) is a slow metaclass hook.
_UPLOAD_SENDING, _DOWNLOAD_REQUESTING = _S.UPLOAD_SENDING, _S.DOWNLOAD_REQUESTING
_REQUEST, _ITEM, _ITEM_OUT_OF_SEQUENCE = _E.REQUEST, _E.ITEM, _E.ITEM_OUT_OF_SEQUENCE
_UPLOAD, _DOWNLOAD, _SET_CURRENT = Operation.UPLOAD, Operation.DOWNLOAD, Operation.SET_CURRENT


class ClientReplies:
    """The reply handlers; `MissionClient` supplies the attributes below and `_finish`,
    `_to_target`, `_move`, `_request_expected`, `_nack_ignored`, `_restart_download`,
    `_upload_unknown` and `_clear_next`."""

    target: Peer
    timings: Timings
    upload_int: bool
    download_int: bool
    answer_request_with_int: bool
    adaptations: Adaptations
    state: ClientState
    stray_replies: int
    used: dict[str, None]
    _served: dict[MissionType, list[MissionItem]]

    # --- handlers -------------------------------------------------------------------------
    def _on_request(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if msg.mission_type != op.mission_type:
            return []  # a request about another plan type is not about this upload
        if msg.seq >= op.count:
            out = [self._to_target(m.ack_message(MissionResult.INVALID_SEQUENCE, op.mission_type, self.target))]
            return out + self._finish(now, Outcome.PROTOCOL_ERROR, unknown=self._upload_unknown(op),
                                      detail=f"vehicle requested seq {msg.seq} of a {op.count}-item upload")
        op.answers += 1
        if op.answers > (op.count + 1) * (self.timings.max_retries + 1) * 2:
            return self._finish(now, Outcome.PROTOCOL_ERROR,
                                unknown=op.last_item_sent or self._upload_unknown(op), detail=(
                f"vehicle requested items {op.answers} times for a {op.count}-item upload"))
        self._move(_REQUEST)
        seq = msg.seq
        if msg._type == m.REQUEST_INT:
            as_int = self.upload_int
        elif self.answer_request_with_int:
            as_int = True
        else:
            as_int = self.adaptations.item_int_for_request
            if as_int:
                op.use(ITEM_INT_FOR_REQUEST.id)
        item_msg = m.item_message(op.items[seq], self.target, as_int=as_int)
        if seq == op.count - 1:
            op.last_item_sent = True
        op.last_sent = item_msg
        if self._lengthened_wait() and now - op.wait_from > self.timings.default_timeout:
            op.use(LONG_VEHICLE_TIMEOUT.id)   # without it we would have resent already
        # Progress (the vehicle moving on) restarts the wait; repeated or backward requests
        # are answered but do not, so a vehicle stuck on one item cannot keep us forever.
        if seq > op.highest_request or seq == op.last_request + 1:
            op.wait_from = now
            op.consecutive = 0
            op.waiting_out = False
            op.last_nack = None
            op.last_progress = now
            op.deadline = now + self._timeout_for(op)
        op.highest_request = max(op.highest_request, seq)
        op.last_request = seq
        return [self._to_target(item_msg)]

    def _on_count(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if msg.mission_type != op.mission_type or self.state is not _S.DOWNLOAD_LIST_SENT:
            return []  # a duplicate COUNT, or one for another plan type
        op.count, op.opaque_id = msg.count, getattr(msg, "opaque_id", 0)
        op.last_nack = None
        self._move(_E.COUNT)
        if op.count == 0:
            ack = self._to_target(m.ack_message(MissionResult.ACCEPTED, op.mission_type, self.target))
            return [ack] + self._finish(now, Outcome.SUCCESS, items=())
        op.consecutive = 0
        if op.home:
            op.use(HOME_AT_SEQ0.id)
        return self._request_expected(op, now)

    def _on_item(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if self.state is not _DOWNLOAD_REQUESTING:
            return []
        if msg.seq != op.expected:
            # Seed 000: dropped, and the expected item re-requested. A copy of an item we
            # already have (seq < expected) needs no new request: ours is out and its timer
            # covers a loss. A gap is re-requested at once, without moving the deadline.
            self._move(_ITEM_OUT_OF_SEQUENCE)
            if msg.seq < op.expected:
                return []
            # Once per request: a vehicle that keeps answering with the wrong item must not
            # draw an endless request/item volley; the request timer carries on from there.
            op.wrong_item = (msg.seq, op.expected)
            if op.gap_rerequested:
                return []
            op.gap_rerequested = True
            return [self._to_target(m.request_message(
                op.expected, op.mission_type, self.target, as_int=self.download_int))]
        if msg.mission_type != op.mission_type:
            # Field report (ANCHORS.md): fence items labelled as mission items.
            ack = self._to_target(m.ack_message(MissionResult.ERROR, op.mission_type, self.target))
            return [ack] + self._finish(now, Outcome.PROTOCOL_ERROR, detail=(
                f"vehicle sent a mission_type {msg.mission_type} item during a "
                f"{op.mission_type.label} download"))
        item = m.item_from_message(msg)
        if item is None:
            ack = self._to_target(m.ack_message(MissionResult.ERROR, op.mission_type, self.target))
            return [ack] + self._finish(now, Outcome.PROTOCOL_ERROR,
                                        detail=f"item {msg.seq} has x/y that no MISSION_ITEM_INT can hold")
        self._move(_ITEM)
        op.items.append(item)
        op.expected += 1
        op.consecutive = 0
        op.wrong_item = None
        if op.expected < op.count:
            return self._request_expected(op, now)
        ack = self._to_target(m.ack_message(MissionResult.ACCEPTED, op.mission_type, self.target))
        # drop the vehicle's home, and count DO_JUMP targets without it
        items = renumber(shift_jumps(op.items[op.home:], -op.home) if op.home else op.items)
        # `current` is the vehicle's progress marker (seed 000 field table), not the plan's:
        # the plan comes back without it, and which item was current is said beside it
        current = next((it.seq for it in items if it.current), None)
        plan = tuple(replace(it, current=0) if it.current else it for it in items)
        return [ack] + self._finish(now, Outcome.SUCCESS, items=plan, current_seq=current)

    def _on_ack(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if op.operation is Operation.SET_CURRENT:
            if msg.type == MissionResult.UNSUPPORTED and msg.mission_type == MissionType.MISSION:
                # a vehicle without missions: no item of it can ever be made current
                return self._set_current_refused(op, "vehicle answered MISSION_ACK UNSUPPORTED", now,
                                                 transient=False)
            return []
        if op.operation is Operation.CLEAR:
            if msg.mission_type not in (op.clearing, MissionType.ALL):
                return []  # an ACK about another plan type
            if _stale_for_clear(msg):
                return []  # a late copy of an earlier operation's ACK
        elif msg.mission_type != op.mission_type:
            return []  # an ACK about another plan type
        if (msg.type == MissionResult.OPERATION_CANCELLED
                and self.state in (_S.UPLOAD_COUNT_SENT, _S.DOWNLOAD_LIST_SENT, _S.CLEAR_SENT)):
            # Nothing of this operation has started on the vehicle's side yet, so a cancel is
            # about an earlier transfer (its reply to a late stray copy). Our resends go on;
            # if they are all in vain, this is the NACK reported.
            op.last_nack = msg.type
            return []
        if msg.type != MissionResult.ACCEPTED and self._nack_ignored(op, msg.type, now):
            return []
        if (msg.type == MissionResult.ERROR and op.operation is Operation.DOWNLOAD
                and self.adaptations.restart_download_on_error and op.restarts < self.timings.max_retries):
            return self._restart_download(op, now)
        if msg.type != MissionResult.ACCEPTED:
            # After the last item went out the vehicle may already have committed, and a
            # generic error can be its idle reply to a late duplicate; only a code about the
            # item itself proves the upload was refused.
            unknown = (op.operation is Operation.UPLOAD and op.last_item_sent
                       and msg.type not in ITEM_DEFECT_CODES)
            detail = f"vehicle answered {MissionResult.describe(msg.type)}"
            if op.cleared:
                # clearing type by type: those before this one are gone already
                unknown = True
                detail += (f" to clearing the {op.clearing.label}; already cleared: "
                           f"{', '.join(t.label for t in op.cleared)}")
            return self._finish(now, Outcome.NACK, nack=_result(msg.type),
                                unknown=unknown or self._upload_unknown(op, msg.type), detail=detail)
        if op.operation is Operation.CLEAR:
            if op.clear_queue:
                op.cleared.append(op.clearing)
                return self._clear_next(op, now)
            return self._finish(now, Outcome.SUCCESS)
        if op.operation is Operation.UPLOAD:
            if op.last_item_sent:
                if self.adaptations.finish_restarted_upload and op.items:
                    self._served[op.mission_type] = op.items
                return self._finish(now, Outcome.SUCCESS, opaque_id=getattr(msg, "opaque_id", 0))
            if self.state is _S.UPLOAD_COUNT_SENT:
                return []  # before any request: a late copy from an earlier operation
            return self._finish(now, Outcome.PROTOCOL_ERROR, unknown=self._upload_unknown(op), detail=(
                f"vehicle sent ACK ACCEPTED before requesting seq {op.count - 1}"))
        return []  # ACCEPTED during a download means nothing

    def _on_set_current_reply(self, op: _Op, msg: Any, name: str, now: float) -> list[Action]:
        if op.operation is not Operation.SET_CURRENT:
            return []
        if name == "MISSION_CURRENT" and msg.seq == op.seq:
            return self._finish(now, Outcome.SUCCESS)
        if name == "STATUSTEXT" and msg.severity <= Severity.WARNING and not op.via_command:
            # the message form's only failure notice (seed 000); the command has COMMAND_ACK
            text = msg.text.decode(errors="replace") if isinstance(msg.text, bytes) else msg.text
            text = text.rstrip(chr(0))
            transient = any(word in text.lower() for word in TRANSIENT_SET_CURRENT_TEXTS)
            return self._set_current_refused(op, f"vehicle said: {text}", now, transient=transient)
        if (name == "COMMAND_ACK" and msg.command == Cmd.DO_SET_MISSION_CURRENT
                and msg.result not in (CommandResult.ACCEPTED, CommandResult.IN_PROGRESS)):
            return self._set_current_refused(op, f"COMMAND_ACK {_command_result(msg.result)}", now,
                                             transient=msg.result in TRANSIENT_COMMAND_RESULTS)
        return []

    def _set_current_refused(self, op: _Op, why: str, now: float, *, transient: bool) -> list[Action]:
        """A definitive refusal ends the operation at once, named; only a busy vehicle is
        asked again (with RETRY_REFUSED_SET_CURRENT), as is one that does not answer."""
        if not transient or not self.adaptations.retry_refused_set_current:
            return self._finish(now, Outcome.REJECTED, detail=why)
        # P12/P2': a transfer the vehicle still holds for us blocks it; end that transfer,
        # and let the timer resend the set-current (it gives up after max_retries).
        op.use(RETRY_REFUSED_SET_CURRENT.id)
        op.refusal = why
        return [self._to_target(m.ack_message(MissionResult.OPERATION_CANCELLED, t, self.target))
                for t in PLAN_TYPES]

    def _late_request(self, op: _Op | None, msg: Any) -> list[Action]:
        """A request outside an upload of its type: the vehicle missed our cancel or timed
        out, or (FINISH_RESTARTED_UPLOAD) a late copy of our MISSION_COUNT restarted an upload
        that had already succeeded."""
        served = self._served.get(PLAN_TYPE_BY_VALUE.get(msg.mission_type))
        if served is not None and msg.seq < len(served):
            self._use(op, FINISH_RESTARTED_UPLOAD.id)
            as_int = msg._type == m.REQUEST_INT or self.adaptations.item_int_for_request
            return [self._to_target(m.item_message(served[msg.seq], self.target, as_int=as_int))]
        if op is not None:
            return []   # busy with something else: the vehicle's own timeout ends its transfer
        self.stray_replies += 1
        return [self._to_target(m.ack_message(
            MissionResult.OPERATION_CANCELLED, msg.mission_type, self.target))]

    def _use(self, op: _Op | None, adaptation_id: str) -> None:
        if op is not None:
            op.use(adaptation_id)
        self.used.setdefault(adaptation_id, None)


# Codes a vehicle gives only about an item or a count: never the answer to MISSION_CLEAR_ALL
# (UNSUPPORTED is: a plan type, or MAV_MISSION_TYPE_ALL, the vehicle does not clear).
_NOT_A_CLEAR_ANSWER = (ITEM_DEFECT_CODES - {MissionResult.UNSUPPORTED}) | {
    MissionResult.INVALID_SEQUENCE, MissionResult.NO_SPACE}


def _stale_for_clear(msg: Any) -> bool:
    """MISSION_ACK carries no operation id, so a late copy of an earlier operation's ACK can
    arrive while a clear waits. Two kinds can be told apart: an ACCEPTED that names a plan
    (`opaque_id` != 0: an upload's final ACK; a cleared plan has id 0), and a NACK whose
    code is only ever about an item or a count (found by the protocol fuzzer)."""
    if msg.type == MissionResult.ACCEPTED:
        return bool(getattr(msg, "opaque_id", 0))
    return msg.type in _NOT_A_CLEAR_ANSWER


def _command_result(code: int) -> str:
    """MAV_RESULT as its name (e.g. DENIED), or the number if the dialect has none."""
    try:
        return CommandResult(code).name
    except ValueError:
        return f"result {code}"


def _result(code: int) -> MissionResult | int:
    try:
        return MissionResult(code)
    except ValueError:
        return code
