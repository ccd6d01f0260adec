"""QGroundControl's MockLink mission failure modes, injected in front of any vehicle.

QGC tests its mission manager against MockLink, a fake vehicle with a switch per failure
(ANCHORS.md, "QGroundControl MockLink"; `MockLinkMissionItemHandler`): no answer to
MISSION_REQUEST_LIST, an item sent with seq + 1, an error ACK instead of a request, no final
ACK, and so on. `MockLinkVehicle` wraps a real vehicle node (any profile) and does the same
to the traffic around it: it drops what the vehicle would have received, or drops or
rewrites what it sends, following MockLink's own rules ("incorrect sequence" is seq + 1,
"error ACK" is MAV_MISSION_ERROR, "missing requests" is ACCEPTED in place of request 3).
Every injection is counted and logged, so a test can prove the failure was on the wire.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..mission import messages as m
from ..mission.constants import MissionResult
from ..mission.items import MissionType
from ..mission.results import Operation
from ..net.node import Address
from ..wire.codec import FrameDecoder, FrameEncoder

REQUESTS = frozenset({m.REQUEST_INT, m.REQUEST_FLOAT})
ITEMS = frozenset({m.ITEM_INT, m.ITEM_FLOAT})


@dataclass(frozen=True)
class FailureMode:
    """One MockLink switch. `inbound`: it acts on what the GCS sends (the vehicle never sees
    the message, as MockLink ignores it); otherwise on what the vehicle sends."""

    id: str
    qgc: str                      # the FailureMode_t name in MockLinkMissionItemHandler.h
    operation: Operation          # READ = download, WRITE = upload
    description: str
    qgc_recovers: bool            # what QGC's MissionManagerTest expects of QGC
    names: frozenset[str]         # messages it acts on
    seq: int | None = None        # only those with this seq (None: any)
    action: str = "drop"          # drop | bump-seq | error-ack | accept-ack
    inbound: bool = False
    first_only: bool = False      # only the first match ("first response lost")
    accepted_only: bool = False   # MISSION_ACK: only ACCEPTED ones (the final ACK)

    def matches(self, msg: Any) -> bool:
        if msg._type not in self.names or getattr(msg, "mission_type", 0) != MissionType.MISSION:
            return False
        if self.seq is not None and msg.seq != self.seq:
            return False
        return not self.accepted_only or msg.type == MissionResult.ACCEPTED


_R, _W = Operation.DOWNLOAD, Operation.UPLOAD
_LIST, _COUNT, _ACK = frozenset({"MISSION_REQUEST_LIST"}), frozenset({"MISSION_COUNT"}), frozenset({"MISSION_ACK"})

MODES: tuple[FailureMode, ...] = (
    FailureMode("read-list-no-response", "FailReadRequestListNoResponse", _R,
                "no response to MISSION_REQUEST_LIST", False, _LIST, inbound=True),
    FailureMode("read-list-first-lost", "FailReadRequestListFirstResponse", _R,
                "first response to MISSION_REQUEST_LIST lost", True, _LIST, inbound=True, first_only=True),
    FailureMode("read-req0-no-response", "FailReadRequest0NoResponse", _R,
                "no response to request 0", False, REQUESTS, 0, inbound=True),
    FailureMode("read-req1-no-response", "FailReadRequest1NoResponse", _R,
                "no response to request 1", False, REQUESTS, 1, inbound=True),
    FailureMode("read-req1-first-lost", "FailReadRequest1FirstResponse", _R,
                "first response to request 1 lost", True, REQUESTS, 1, inbound=True, first_only=True),
    FailureMode("read-req0-bad-seq", "FailReadRequest0IncorrectSequence", _R,
                "incorrect sequence (seq + 1) in the answer to request 0", False, ITEMS, 0, "bump-seq"),
    FailureMode("read-req1-bad-seq", "FailReadRequest1IncorrectSequence", _R,
                "incorrect sequence (seq + 1) in the answer to request 1", False, ITEMS, 1, "bump-seq"),
    FailureMode("read-req0-error-ack", "FailReadRequest0ErrorAck", _R,
                "MISSION_ACK ERROR in answer to request 0", False, ITEMS, 0, "error-ack"),
    FailureMode("read-req1-error-ack", "FailReadRequest1ErrorAck", _R,
                "MISSION_ACK ERROR in answer to request 1", False, ITEMS, 1, "error-ack"),
    FailureMode("write-count-no-response", "FailWriteMissionCountNoResponse", _W,
                "no response (request 0) to MISSION_COUNT", False, REQUESTS, 0),
    FailureMode("write-count-first-lost", "FailWriteMissionCountFirstResponse", _W,
                "first response to MISSION_COUNT lost", True, _COUNT, inbound=True, first_only=True),
    FailureMode("write-req1-no-response", "FailWriteRequest1NoResponse", _W,
                "no request 1 after item 0", False, REQUESTS, 1),
    FailureMode("write-req0-bad-seq", "FailWriteRequest0IncorrectSequence", _W,
                "request 0 sent with an incorrect sequence (seq + 1)", False, REQUESTS, 0, "bump-seq"),
    FailureMode("write-req1-bad-seq", "FailWriteRequest1IncorrectSequence", _W,
                "request 1 sent with an incorrect sequence (seq + 1)", False, REQUESTS, 1, "bump-seq"),
    FailureMode("write-req0-error-ack", "FailWriteRequest0ErrorAck", _W,
                "MISSION_ACK ERROR instead of request 0", False, REQUESTS, 0, "error-ack"),
    FailureMode("write-req1-error-ack", "FailWriteRequest1ErrorAck", _W,
                "MISSION_ACK ERROR instead of request 1", False, REQUESTS, 1, "error-ack"),
    FailureMode("write-final-ack-missing", "FailWriteFinalAckNoResponse", _W,
                "no final MISSION_ACK", False, _ACK, accepted_only=True),
    FailureMode("write-final-ack-error", "FailWriteFinalAckErrorAck", _W,
                "MISSION_ACK ERROR as the final ACK", False, _ACK, action="error-ack", accepted_only=True),
    FailureMode("write-final-ack-early", "FailWriteFinalAckMissingRequests", _W,
                "final ACK ACCEPTED sent before all items were requested (in place of request 3)",
                False, REQUESTS, 3, "accept-ack"),
)
MODES_BY_ID: dict[str, FailureMode] = {mode.id: mode for mode in MODES}


class MockLinkVehicle:
    """A `DatagramNode` around a vehicle node that applies one `FailureMode` while armed."""

    def __init__(self, vehicle: Any, mode: FailureMode) -> None:
        self.vehicle = vehicle
        self.mode = mode
        self.armed = False
        self.injections: list[tuple[float, str]] = []   # (time, what was done), in order
        self._now = 0.0
        self._matched = 0
        self._in = FrameDecoder()
        self._out = FrameDecoder()
        self._encoders: dict[tuple[int, int], FrameEncoder] = {}

    @property
    def fired(self) -> int:
        return len(self.injections)

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        self._now = now
        if self.armed and self.mode.inbound:
            for frame in self._in.feed(data):
                msg = getattr(frame, "msg", None)
                if msg is not None and self._fires(msg):
                    self._log(f"dropped {_describe(msg)} on its way to the vehicle")
                    return
        self.vehicle.datagram_received(data, source, now)

    def poll(self, now: float) -> None:
        self._now = now
        self.vehicle.poll(now)

    def next_deadline(self) -> float | None:
        return self.vehicle.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out = self.vehicle.take_outgoing()
        if not self.armed or self.mode.inbound:
            return out
        kept: list[tuple[bytes, Address]] = []
        for data, dst in out:
            frames = self._out.feed(data)
            if not any(getattr(f, "msg", None) is not None and self._fires(f.msg) for f in frames):
                kept.append((data, dst))     # untouched, byte for byte
                continue
            parts: list[bytes] = []
            for frame in frames:
                msg = getattr(frame, "msg", None)
                if msg is None:
                    continue
                if not self.mode.matches(msg):
                    parts.append(frame.raw)
                    continue
                replacement = self._rewrite(msg)
                if replacement is None:
                    self._log(f"dropped {_describe(msg)} from the vehicle")
                    continue
                self._log(f"replaced {_describe(msg)} from the vehicle by {_describe(replacement)}")
                parts.append(self._encoder(frame).encode(replacement, version=frame.version))
            if parts:
                kept.append((b"".join(parts), dst))
        return kept

    # --- internals ------------------------------------------------------------------------
    def _fires(self, msg: Any) -> bool:
        if not self.mode.matches(msg):
            return False
        self._matched += 1
        return not self.mode.first_only or self._matched == 1

    def _rewrite(self, msg: Any) -> Any:
        action = self.mode.action
        target = (msg.target_system, msg.target_component)
        if action == "drop":
            return None
        if action == "bump-seq":
            msg.seq += 1          # a decoded copy of our own: safe to change
            return msg
        code = MissionResult.ERROR if action == "error-ack" else MissionResult.ACCEPTED
        return m.ack_message(code, msg.mission_type, target)

    def _encoder(self, frame: Any) -> FrameEncoder:
        key = frame.source
        enc = self._encoders.get(key)
        if enc is None:
            enc = self._encoders[key] = FrameEncoder(*key)
        return enc

    def _log(self, what: str) -> None:
        self.injections.append((self._now, what))


def _describe(msg: Any) -> str:
    name = msg._type
    if name == "MISSION_ACK":
        return f"MISSION_ACK {MissionResult.describe(msg.type)}"
    if hasattr(msg, "seq") and name != "MISSION_COUNT":
        return f"{name} seq {msg.seq}"
    return name
