"""The GCS side of the Mission Protocol as a sans-IO state machine.

Like the server: moves only through `CLIENT_TRANSITIONS`, no I/O, no clock. One operation
at a time (starting a second one while busy is the caller's bug: `LocalProtocolError`).
Every operation ends with exactly one `Finished(OperationResult)` action.

Who retries what (seed 000, "Timeouts and Retries"): the GCS resends MISSION_COUNT,
MISSION_REQUEST_LIST, MISSION_CLEAR_ALL and its item requests on a download; on an upload
the vehicle drives with its requests, and the GCS resends the item it last sent only when
the vehicle has gone quiet (this is how a lost final ACK is recovered). Out-of-sequence
items on a download are dropped and the expected one re-requested.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any, Sequence

from ..errors import LocalProtocolError
from ..wire.frame import Frame
from . import messages as m
from .actions import Finished, Peer, Send
from .constants import Cmd, CommandResult, MissionResult, Severity
from .items import MissionItem, MissionType, renumber
from .results import Operation, OperationResult, Outcome
from .timing import Timings
from .transitions import CLIENT_TRANSITIONS, ClientEvent, ClientState

Action = Send | Finished

# Broadcasts with no target fields: only a running set-current cares about them.
_STREAMED = frozenset({"HEARTBEAT", "MISSION_CURRENT", "GLOBAL_POSITION_INT", "STATUSTEXT",
                       "MISSION_ITEM_REACHED"})

# NACK codes that only a vehicle judging the item it just received sends.
ITEM_DEFECT_CODES = frozenset({
    MissionResult.UNSUPPORTED_FRAME, MissionResult.UNSUPPORTED, MissionResult.INVALID,
    MissionResult.INVALID_PARAM1, MissionResult.INVALID_PARAM2, MissionResult.INVALID_PARAM3,
    MissionResult.INVALID_PARAM4, MissionResult.INVALID_PARAM5_X, MissionResult.INVALID_PARAM6_Y,
    MissionResult.INVALID_PARAM7,
})

_S, _E = ClientState, ClientEvent


@dataclass
class _Op:
    operation: Operation
    mission_type: MissionType
    started: float
    items: list[MissionItem] = field(default_factory=list)  # upload: to send; download: received
    count: int = 0
    expected: int = 0
    last_sent: Any = None          # the message a timeout resends
    last_item_sent: bool = False   # upload: the final item went out at least once
    opaque_id: int = 0
    seq: int = 0                   # set current: the requested item
    via_command: bool = False      # set current: by MAV_CMD_DO_SET_MISSION_CURRENT
    last_request: int = -1         # upload: the seq the vehicle asked for last
    highest_request: int = -1      # upload: the highest seq it has asked for
    answers: int = 0               # upload: items sent in answer to requests
    retries: int = 0
    consecutive: int = 0
    max_consecutive: int = 0
    deadline: float | None = None


class MissionClient:
    """GCS-side mission engine for one target vehicle."""

    def __init__(self, system: int, component: int, target: Peer,
                 timings: Timings | None = None, *, upload_int: bool = True,
                 download_int: bool = True, answer_request_with_int: bool = False) -> None:
        self.system = system
        self.component = component
        self.target = target
        self.timings = timings or Timings()
        self.upload_int = upload_int              # what we send when asked with MISSION_REQUEST_INT
        self.download_int = download_int          # request items with MISSION_REQUEST_INT
        self.answer_request_with_int = answer_request_with_int  # MISSION_REQUEST -> ITEM_INT
        self.state = ClientState.IDLE
        # the last moves, for diagnosis and for tests that walk the transition table
        self.history: deque[tuple[ClientState, ClientEvent, ClientState]] = deque(maxlen=256)
        self.stray_replies = 0
        self._op: _Op | None = None

    # --- starting operations --------------------------------------------------------------
    @property
    def busy(self) -> bool:
        return self._op is not None

    def upload(self, mission_type: MissionType, items: Sequence[MissionItem], now: float) -> list[Action]:
        op = self._start(Operation.UPLOAD, mission_type, now, _E.START_UPLOAD)
        op.items = renumber(items, mission_type)
        op.count = len(op.items)
        # An empty upload is applied by its MISSION_COUNT alone (count 0 = clear), so from
        # here on the vehicle may have acted on it, as after the last item of a longer one.
        op.last_item_sent = op.count == 0
        return self._send_and_wait(op, m.count_message(op.count, mission_type, self.target), now)

    def download(self, mission_type: MissionType, now: float) -> list[Action]:
        op = self._start(Operation.DOWNLOAD, mission_type, now, _E.START_DOWNLOAD)
        return self._send_and_wait(op, m.request_list_message(mission_type, self.target), now)

    def clear(self, mission_type: MissionType, now: float) -> list[Action]:
        op = self._start(Operation.CLEAR, mission_type, now, _E.START_CLEAR)
        return self._send_and_wait(op, m.clear_all_message(mission_type, self.target), now)

    def set_current(self, seq: int, now: float, *, via_command: bool = False) -> list[Action]:
        op = self._start(Operation.SET_CURRENT, MissionType.MISSION, now, _E.START_SET_CURRENT)
        op.seq, op.via_command = seq, via_command
        msg = (m.set_current_command(seq, self.target) if via_command
               else m.set_current_message(seq, self.target))
        return self._send_and_wait(op, msg, now)

    def cancel(self, now: float) -> list[Action]:
        """Cancel the running operation (seed 000, "Canceling Operations")."""
        op = self._op
        if op is None:
            return []
        out: list[Action] = []
        if op.operation in (Operation.UPLOAD, Operation.DOWNLOAD):
            out.append(self._to_target(m.ack_message(
                MissionResult.OPERATION_CANCELLED, op.mission_type, self.target)))
        # a clear or set-current already sent may have been applied; so may an upload
        # whose last item went out
        unknown = op.operation in (Operation.CLEAR, Operation.SET_CURRENT) or op.last_item_sent
        return out + self._finish(now, Outcome.CANCELLED, detail="cancelled by this GCS",
                                  unknown=unknown)

    # --- events ---------------------------------------------------------------------------
    def handle(self, frame: Frame, now: float) -> list[Action]:
        msg = frame.msg
        target = self.target
        if frame.src_system != target[0] or (target[1] and frame.src_component != target[1]):
            return []
        name = msg._type
        if name in _STREAMED:
            return self._on_set_current_reply(self._op, msg, name, now) if self._op else []
        if getattr(msg, "target_system", 0) not in (0, self.system):
            return []
        op = self._op
        if op is None:
            return self._idle_reply(msg, name)
        if name == "MISSION_ACK":
            return self._on_ack(op, msg, now)
        if op.operation is Operation.UPLOAD and name in (m.REQUEST_INT, m.REQUEST_FLOAT):
            return self._on_request(op, msg, now)
        if op.operation is Operation.DOWNLOAD:
            if name == "MISSION_COUNT":
                return self._on_count(op, msg, now)
            if name in (m.ITEM_INT, m.ITEM_FLOAT):
                return self._on_item(op, msg, now)
        if op.operation is Operation.SET_CURRENT:
            return self._on_set_current_reply(op, msg, name, now)
        return []

    def poll(self, now: float) -> list[Action]:
        op = self._op
        if op is None or op.deadline is None or now < op.deadline:
            return []
        if op.consecutive >= self.timings.max_retries:
            what = {Operation.UPLOAD: "no request or final ACK from the vehicle",
                    Operation.DOWNLOAD: "no reply from the vehicle",
                    Operation.CLEAR: "no MISSION_ACK", Operation.SET_CURRENT: "no MISSION_CURRENT"}
            unknown = (op.operation is Operation.CLEAR
                       or (op.operation is Operation.UPLOAD and op.last_item_sent)
                       or op.operation is Operation.SET_CURRENT)
            return self._finish(now, Outcome.TIMEOUT, unknown=unknown,
                                detail=f"{what[op.operation]} after {op.consecutive} retries")
        op.retries += 1
        op.consecutive += 1
        op.max_consecutive = max(op.max_consecutive, op.consecutive)
        self._move(_E.TIMEOUT_RETRY)
        op.deadline = now + self._timeout_for(op)
        return [self._to_target(op.last_sent)]

    def next_deadline(self) -> float | None:
        return None if self._op is None else self._op.deadline

    # --- handlers -------------------------------------------------------------------------
    def _on_request(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if msg.mission_type != op.mission_type:
            return []  # a request about another plan type is not about this upload
        if msg.seq >= op.count:
            out = [self._to_target(m.ack_message(MissionResult.INVALID_SEQUENCE, op.mission_type, self.target))]
            return out + self._finish(now, Outcome.PROTOCOL_ERROR,
                                      detail=f"vehicle requested seq {msg.seq} of a {op.count}-item upload")
        op.answers += 1
        if op.answers > (op.count + 1) * (self.timings.max_retries + 1) * 2:
            return self._finish(now, Outcome.PROTOCOL_ERROR, unknown=op.last_item_sent, detail=(
                f"vehicle requested items {op.answers} times for a {op.count}-item upload"))
        self._move(_E.REQUEST)
        seq = msg.seq
        as_int = self.upload_int if msg._type == m.REQUEST_INT else self.answer_request_with_int
        item_msg = m.item_message(op.items[seq], self.target, as_int=as_int)
        if seq == op.count - 1:
            op.last_item_sent = True
        op.last_sent = item_msg
        # Progress (the vehicle moving on) restarts the wait; repeated or backward requests
        # are answered but do not, so a vehicle stuck on one item cannot keep us forever.
        if seq > op.highest_request or seq == op.last_request + 1:
            op.consecutive = 0
            op.deadline = now + self.timings.default_timeout
        op.highest_request = max(op.highest_request, seq)
        op.last_request = seq
        return [self._to_target(item_msg)]

    def _on_count(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if msg.mission_type != op.mission_type or self.state is not _S.DOWNLOAD_LIST_SENT:
            return []  # a duplicate COUNT, or one for another plan type
        op.count, op.opaque_id = msg.count, getattr(msg, "opaque_id", 0)
        self._move(_E.COUNT)
        if op.count == 0:
            ack = self._to_target(m.ack_message(MissionResult.ACCEPTED, op.mission_type, self.target))
            return [ack] + self._finish(now, Outcome.SUCCESS, items=())
        op.consecutive = 0
        return self._request_expected(op, now)

    def _on_item(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if self.state is not _S.DOWNLOAD_REQUESTING:
            return []
        if msg.seq != op.expected:
            # Seed 000: dropped, and the expected item re-requested. A copy of an item we
            # already have (seq < expected) needs no new request: ours is out and its timer
            # covers a loss. A gap is re-requested at once, without moving the deadline.
            self._move(_E.ITEM_OUT_OF_SEQUENCE)
            if msg.seq < op.expected:
                return []
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
        self._move(_E.ITEM)
        op.items.append(item)
        op.expected += 1
        op.consecutive = 0
        if op.expected < op.count:
            return self._request_expected(op, now)
        ack = self._to_target(m.ack_message(MissionResult.ACCEPTED, op.mission_type, self.target))
        return [ack] + self._finish(now, Outcome.SUCCESS, items=tuple(op.items))

    def _on_ack(self, op: _Op, msg: Any, now: float) -> list[Action]:
        if op.operation is Operation.SET_CURRENT:
            return []
        if msg.mission_type != op.mission_type and not (
                op.operation is Operation.CLEAR and msg.mission_type == MissionType.ALL):
            return []  # an ACK about another plan type
        if msg.type != MissionResult.ACCEPTED:
            # After the last item went out the vehicle may already have committed, and a
            # generic error can be its idle reply to a late duplicate; only a code about the
            # item itself proves the upload was refused.
            unknown = (op.operation is Operation.UPLOAD and op.last_item_sent
                       and msg.type not in ITEM_DEFECT_CODES)
            return self._finish(now, Outcome.NACK, nack=_result(msg.type), unknown=unknown,
                                detail=f"vehicle answered {MissionResult.describe(msg.type)}")
        if op.operation is Operation.CLEAR:
            return self._finish(now, Outcome.SUCCESS)
        if op.operation is Operation.UPLOAD:
            if op.last_item_sent:
                return self._finish(now, Outcome.SUCCESS, opaque_id=getattr(msg, "opaque_id", 0))
            if self.state is _S.UPLOAD_COUNT_SENT:
                return []  # before any request: a late copy from an earlier operation
            return self._finish(now, Outcome.PROTOCOL_ERROR, detail=(
                f"vehicle sent ACK ACCEPTED before requesting item {op.count - 1}"))
        return []  # ACCEPTED during a download means nothing

    def _on_set_current_reply(self, op: _Op, msg: Any, name: str, now: float) -> list[Action]:
        if op.operation is not Operation.SET_CURRENT:
            return []
        if name == "MISSION_CURRENT" and msg.seq == op.seq:
            return self._finish(now, Outcome.SUCCESS)
        if name == "STATUSTEXT" and msg.severity <= Severity.WARNING and not op.via_command:
            # the message form's only failure notice (seed 000); the command has COMMAND_ACK
            text = msg.text.decode(errors="replace") if isinstance(msg.text, bytes) else msg.text
            return self._finish(now, Outcome.REJECTED, detail=f"vehicle said: {text}")
        if (name == "COMMAND_ACK" and msg.command == Cmd.DO_SET_MISSION_CURRENT
                and msg.result != CommandResult.ACCEPTED):
            return self._finish(now, Outcome.REJECTED, detail=f"COMMAND_ACK result {msg.result}")
        return []

    def _idle_reply(self, msg: Any, name: str) -> list[Action]:
        """A request while we run no upload: the vehicle missed our cancel or timed out."""
        if name in (m.REQUEST_INT, m.REQUEST_FLOAT):
            self.stray_replies += 1
            return [self._to_target(m.ack_message(
                MissionResult.OPERATION_CANCELLED, msg.mission_type, self.target))]
        return []

    # --- helpers --------------------------------------------------------------------------
    def _start(self, operation: Operation, mission_type: MissionType, now: float,
               event: ClientEvent) -> _Op:
        if self._op is not None:
            raise LocalProtocolError(
                f"cannot start {operation.value}: {self._op.operation.value} is still running")
        self._op = _Op(operation, MissionType(mission_type), started=now)
        self._move(event)
        return self._op

    def _send_and_wait(self, op: _Op, msg: Any, now: float) -> list[Action]:
        op.last_sent = msg
        op.deadline = now + self._timeout_for(op)
        return [self._to_target(msg)]

    def _request_expected(self, op: _Op, now: float) -> list[Action]:
        msg = m.request_message(op.expected, op.mission_type, self.target, as_int=self.download_int)
        return self._send_and_wait(op, msg, now)

    def _timeout_for(self, op: _Op) -> float:
        if self.state is _S.DOWNLOAD_REQUESTING:
            return self.timings.item_timeout
        return self.timings.default_timeout

    def _finish(self, now: float, outcome: Outcome, *, items: tuple | None = None,
                opaque_id: int | None = None, nack: Any = None, detail: str = "",
                unknown: bool = False) -> list[Action]:
        op = self._op
        assert op is not None
        self._move(_E.FINISH)
        self._op = None
        result = OperationResult(
            operation=op.operation, mission_type=op.mission_type, outcome=outcome,
            items=items, opaque_id=op.opaque_id if opaque_id is None else opaque_id,
            nack=nack, retries=op.retries, max_consecutive_retries=op.max_consecutive,
            outcome_unknown=unknown, detail=detail, started=op.started, finished=now)
        return [Finished(result)]

    def _to_target(self, msg: Any) -> Send:
        return Send(msg, self.target)

    def _move(self, event: ClientEvent) -> None:
        try:
            new_state = CLIENT_TRANSITIONS[(self.state, event)]
        except KeyError:
            raise LocalProtocolError(f"client: no transition for {event.name} in {self.state.name}") from None
        self.history.append((self.state, event, new_state))
        self.state = new_state


def _result(code: int) -> MissionResult | int:
    try:
        return MissionResult(code)
    except ValueError:
        return code
