"""One socket to a UDP target for a whole campaign, and a watch on its HEARTBEAT.

A real vehicle's GCS link is bound to one peer (VARIANTS.md L1, L2), so every fuzz GCS
shares one socket (`SharedLink`, routed by system id), and that socket stays the same
from the first example to the last: a fresh local port per example would be a new peer to
the target each time (PX4 answers only its first), and finding the target again by its
HEARTBEAT would cost up to a second per example. Each example brings fresh GCS nodes and
a clean link (`attach`); the socket, the discovered target and the watch stay.

The watch reads every datagram from the target and keeps the time of its last HEARTBEAT:
when the target stops answering, that tells a crashed target (silent) from a hung one
(still beating).
"""

from __future__ import annotations

import time
from typing import Any

from mavconform.conformance.target_uri import TargetUri
from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.mission.messages import HEARTBEAT_PERIOD, gcs_heartbeat_message, is_vehicle_heartbeat
from mavconform.reference_impl.net import FaultModel, UdpDriver
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.net.shared_link import SharedLink
from mavconform.reference_impl.net.sim import CaptureHook
from mavconform.reference_impl.net.links import attach

from ..outcomes import TargetUnresponsive
from .faults import install

DISCOVERY_TIMEOUT = 5.0   # s for the target's first HEARTBEAT
WATCH_SYSTEM, WATCH_COMPONENT = 245, 190   # GCS A's ids: the watch speaks only to be found
# What a vehicle says in answer to a GCS (streams such as MISSION_CURRENT are not answers).
REPLIES = frozenset({"MISSION_ACK", "MISSION_COUNT", "MISSION_REQUEST", "MISSION_REQUEST_INT",
                     "MISSION_ITEM", "MISSION_ITEM_INT", "COMMAND_ACK"})


class Watch:
    """A `DatagramNode` that finds the target by its HEARTBEAT and keeps watching it. It
    sends a GCS HEARTBEAT at 1 Hz only until the target is found (a `udp:` target may wait
    to hear from us first); the fuzz GCSs take over from there."""

    def __init__(self, wall_clock: Any = time.time) -> None:
        self.endpoint = MavlinkEndpoint(WATCH_SYSTEM, WATCH_COMPONENT, wall_clock=wall_clock)
        self.target: tuple[int, int] | None = None
        self.address: Address | None = None
        self.autopilot: int | None = None
        self.mav_type: int | None = None
        self.last_heartbeat: float | None = None   # driver clock time of the target's last one
        self.last_reply: float | None = None       # ... and of its last answer to a GCS (REPLIES)
        self.last_status: tuple[float, Any] | None = None   # ... and its last CONTROL_STATUS
        self._next_beat: float | None = 0.0

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for frame in self.endpoint.receive(data, source):
            msg = frame.msg
            if msg._type in REPLIES and (frame.src_system, frame.src_component) == self.target:
                self.last_reply = now
                continue
            if msg._type == "CONTROL_STATUS" and self.target is not None and frame.src_system == self.target[0]:
                self.last_status = (now, msg)
                continue
            if not is_vehicle_heartbeat(msg):
                continue
            ids = (frame.src_system, frame.src_component)
            if self.target is None:
                self.target, self.address, self.autopilot = ids, source, msg.autopilot
                self.mav_type = msg.type
                self._next_beat = None
            if ids == self.target:
                self.last_heartbeat = now

    def poll(self, now: float) -> None:
        if self._next_beat is not None and now >= self._next_beat:
            self._next_beat = now + HEARTBEAT_PERIOD
            self.endpoint.send(gcs_heartbeat_message())

    def next_deadline(self) -> float | None:
        return self._next_beat

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()


class TargetConnection:
    """The campaign's link to `uri` (udp:, udpin:, tcp:, tcpin:, serial:), opened and the target found.

    `up` and `down` are GCS A's link faults (what leaves the socket, what reaches it): the
    same objects for the life of the connection, changed in place by each example."""

    def __init__(self, uri: TargetUri, *, seed: int = 0, capture: CaptureHook | None = None,
                 discovery_timeout: float | None = None) -> None:
        self.uri = uri
        if discovery_timeout is None:
            discovery_timeout = DISCOVERY_TIMEOUT
        self.up, self.down = FaultModel(), FaultModel()
        self.driver = UdpDriver(seed=seed)
        self.watch = Watch(wall_clock=self.driver.clock.wall)
        self.link = SharedLink(self.watch)
        try:
            if capture is not None:
                self.driver.add_capture(capture)
            peer, _ = attach(self.driver, self.link, uri.link, outgoing=self.up, incoming=self.down)
            if peer is not None:   # udpin: learnt from the target's first datagram
                self.watch.endpoint.add_address(peer)
            if not self.driver.run_until(lambda: self.watch.target is not None, timeout=discovery_timeout):
                raise TargetUnresponsive(f"no HEARTBEAT from {uri} within {discovery_timeout:g} s "
                                         "(is it running, and is the address right?)")
        except BaseException:
            self.driver.close()
            raise

    @property
    def target(self) -> tuple[int, int]:
        assert self.watch.target is not None
        return self.watch.target

    @property
    def address(self) -> Address:
        assert self.watch.address is not None
        return self.watch.address

    @property
    def autopilot(self) -> int | None:
        return self.watch.autopilot

    @property
    def mav_type(self) -> int | None:
        return self.watch.mav_type

    def heartbeat_age(self) -> float:
        """Seconds since the target's last HEARTBEAT (driver clock)."""
        last = self.watch.last_heartbeat
        return float("inf") if last is None else self.driver.clock.now() - last

    def control_status_after(self, since: float, timeout: float) -> Any | None:
        """The target's latest CONTROL_STATUS if it was received after `since` (driver clock),
        waiting up to `timeout` for one; None if none came."""
        watch = self.watch
        self.driver.run_until(lambda: watch.last_status is not None and watch.last_status[0] > since,
                              timeout=max(0.0, timeout))
        last = watch.last_status
        return last[1] if last is not None and last[0] > since else None

    def replies_quiet(self, since: float, quiet: float) -> bool:
        """No answer from the target for `quiet` s, counted from `since` at the earliest."""
        last = max(since, self.watch.last_reply or since)
        return self.driver.clock.now() - last >= quiet

    def attach(self, nodes: list[Any]) -> None:
        """The GCS nodes of a new example on the socket (the previous ones leave), on a
        clean link."""
        self.link.nodes = [self.watch, *nodes]
        install(self.up, FaultModel())
        install(self.down, FaultModel())

    def close(self) -> None:
        self.driver.close()
