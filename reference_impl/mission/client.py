"""The GCS side of the Mission Protocol as a sans-IO state machine.

Like the server: moves only through `CLIENT_TRANSITIONS`, no I/O, no clock. One operation
at a time (starting a second one while busy is the caller's bug: `LocalProtocolError`).
Every operation ends with exactly one `Finished(OperationResult)` action.

Who retries what (seed 000, "Timeouts and Retries"): the GCS resends MISSION_COUNT,
MISSION_REQUEST_LIST, MISSION_CLEAR_ALL and its item requests on a download; on an upload
the vehicle drives with its requests, and the GCS resends the item it last sent only when
the vehicle has gone quiet (this is how a lost final ACK is recovered). Out-of-sequence
items on a download are dropped and the expected one re-requested (once per request, so a
vehicle that keeps sending the wrong item cannot start an endless volley). A MISSION_ACK
OPERATION_CANCELLED that comes before the vehicle has answered our opening message is about
an earlier transfer (its reply to a late stray copy) and does not end the operation; if
every resend is in vain it is the NACK reported.

Vehicles that depart from the spec are met with `Adaptations` (adaptations.py): knobs read
here, chosen outside from the vehicle's HEARTBEAT. Each operation records the adaptations
that changed what it did, and its result lists them. What it does with each reply from the
vehicle is in client_replies.py.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any, Sequence

from ..errors import LocalProtocolError
from ..state_table import next_state
from ..wire.frame import Frame
from . import messages as m
from .actions import Finished, Peer, Send
from .adaptations import (CLEAR_TYPES_SEPARATELY, HOME_AT_SEQ0,
                          IGNORE_NONTERMINATING_NACK, LONG_VEHICLE_TIMEOUT,
                          AWAIT_ACCEPT_AFTER_NACK, NON_ATOMIC_UPLOAD, NONE,
                          RESTART_DOWNLOAD_ON_ERROR, Adaptations,
                          home_placeholder, shift_jumps)
from .client_replies import (_DOWNLOAD, _DOWNLOAD_REQUESTING, _SET_CURRENT, _UPLOAD, _UPLOAD_SENDING,
                             ITEM_DEFECT_CODES, TRANSIENT_COMMAND_RESULTS, TRANSIENT_SET_CURRENT_TEXTS,
                             ClientReplies, _result)
from .constants import MissionResult
from .items import PLAN_TYPES, MissionItem, MissionType, renumber
from .results import Operation, OperationResult, Outcome
from .timing import Timings
from .transitions import CLIENT_TRANSITIONS, ClientEvent, ClientState

__all__ = ["ITEM_DEFECT_CODES", "TRANSIENT_COMMAND_RESULTS", "TRANSIENT_SET_CURRENT_TEXTS", "Action",
           "MissionClient"]

Action = Send | Finished

# Broadcasts with no target fields: only a running set-current cares about them.
_STREAMED = frozenset({"HEARTBEAT", "MISSION_CURRENT", "GLOBAL_POSITION_INT", "STATUSTEXT",
                       "MISSION_ITEM_REACHED"})

# NACKs that refuse an operation's opening message itself (nothing was changed by it).
_REFUSALS = frozenset({MissionResult.NO_SPACE, MissionResult.DENIED, MissionResult.UNSUPPORTED})

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
    home: int = 0                  # 1: the vehicle keeps home at seq 0 of this plan (wire = plan + 1)
    clearing: MissionType | None = None                          # clear: the type in flight
    clear_queue: list[MissionType] = field(default_factory=list)  # clear: types still to clear
    cleared: list[MissionType] = field(default_factory=list)     # clear: types already cleared
    gap_rerequested: bool = False  # download: a gap was re-requested since the last request
    wrong_item: tuple[int, int] | None = None  # download: (got, wanted) of the last wrong item
    last_progress: float = 0.0     # upload: when the vehicle last moved on
    wait_from: float = 0.0         # upload: when the current wait for a request began
    waiting_out: bool = False      # upload: retries spent, waiting out the vehicle's timeout
    last_nack: int | None = None   # a NACK ignored by an adaptation (reported if we give up)
    restarts: int = 0              # download: restarts after a vehicle error
    refusal: str = ""              # set current: the vehicle's last refusal, being retried
    held_nack: bool = False        # upload: a NACK after the last item, waiting for ACCEPTED
    used: list[str] = field(default_factory=list)  # ids of adaptations that acted

    def use(self, adaptation_id: str) -> None:
        if adaptation_id not in self.used:
            self.used.append(adaptation_id)


class MissionClient(ClientReplies):
    """GCS-side mission engine for one target vehicle."""

    def __init__(self, system: int, component: int, target: Peer,
                 timings: Timings | None = None, *, upload_int: bool = True,
                 download_int: bool = True, answer_request_with_int: bool = False,
                 adaptations: Adaptations = NONE) -> None:
        self.system = system
        self.component = component
        self.target = target
        self.timings = timings or Timings()
        self.upload_int = upload_int              # what we send when asked with MISSION_REQUEST_INT
        self.download_int = download_int          # request items with MISSION_REQUEST_INT
        self.answer_request_with_int = answer_request_with_int  # MISSION_REQUEST -> ITEM_INT
        self.adaptations = adaptations            # read at every step; replace only while idle
        self.state = ClientState.IDLE
        # the last moves, for diagnosis and for tests that walk the transition table
        self.history: deque[tuple[ClientState, ClientEvent, ClientState]] = deque(maxlen=256)
        self.stray_replies = 0
        self.used: dict[str, None] = {}   # ids of adaptations that ever acted, first use first
        # FINISH_RESTARTED_UPLOAD: the wire items of the last successful upload per plan type
        self._served: dict[MissionType, list[MissionItem]] = {}
        self._op: _Op | None = None

    # --- starting operations --------------------------------------------------------------
    @property
    def busy(self) -> bool:
        return self._op is not None

    def upload(self, mission_type: MissionType, items: Sequence[MissionItem], now: float) -> list[Action]:
        op = self._start(Operation.UPLOAD, mission_type, now, _E.START_UPLOAD)
        self._served.pop(op.mission_type, None)
        op.items = renumber(items, mission_type)
        op.last_progress = now
        if op.items and self.adaptations.home_offset(op.mission_type):
            # Seed 000 / A1: the vehicle's seq 0 is home, so the plan goes out from seq 1
            # (and a DO_JUMP's target with it).
            op.home = 1
            op.items = renumber([home_placeholder(op.items), *shift_jumps(op.items, 1)], mission_type)
            op.use(HOME_AT_SEQ0.id)
        op.count = len(op.items)
        # An empty upload is applied by its MISSION_COUNT alone (count 0 = clear), so from
        # here on the vehicle may have acted on it, as after the last item of a longer one.
        op.last_item_sent = op.count == 0
        return self._send_and_wait(op, m.count_message(op.count, mission_type, self.target), now)

    def download(self, mission_type: MissionType, now: float) -> list[Action]:
        op = self._start(Operation.DOWNLOAD, mission_type, now, _E.START_DOWNLOAD)
        op.home = self.adaptations.home_offset(op.mission_type)
        return self._send_and_wait(op, m.request_list_message(mission_type, self.target), now)

    def clear(self, mission_type: MissionType, now: float) -> list[Action]:
        op = self._start(Operation.CLEAR, mission_type, now, _E.START_CLEAR)
        for t in (PLAN_TYPES if op.mission_type is MissionType.ALL else (op.mission_type,)):
            self._served.pop(t, None)
        if op.mission_type is MissionType.ALL and self.adaptations.clear_types_separately:
            op.use(CLEAR_TYPES_SEPARATELY.id)
            op.clear_queue = list(PLAN_TYPES)
            return self._clear_next(op, now)
        op.clearing = op.mission_type
        return self._send_and_wait(op, m.clear_all_message(mission_type, self.target), now)

    def set_current(self, seq: int, now: float, *, via_command: bool = False) -> list[Action]:
        op = self._start(Operation.SET_CURRENT, MissionType.MISSION, now, _E.START_SET_CURRENT)
        op.home = self.adaptations.home_offset(MissionType.MISSION)
        if op.home:
            op.use(HOME_AT_SEQ0.id)
        op.seq, op.via_command = seq + op.home, via_command   # op.seq: as the vehicle counts
        msg = (m.set_current_command(op.seq, self.target) if via_command
               else m.set_current_message(op.seq, self.target))
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
        if not self._addressed_to_us(msg):
            return []
        op = self._op
        if name in (m.REQUEST_INT, m.REQUEST_FLOAT):
            if op is not None and op.operation is _UPLOAD and msg.mission_type == op.mission_type:
                return self._on_request(op, msg, now)
            return self._late_request(op, msg)
        if op is None:
            return []
        if name == "MISSION_ACK":
            return self._on_ack(op, msg, now)
        if op.operation is _DOWNLOAD:
            if name == "MISSION_COUNT":
                return self._on_count(op, msg, now)
            if name in (m.ITEM_INT, m.ITEM_FLOAT):
                return self._on_item(op, msg, now)
        if op.operation is _SET_CURRENT:
            return self._on_set_current_reply(op, msg, name, now)
        return []

    def _addressed_to_us(self, msg: Any) -> bool:
        """Seed 001's routing rule: ours when its target_system is ours (or 0, broadcast) and
        its target_component ours (or 0). Another GCS's reply on a shared link (a system or a
        component of ours beside this one) is not an answer to our operation."""
        return (getattr(msg, "target_system", 0) in (0, self.system)
                and getattr(msg, "target_component", 0) in (0, self.component))

    def poll(self, now: float) -> list[Action]:
        op = self._op
        if op is None or op.deadline is None or now < op.deadline:
            return []
        if op.held_nack:
            return self._finish(now, Outcome.NACK, nack=_result(op.last_nack), unknown=True, detail=(
                f"vehicle answered {MissionResult.describe(op.last_nack)} after the last item, "
                "and no ACCEPTED followed"))
        if op.waiting_out or op.consecutive >= self.timings.max_retries:
            if self._wait_out_vehicle(op, now):
                return []
            if op.refusal:
                return self._finish(now, Outcome.REJECTED, unknown=True,
                                    detail=f"{op.refusal} ({op.consecutive} retries)")
            if op.last_nack is not None:
                return self._finish(now, Outcome.NACK, nack=_result(op.last_nack),
                                    unknown=self._upload_unknown(op, op.last_nack), detail=(
                    f"vehicle kept answering {MissionResult.describe(op.last_nack)} "
                    f"({op.consecutive} retries)"))
            what = {Operation.UPLOAD: "no request or final ACK from the vehicle",
                    Operation.DOWNLOAD: "no reply from the vehicle",
                    Operation.CLEAR: "no MISSION_ACK", Operation.SET_CURRENT: "no MISSION_CURRENT"}
            unknown = (op.operation is Operation.CLEAR
                       or (op.operation is Operation.UPLOAD and op.last_item_sent)
                       or op.operation is Operation.SET_CURRENT)
            detail = f"{what[op.operation]} after {op.consecutive} retries"
            if op.wrong_item is not None:
                got, wanted = op.wrong_item
                detail = (f"vehicle answered the request for seq {wanted} with seq {got} "
                          f"({op.consecutive} retries)")
            return self._finish(now, Outcome.TIMEOUT, unknown=unknown or self._upload_unknown(op),
                                detail=detail)
        op.retries += 1
        op.consecutive += 1
        op.max_consecutive = max(op.max_consecutive, op.consecutive)
        self._move(_E.TIMEOUT_RETRY)
        if self._lengthened_wait():
            op.use(LONG_VEHICLE_TIMEOUT.id)   # this resend came later than it would have
        op.wait_from = now
        op.deadline = now + self._timeout_for(op)
        op.gap_rerequested = False
        return [self._to_target(op.last_sent)]

    def next_deadline(self) -> float | None:
        return None if self._op is None else self._op.deadline
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
        op.gap_rerequested = False
        msg = m.request_message(op.expected, op.mission_type, self.target, as_int=self.download_int)
        return self._send_and_wait(op, msg, now)

    def _timeout_for(self, op: _Op) -> float:
        if self.state is _DOWNLOAD_REQUESTING:
            return self.timings.item_timeout
        if self._lengthened_wait():
            # A5: wait out the vehicle's own re-request (~1 s on ArduPilot) before resending.
            return 2 * self.adaptations.vehicle_request_interval
        return self.timings.default_timeout

    def _lengthened_wait(self) -> bool:
        """Whether LONG_VEHICLE_TIMEOUT stretches the wait for the vehicle's next request."""
        interval = self.adaptations.vehicle_request_interval
        return (self.state is _UPLOAD_SENDING and interval is not None
                and 2 * interval > self.timings.default_timeout)

    def _wait_out_vehicle(self, op: _Op, now: float) -> bool:
        """Our retries are spent on an upload, but the vehicle may still be inside its own
        (longer) transfer timeout: wait, without resending, until that has surely passed,
        so its own give-up reaches us and both ends stop together. False: give up now."""
        vehicle_timeout = self.adaptations.vehicle_timeout
        if op.operation is not Operation.UPLOAD or vehicle_timeout is None:
            return False
        until = op.last_progress + vehicle_timeout + self.timings.default_timeout
        if op.waiting_out or now >= until:
            return False
        op.use(LONG_VEHICLE_TIMEOUT.id)
        op.waiting_out = True
        op.deadline = until
        return True

    def _nack_ignored(self, op: _Op, code: int, now: float) -> bool:
        """Whether an adaptation says this NACK does not end the operation."""
        adapt = self.adaptations
        if (op.operation is Operation.UPLOAD and adapt.ignore_nonterminating_nack
                and (code == MissionResult.INVALID_SEQUENCE
                     or (code == MissionResult.DENIED and self.state is _S.UPLOAD_SENDING))):
            # A3: the vehicle refused one stray copy of an item and carries on requesting.
            op.use(IGNORE_NONTERMINATING_NACK.id)
            return True
        if (op.operation is Operation.UPLOAD and adapt.await_accept_after_nack and op.last_item_sent
                and code not in ITEM_DEFECT_CODES and op.count > 0):
            # The committed vehicle's answer to a late duplicate item can overtake its ACCEPTED.
            if not op.held_nack:
                op.use(AWAIT_ACCEPT_AFTER_NACK.id)
                op.held_nack, op.last_nack = True, code
                op.deadline = now + self.timings.default_timeout
            return True
        if (code == MissionResult.DENIED and adapt.vehicle_timeout is not None
                and self.state in (_S.UPLOAD_COUNT_SENT, _S.DOWNLOAD_LIST_SENT, _S.CLEAR_SENT)
                and now < op.started + adapt.vehicle_timeout + self.timings.default_timeout):
            # A4/A8: the vehicle may still hold a transfer we (or another GCS) abandoned, which
            # it ends only on its own timeout; our resends go on until that has passed.
            op.use(LONG_VEHICLE_TIMEOUT.id)
            op.last_nack = code
            return True
        return False

    def _restart_download(self, op: _Op, now: float) -> list[Action]:
        """P6: the vehicle ended the download (a stale copy of an earlier request reached it
        out of order); ask for the list again and start over from item 0."""
        op.use(RESTART_DOWNLOAD_ON_ERROR.id)
        op.restarts += 1
        op.items, op.count, op.expected, op.consecutive, op.wrong_item = [], 0, 0, 0, None
        self._move(_E.RESTART)
        return self._send_and_wait(op, m.request_list_message(op.mission_type, self.target), now)

    def _upload_unknown(self, op: _Op, code: int | None = None) -> bool:
        """A2: a failed upload to a non-atomic vehicle may have left a mix of old and new,
        unless the vehicle refused the MISSION_COUNT itself."""
        if op.operation is not Operation.UPLOAD or not self.adaptations.non_atomic_upload:
            return False
        if code in _REFUSALS and self.state is _S.UPLOAD_COUNT_SENT:
            return False
        op.use(NON_ATOMIC_UPLOAD.id)
        return True

    def _clear_next(self, op: _Op, now: float) -> list[Action]:
        """A10: clear the next plan type on its own."""
        if op.clearing is not None:
            self._move(_E.CLEAR_NEXT)
        op.clearing = op.clear_queue.pop(0)
        op.consecutive = 0
        return self._send_and_wait(op, m.clear_all_message(op.clearing, self.target), now)

    def _finish(self, now: float, outcome: Outcome, *, items: tuple | None = None,
                opaque_id: int | None = None, nack: Any = None, detail: str = "",
                unknown: bool = False, current_seq: int | None = None) -> list[Action]:
        op = self._op
        assert op is not None
        self._move(_E.FINISH)
        self._op = None
        self.used.update(dict.fromkeys(op.used))
        result = OperationResult(
            operation=op.operation, mission_type=op.mission_type, outcome=outcome,
            items=items, current_seq=current_seq, opaque_id=op.opaque_id if opaque_id is None else opaque_id,
            nack=nack, retries=op.retries, max_consecutive_retries=op.max_consecutive,
            outcome_unknown=unknown, detail=detail, started=op.started, finished=now,
            adaptations=tuple(op.used))
        return [Finished(result)]

    def _to_target(self, msg: Any) -> Send:
        return Send(msg, self.target)

    def _move(self, event: ClientEvent) -> None:
        new_state = next_state(CLIENT_TRANSITIONS, self.state, event, "client")
        self.history.append((self.state, event, new_state))
        self.state = new_state
