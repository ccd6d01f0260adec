"""The reference GCS: heartbeat, target discovery, mission client, one node.

A `DatagramNode` like the vehicle. The target vehicle is either given or discovered from
the first HEARTBEAT of an autopilot (not another GCS). Operations are started with the
time (`upload(..., now)`); results collect in `results` in the order they finish.

How the GCS adapts to the vehicle (adaptations.py) is chosen from the target's HEARTBEAT
`autopilot` field, as QGroundControl picks its firmware plugin, unless the config fixes it.

Operator control (MAV_CMD_REQUEST_OPERATOR_CONTROL) is off unless `GcsConfig.control` is
set; then a `ControlClient` follows the vehicle's CONTROL_STATUS, runs requests, releases
and takeover flags, and answers requests the vehicle forwards by the injected policy. Its
results go to `control_results`, apart from the mission `results`: the client also finishes
operations of its own (answers to forwarded requests), which must not be taken for a
mission operation's result. The 1 Hz HEARTBEAT is what keeps this GCS in control.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable, Sequence

from .endpoint import MavlinkEndpoint
from .errors import LocalProtocolError
from .handover.control_client import ClientConfig, ControlClient, Policy, always
from .handover.control_results import ControlResult, Decision, StatusChanged, TakeoverRequested
from .handover.gcs_handover import HandoverAgent
from .mission.actions import Finished, Peer
from .mission import messages as m
from .mission.adaptations import NONE, Adaptations, for_autopilot
from .mission.client import MissionClient
from .mission.items import MissionItem, MissionType
from .mission.results import OperationResult
from .mission.timing import Timings
from .net.node import Address
from .wire.dialect import mavlink as _d
from .wire.signing import SigningKey


@dataclass(frozen=True)
class GcsConfig:
    system: int = 255
    component: int = _d.MAV_COMP_ID_MISSIONPLANNER
    target: Peer | None = None          # None: the first autopilot whose HEARTBEAT we hear
    timings: Timings = Timings()
    upload_int: bool = True
    download_int: bool = True
    mavlink_version: int = 2
    signing: SigningKey | None = None
    # How to adapt to the vehicle; None: chosen from its HEARTBEAT autopilot (for_autopilot)
    adaptations: Adaptations | None = None
    # Operator control; None: off (a GCS that never asks for control, as before)
    control: ClientConfig | None = None


MAX_CONTROL_EVENTS = 1000


class GcsNode:
    def __init__(self, config: GcsConfig | None = None, *, remote: Address | None = None,
                 wall_clock: Callable[[], float] = time.time, control_policy: Policy = always(None),
                 handover: HandoverAgent | None = None) -> None:
        """`control_policy` answers requests for control the vehicle forwards to us while we
        own it (None from it: the operator answers later with `answer_takeover`)."""
        self.config = cfg = config or GcsConfig()
        self.endpoint = MavlinkEndpoint(cfg.system, cfg.component, version=cfg.mavlink_version,
                                        signing=cfg.signing, wall_clock=wall_clock)
        if remote is not None:
            self.endpoint.add_address(remote)
        self.target: Peer | None = cfg.target
        self.target_heartbeat: Any = None
        self.client: MissionClient | None = None
        self.results: list[OperationResult] = []
        self.adaptations: Adaptations = cfg.adaptations or NONE
        self.received: list[Any] = []   # every message from the target (the first 10 000)
        self._next_heartbeat: float | None = 0.0
        self.control: ControlClient | None = None
        self.control_policy = control_policy
        # the handover agent (handover/gcs_handover.py): its policy replaces control_policy
        self.handover = handover
        self.control_results: list[ControlResult] = []
        self.control_events: deque[TakeoverRequested | StatusChanged] = deque(maxlen=MAX_CONTROL_EVENTS)
        if self.target is not None:
            self._make_client()

    # --- operations -----------------------------------------------------------------------
    @property
    def connected(self) -> bool:
        return self.client is not None

    def upload(self, mission_type: MissionType, items: Sequence[MissionItem], now: float) -> None:
        self._run(self._require_client().upload(mission_type, items, now))

    def download(self, mission_type: MissionType, now: float) -> None:
        self._run(self._require_client().download(mission_type, now))

    def clear(self, mission_type: MissionType, now: float) -> None:
        self._run(self._require_client().clear(mission_type, now))

    def set_current(self, seq: int, now: float, *, via_command: bool = False) -> None:
        self._run(self._require_client().set_current(seq, now, via_command=via_command))

    def cancel(self, now: float) -> None:
        if self.client is not None:
            self._run(self.client.cancel(now))

    def send(self, msg: Any) -> None:
        """Send any message to the target (for commands outside the mission protocol)."""
        self.endpoint.send(msg, self.target)

    @property
    def busy(self) -> bool:
        return self.client is not None and self.client.busy

    # --- operator control -----------------------------------------------------------------
    def require_control(self) -> ControlClient:
        """The control client, or a LocalProtocolError saying why there is none yet."""
        if self.config.control is None:
            raise LocalProtocolError("operator control is off: set GcsConfig.control")
        if self.control is None:
            raise LocalProtocolError("no target vehicle yet: wait for its HEARTBEAT first")
        return self.control

    def request_control(self, now: float, *, allow_takeover: bool = False, timeout: float | None = None,
                        wait: bool = True) -> None:
        self._run_control(self.require_control().request_control(
            now, allow_takeover=allow_takeover, timeout=timeout, wait=wait))

    def release_control(self, now: float) -> None:
        self._run_control(self.require_control().release_control(now))

    def set_takeover(self, allowed: bool, now: float) -> None:
        self._run_control(self.require_control().set_takeover(allowed, now))

    def answer_takeover(self, decision: Decision, now: float) -> None:
        """The operator's late answer to a forwarded request the policy left open."""
        self._run_control(self.require_control().answer(decision, now))

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for frame in self.endpoint.receive(data, source):
            if self.target is None:
                self._maybe_discover(frame)
                continue
            target = self.target
            if frame.src_system != target[0] or (target[1] and frame.src_component != target[1]):
                continue
            if frame.msg._type == "HEARTBEAT":
                self.target_heartbeat = frame.msg
                self._adapt_to(frame.msg)
            if self.client is not None:
                self._run(self.client.handle(frame, now))
            if self.control is not None:
                self._run_control(self.control.handle(frame, now))
                if self.handover is not None:
                    self._run_control(self.handover.handle(frame, now, self.control))
            if len(self.received) < 10_000:
                self.received.append(frame.msg)

    def poll(self, now: float) -> None:
        if self.client is not None:
            self._run(self.client.poll(now))
        if self.control is not None:
            self._run_control(self.control.poll(now))
            if self.handover is not None:
                self._run_control(self.handover.poll(now, self.control))
        if self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = now + m.HEARTBEAT_PERIOD
            self.endpoint.send(m.gcs_heartbeat_message())

    def next_deadline(self) -> float | None:
        best = self._next_heartbeat
        client = self.client    # asked after every datagram: the usual engine first, no tuple
        t = client.next_deadline() if client is not None else None
        if t is not None and (best is None or t < best):
            best = t
        if self.control is not None:
            for engine in (self.control, self.handover):
                t = engine.next_deadline() if engine is not None else None
                if t is not None and (best is None or t < best):
                    best = t
        return best

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- internals ------------------------------------------------------------------------
    def _maybe_discover(self, frame: Any) -> None:
        msg = frame.msg
        if m.is_vehicle_heartbeat(msg):
            self.target = frame.source
            self.target_heartbeat = msg
            self._adapt_to(msg)
            self._make_client()

    @property
    def adaptations_used(self) -> tuple[str, ...]:
        """Ids of the adaptations that acted so far (in operations or between them), first use first."""
        return tuple(self.client.used) if self.client is not None else ()

    def _adapt_to(self, heartbeat: Any) -> None:
        """Pick the adaptation set for the target's autopilot (between operations only)."""
        if self.config.adaptations is not None:
            return
        chosen = for_autopilot(heartbeat.autopilot)
        if chosen != self.adaptations and not self.busy:
            self.adaptations = chosen
            if self.client is not None:
                self.client.adaptations = chosen

    def _make_client(self) -> None:
        cfg = self.config
        self.client = MissionClient(cfg.system, cfg.component, self.target, cfg.timings,
                                    upload_int=cfg.upload_int, download_int=cfg.download_int,
                                    adaptations=self.adaptations)
        if cfg.control is not None:
            self.control = ControlClient(cfg.system, cfg.component, self.target, cfg.control,
                                         policy=self.handover.policy if self.handover is not None
                                         else self.control_policy)

    def _require_client(self) -> MissionClient:
        if self.client is None:
            raise LocalProtocolError("no target vehicle yet: wait for its HEARTBEAT first")
        return self.client

    def _run_control(self, actions: list[Any]) -> None:
        for action in self.endpoint.send_all(actions):
            if isinstance(action, Finished):
                self.control_results.append(action.result)
            else:
                self.control_events.append(action)

    def _run(self, actions: list[Any]) -> None:
        for action in self.endpoint.send_all(actions):
            if isinstance(action, Finished):
                self.results.append(action.result)
