"""The fuzzer's GCS: the reference `MissionClient` for operations, raw sends for the rest.

Well-formed operations go through the reference client, which is also the judge of
"every operation ends with exactly one result". What the client would never send (stray
ACKs, items nobody asked for, wrong ids) goes out raw through the same endpoint, so the
vehicle sees it from the same GCS. An upload's wire items may carry a `seq` or
`mission_type` other than the transfer's (seq gaps, another plan type): the client
answers the vehicle's requests as usual and the node rewrites those fields on the way
out (`outgoing`). A wire item's "fx"/"fy" are float overrides of x/y: when the item goes
out as MISSION_ITEM (float x/y) they replace the x/y the client converted from the int
ones, so out-of-range floats (1e10, NaN, +-inf, 215 deg) reach the vehicle inside a
transfer. A MISSION_ITEM_INT of the same item keeps its int32 x/y: a float has no meaning
there (its out-of-range ints are the wire item's own x/y).

With operator control (`--operator-control`) the GCS also runs the reference `ControlClient`
(`control`): requests, releases and the takeover flag go through it, so it is also the judge
of "every control operation ends with exactly one result"; the owner's answer to a request
the vehicle forwards is `answer` (allow, release, refuse, or None: no answer, the request
times out). Such a GCS sends HEARTBEAT at 1 Hz (the vehicle's owner-loss rule counts them),
except while `silence` keeps it quiet: a GCS lost for a while, then back.
"""

from __future__ import annotations

import copy
import time
from typing import Any, Callable, Sequence

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.handover.control_client import ControlClient
from mavconform.reference_impl.handover.control_results import ControlOperation, ControlResult, Decision
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Finished, Peer, Send
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.results import OperationResult
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net.node import Address

_ITEMS = ("MISSION_ITEM_INT", "MISSION_ITEM")
# What a user asks of the control client (its answers to forwarded requests are its own).
USER_CONTROL_OPS = frozenset({ControlOperation.REQUEST, ControlOperation.RELEASE,
                              ControlOperation.ALLOW_TAKEOVER, ControlOperation.DISALLOW_TAKEOVER})
# Rewrite keys that stand for MISSION_ITEM's float x/y (and mean nothing for MISSION_ITEM_INT).
FLOAT_XY = {"fx": "x", "fy": "y"}


def outgoing(msg: Any, over: dict[str, Any]) -> Any:
    """The copy of item message `msg` that goes out with the fields in `over` replaced.
    "fx"/"fy" replace x/y of a MISSION_ITEM only; any other key names a field both item
    messages have (seq, mission_type; a param or z, which are float32 in both) and is set
    on either. The client keeps the original, to resend."""
    msg = copy.copy(msg)
    for name, value in over.items():
        xy = FLOAT_XY.get(name)
        if xy is None:
            setattr(msg, name, value)
        elif msg._type == "MISSION_ITEM":
            setattr(msg, xy, float(value))
    return msg


class FuzzGcs:
    """A `DatagramNode`. Until `target` is known (discovery), it only listens for an
    autopilot's HEARTBEAT; `results` collects every operation result in finishing order.
    A `mute` GCS sends what it is told and never answers anything: a GCS that crashed or
    left mid-transfer, which only the vehicle's own timeouts can end."""

    def __init__(self, system: int, component: int, target: Peer | None, *,
                 timings: Timings | None = None, heartbeat: bool = False, mute: bool = False,
                 wall_clock: Callable[[], float] = time.time, control: bool = False) -> None:
        self.endpoint = MavlinkEndpoint(system, component, wall_clock=wall_clock)
        self.timings = timings or Timings()
        self.heartbeat = heartbeat
        self.mute = mute
        self.with_control = control and not mute
        self.control: ControlClient | None = None
        self.control_results: list[ControlResult] = []   # the user's operations, in finishing order
        self.control_answers: list[ControlResult] = []   # the client's own (answers, window closes)
        self.control_log: list[ControlResult] = []       # both, in finishing order
        self.answer: Decision | None = None              # the owner's answer to a forwarded request
        self.silent_until = 0.0                          # no HEARTBEAT before this (GCS loss)
        self.items_sent = 0                              # MISSION_ITEM(_INT)s sent since `listen()`
        self.float_only = False                          # the target reads no _INT forms (INAV)
        self.results: list[OperationResult] = []
        self.heard: list[Any] = []          # messages from the target since `listen()`
        self.listening = False
        self.counts: dict[int, int] = {}    # mission_type -> first MISSION_COUNT to us since `listen()`
        self.client: MissionClient | None = None
        self.target: Peer | None = None
        self._rewrite: dict[int, dict[str, Any]] = {}
        self._next_heartbeat: float | None = 0.0 if heartbeat else None
        if target is not None:
            self.set_target(target)

    @property
    def system(self) -> int:
        return self.endpoint.system

    def set_target(self, target: Peer) -> None:
        self.target = target
        self.client = MissionClient(self.endpoint.system, self.endpoint.component, target, self.timings)
        if self.with_control:
            self.control = ControlClient(self.endpoint.system, self.endpoint.component, target,
                                         policy=lambda request: self.answer)

    # --- operations -----------------------------------------------------------------------
    @property
    def busy(self) -> bool:
        return self.client is not None and self.client.busy

    def upload(self, mission_type: MissionType, items: Sequence[MissionItem],
               rewrite: dict[int, dict[str, Any]], *, as_float: bool, now: float) -> None:
        """Upload `items`; item k goes out with the fields in `rewrite[k]` replaced
        (`outgoing`: "fx"/"fy" only where it goes out as MISSION_ITEM). `as_float`: answer
        MISSION_REQUEST_INT with MISSION_ITEM too."""
        client = self._client()
        self._rewrite = rewrite
        client.upload_int = not (as_float or self.float_only)
        self._run(client.upload(mission_type, items, now))

    def download(self, mission_type: MissionType, now: float) -> None:
        client = self._client()
        client.download_int = not self.float_only
        self._run(client.download(mission_type, now))

    def clear(self, mission_type: MissionType, now: float) -> None:
        self._run(self._client().clear(mission_type, now))

    def set_current(self, seq: int, now: float, *, via_command: bool) -> None:
        self._run(self._client().set_current(seq, now, via_command=via_command))

    def cancel(self, now: float) -> None:
        self._run(self._client().cancel(now))

    # --- operator control (with `control`) ---------------------------------------------------
    @property
    def control_busy(self) -> bool:
        return self.control is not None and self.control.busy

    def request_control(self, now: float, *, allow_takeover: bool, timeout: float, wait: bool) -> None:
        self._run(self._control().request_control(now, allow_takeover=allow_takeover, timeout=timeout,
                                                  wait=wait))

    def release_control(self, now: float) -> None:
        self._run(self._control().release_control(now))

    def set_takeover(self, allowed: bool, now: float) -> bool:
        """The owner sets its takeover flag; False (nothing sent) when this GCS does not
        believe it is in control: its re-request would be a request for control."""
        client = self._control()
        if not client.in_control:
            return False
        self._run(client.set_takeover(allowed, now))
        return True

    def silence(self, now: float, seconds: float) -> None:
        """Send no HEARTBEAT for `seconds` from now (a GCS lost, then back)."""
        self.silent_until = max(self.silent_until, now + seconds)
        if self._next_heartbeat is not None:
            self._next_heartbeat = max(self._next_heartbeat, self.silent_until)

    def send_raw(self, msg: Any) -> None:
        """Send any message to the target's address, exactly as given."""
        self.endpoint.send(msg, self.target)

    def listen(self) -> None:
        """Start collecting what the target says (for probes and download bounds)."""
        self.heard, self.counts, self.listening = [], {}, True
        self.items_sent = 0

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for frame in self.endpoint.receive(data, source):
            msg = frame.msg
            if self.target is None:
                if m.is_vehicle_heartbeat(msg):
                    self.set_target((frame.src_system, frame.src_component))
                continue
            if (frame.src_system, frame.src_component) != self.target:
                continue
            if self.listening and len(self.heard) < 1000:
                self.heard.append(msg)
                if (msg._type == "MISSION_COUNT" and msg.target_system == self.system
                        and msg.mission_type not in self.counts):
                    self.counts[msg.mission_type] = msg.count
            if not self.mute:
                self._run(self.client.handle(frame, now))
                if self.control is not None:
                    self._run(self.control.handle(frame, now))

    def poll(self, now: float) -> None:
        if self.client is not None:
            self._run(self.client.poll(now))
        if self.control is not None:
            self._run(self.control.poll(now))
        if self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = max(now + m.HEARTBEAT_PERIOD, self.silent_until)
            if now >= self.silent_until:
                self.endpoint.send(m.gcs_heartbeat_message())

    def next_deadline(self) -> float | None:
        best = self._next_heartbeat
        for d in (self.client.next_deadline() if self.client is not None else None,
                  self.control.next_deadline() if self.control is not None else None):
            if d is not None and (best is None or d < best):
                best = d
        return best

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- internals ------------------------------------------------------------------------
    def _client(self) -> MissionClient:
        if self.client is None:
            raise RuntimeError("FuzzGcs has no target yet")
        return self.client

    def _control(self) -> ControlClient:
        if self.control is None:
            raise RuntimeError(f"FuzzGcs {self.system} has no operator-control client")
        return self.control

    def _run(self, actions: list[Any]) -> None:
        send = self.endpoint.send
        for action in actions:
            if isinstance(action, Send):
                msg = action.msg
                if msg._type in _ITEMS:
                    self.items_sent += 1
                    if self._rewrite and msg.seq in self._rewrite:
                        msg = outgoing(msg, self._rewrite[msg.seq])
                send(msg, action.to)
            elif isinstance(action, Finished):
                result = action.result
                if isinstance(result, ControlResult):
                    self.control_log.append(result)
                    (self.control_results if result.operation in USER_CONTROL_OPS
                     else self.control_answers).append(result)
                else:
                    self.results.append(result)
