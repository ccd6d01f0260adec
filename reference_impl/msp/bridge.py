"""The MAVLink <-> MSP mission bridge: a MAVLink vehicle whose mission is an MSP flight
controller's waypoint list (`mavconform bridge`, issue 25).

Two datagram nodes share one driver: `MspBridge` speaks MAVLink to the GCSs (HEARTBEAT at
1 Hz, the mission server of bridge_server.py, MISSION_CURRENT), `MspLink` speaks MSP to the
flight controller and runs one job at a time (jobs.py). They are `coupled`: what one does
may give the other something to send, and the drivers look at both after either moves.

- An upload is the reference server's; once every item is in (each checked against the
  mapping as it came), the waypoints are written with MSP_SET_WP and read back with MSP_WP,
  and only then is the upload ACCEPTED (or refused with MAV_MISSION_ERROR naming the
  waypoint and field). A failed write puts the mission held before back, if the flight
  controller still answers: a GCS's error never leaves half a mission behind.
- A download first reads the list (MSP_WP_GETINFO, MSP_WP), then serves it.
- A clear, or an empty upload, writes MSP's "no mission" record (jobs.EMPTY).
- Set-current asks MSP2_INAV_SET_WP_INDEX (INAV takes it only while armed in WP mode);
  MISSION_CURRENT follows MSP_NAV_STATUS's active waypoint, read every second while idle.
While a job runs, the GCSs' mission frames wait (bounded) and are handled after it, in order.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable

from ..endpoint import MavlinkEndpoint
from ..mission import messages as m
from ..mission.actions import Send
from ..mission.constants import Cmd, CommandResult, MissionResult, Severity
from ..net.node import Address
from ..vehicle_info import home_position_message
from ..wire.dialect import mavlink as _d
from .bridge_server import MISSION, BridgeServer, Pending, waypoints_for
from .commands import CODE, Waypoint
from .frame import ERROR, MspFrame, Version
from .jobs import Done, Failed, JobRunner, Result, nav_status, read_mission, read_waypoint, write_home, write_mission
from .nodes import MspClientNode

HEARTBEAT_PERIOD = 1.0
STATUS_PERIOD = 1.0          # s between MSP_NAV_STATUS reads while idle
MAX_HELD = 64                # GCS frames kept while a job runs; beyond, dropped and counted
SET_WP_INDEX = CODE["MSP2_INAV_SET_WP_INDEX"]
SET_CURRENT_REFUSED = "set current refused by the flight controller"


@dataclass(frozen=True)
class BridgeConfig:
    system: int = 1
    component: int = 1
    vehicle_type: int = _d.MAV_TYPE_GENERIC      # MSP_IDENT (seed 004's source for it) is gone from INAV
    autopilot: int = _d.MAV_AUTOPILOT_GENERIC_MISSION_FULL


class MspLink(MspClientNode):
    """The bridge's end of the MSP link: one job at a time, replies fed to it, no inbox kept."""

    def __init__(self, peer: Address | None = None, *, timeout: float | None = None) -> None:
        super().__init__(peer)
        self.runner = JobRunner(self.send) if timeout is None else JobRunner(self.send, timeout=timeout)
        self.coupled: list[Any] = []

    def took(self, frame: MspFrame, now: float) -> None:
        self.runner.reply(frame, now)

    def poll(self, now: float) -> None:
        self.runner.poll(now)

    def next_deadline(self) -> float | None:
        return self.runner.next_deadline()


class MspBridge:
    """The MAVLink side: a DatagramNode for the GCSs' link."""

    def __init__(self, link: MspLink, config: BridgeConfig | None = None, *,
                 wall_clock: Callable[[], float] = time.time) -> None:
        self.config = cfg = config or BridgeConfig()
        self.endpoint = MavlinkEndpoint(cfg.system, cfg.component, wall_clock=wall_clock)
        self.server = BridgeServer(cfg.system, cfg.component)
        self.link = link
        self.coupled = [link]
        link.coupled.append(self)
        self.held: deque[tuple[Any, float]] = deque()
        self.dropped = 0                       # GCS frames dropped because MAX_HELD were waiting
        self.events: list[str] = []
        self._next_heartbeat: float | None = 0.0
        self._next_status: float | None = 0.0

    # --- DatagramNode ------------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for frame in self.endpoint.receive(data, source):
            if self.link.runner.busy or self.held:
                if len(self.held) >= MAX_HELD:
                    self.dropped += 1
                    continue
                self.held.append((frame, now))
                continue
            self._on_frame(frame, now)

    def poll(self, now: float) -> None:
        self._send(self.server.poll(now))
        if self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = now + HEARTBEAT_PERIOD
            self.endpoint.send(_d.MAVLink_heartbeat_message(self.config.vehicle_type, self.config.autopilot,
                                                            _d.MAV_MODE_FLAG_AUTO_ENABLED, 0, _d.MAV_STATE_STANDBY, 3))
        if self._next_status is not None and now >= self._next_status:
            self._next_status = now + STATUS_PERIOD    # a busy link skips this read, never spins on it
            if not self.link.runner.busy and not self.held:
                self.link.runner.start(nav_status(), now, self._on_status)

    def next_deadline(self) -> float | None:
        times = [t for t in (self._next_heartbeat, self._next_status, self.server.next_deadline()) if t is not None]
        return min(times) if times else None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- the GCSs' frames ------------------------------------------------------------------
    def _on_frame(self, frame: Any, now: float) -> None:
        msg = frame.msg
        name = msg._type
        if not self._for_me(msg):
            return
        if name == "MISSION_REQUEST_LIST" and msg.mission_type == int(MISSION):
            self.link.runner.start(read_mission(), now, lambda result, at: self._serve_download(frame, result, at))
        elif name == "MISSION_SET_CURRENT":
            self._set_current(msg.seq, frame, now, command=False)
        elif name in ("COMMAND_LONG", "COMMAND_INT"):
            if msg.command == Cmd.DO_SET_MISSION_CURRENT:
                self._set_current(int(msg.param1), frame, now, command=True)
            elif msg.command == Cmd.GET_HOME_POSITION or (
                    msg.command == Cmd.REQUEST_MESSAGE and int(msg.param1) == _d.MAVLINK_MSG_ID_HOME_POSITION):
                self.link.runner.start(read_waypoint(0), now, lambda result, at: self._home(frame, result, at))
            elif msg.command == Cmd.DO_SET_HOME and name == "COMMAND_INT" and int(msg.param1) == 0:
                self._set_home(frame, now)
            else:
                self.endpoint.send(m.command_ack_message(msg.command, CommandResult.UNSUPPORTED, frame.source),
                                   frame.source)
        elif self.server.handles(name):
            self._send(self.server.handle(frame, now))
            if self.server.pending is not None:
                self._write(self.server.pending, now)

    def _for_me(self, msg: Any) -> bool:
        target = getattr(msg, "target_system", 0)
        return target in (0, self.config.system)

    # --- jobs --------------------------------------------------------------------------------
    def _write(self, pending: Pending, now: float) -> None:
        self.events.append(f"writing {len(pending.items)} items as {len(pending.waypoints)} MSP waypoints")
        before = tuple(self.server.store.items(MISSION))
        self.link.runner.start(write_mission(pending.waypoints), now,
                               lambda result, at: self._written(result, before, at))

    def _written(self, result: Result, before: tuple, now: float) -> None:
        self._send(self.server.finish(result, now))
        if isinstance(result, Failed):
            self.events.append(f"write failed: {result.why}")
            if not result.silent:
                old = waypoints_for(list(before))
                self.link.runner.start(write_mission(old), now, self._put_back)   # type: ignore[arg-type]
                return
        self._release(now)

    def _put_back(self, result: Result, now: float) -> None:
        self.events.append("put the mission held before back" if isinstance(result, Done)
                           else f"could not put the mission held before back: {result.why}")
        self._release(now)

    def _serve_download(self, frame: Any, result: Result, now: float) -> None:
        if isinstance(result, Failed):
            self._refuse_download(frame, result.why)
        else:
            why = self.server.refresh(result)
            if why is not None and why.startswith("waypoint action"):
                self._refuse_download(frame, why)
            else:
                if why is not None:
                    self.endpoint.send(m.statustext_message(Severity.WARNING, why[:50]))
                self._send(self.server.handle(frame, now))
        self._release(now)

    def _refuse_download(self, frame: Any, why: str) -> None:
        self.endpoint.send(m.statustext_message(Severity.ERROR, why[:50]))
        self.endpoint.send(m.ack_message(MissionResult.ERROR, MISSION, frame.source), frame.source)

    def _set_current(self, seq: int, frame: Any, now: float, *, command: bool) -> None:
        count = self.server.store.count(MISSION)
        if not 0 <= seq < min(count, 255):
            self._set_current_answer(frame, command, ok=False, why=f"no item {seq} in a {count}-item mission")
            self._release(now)
            return
        payload = bytes((seq,))

        def asked() -> Any:
            reply = yield MspFrame(SET_WP_INDEX, payload, version=Version.V2)
            return Done(payload=b"" if reply is None or reply.direction == ERROR else b"ok")

        def answered(result: Result, at: float) -> None:
            ok = isinstance(result, Done) and result.payload == b"ok"
            if ok:
                self._send(self.server.progress.set_current(seq, at))
            self._set_current_answer(frame, command, ok=ok, why=SET_CURRENT_REFUSED)
            self._release(at)
        self.link.runner.start(asked(), now, answered)

    def _set_current_answer(self, frame: Any, command: bool, *, ok: bool, why: str) -> None:
        """The command's COMMAND_ACK (ACCEPTED; TEMPORARILY_REJECTED when the flight controller
        refused, as INAV does on the ground; DENIED for an item the mission lacks) and, when
        refused, a STATUSTEXT saying why (MISSION_SET_CURRENT has no answer of its own)."""
        if command:
            result = (CommandResult.ACCEPTED if ok else CommandResult.TEMPORARILY_REJECTED
                      if why == SET_CURRENT_REFUSED else CommandResult.DENIED)
            self.endpoint.send(m.command_ack_message(Cmd.DO_SET_MISSION_CURRENT, result, frame.source), frame.source)
        if not ok:
            self.endpoint.send(m.statustext_message(Severity.WARNING, why[:50]))

    # --- home: MSP waypoint 0 (seed 004: HOME_POSITION <-> MSP_WP, SET_HOME_POSITION <-> MSP_SET_WP) ----
    def _home(self, frame: Any, result: Result, now: float) -> None:
        """HOME_POSITION from MSP_WP 0, which INAV fills only once it has a home (GPS fix):
        zeros mean none yet (TEMPORARILY_REJECTED)."""
        wp = result.waypoints[0] if isinstance(result, Done) else None
        known = wp is not None and (wp.lat or wp.lon)
        if known:
            self.endpoint.send(home_position_message(wp.lat / 1e7, wp.lon / 1e7, wp.alt / 100, now), frame.source)
        result_code = CommandResult.ACCEPTED if known else CommandResult.TEMPORARILY_REJECTED
        self.endpoint.send(m.command_ack_message(frame.msg.command, result_code, frame.source), frame.source)
        self._release(now)

    def _set_home(self, frame: Any, now: float) -> None:
        """MAV_CMD_DO_SET_HOME (COMMAND_INT, a given location) as MSP_SET_WP 0, read back with
        MSP_WP 0: INAV takes a home only while armed with a GPS fix (navigation.c:3958-3962)."""
        msg = frame.msg
        home = Waypoint(0, 1, msg.x, msg.y, round(msg.z * 100), 0, 0, 0, 0)

        def written(result: Result, at: float) -> None:
            back = result.waypoints[0] if isinstance(result, Done) and result.waypoints else None
            ok = back is not None and (back.lat, back.lon, back.alt) == (home.lat, home.lon, home.alt)
            code = CommandResult.ACCEPTED if ok else CommandResult.TEMPORARILY_REJECTED
            self.endpoint.send(m.command_ack_message(msg.command, code, frame.source), frame.source)
            self._release(at)
        self.link.runner.start(write_home(home), now, written)

    def _on_status(self, result: Result, now: float) -> None:
        if isinstance(result, Done) and len(result.payload) >= 4 and result.payload[3] >= 1:
            seq = result.payload[3] - 1
            if seq != self.server.progress.seq and seq < self.server.store.count(MISSION):
                self._send(self.server.progress.set_current(seq, now))
        self._release(now)

    def _release(self, now: float) -> None:
        """A job ended: handle the frames that waited for it, in order, until one starts another."""
        while self.held and not self.link.runner.busy:
            frame, _ = self.held.popleft()
            self._on_frame(frame, now)

    def _send(self, actions: list[Send]) -> None:
        for msg, to in actions:
            self.endpoint.send(msg, to)
