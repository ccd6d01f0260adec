"""The tester's datagram node: a GCS that sends only what the script says.

Besides the scripted messages it sends one thing by itself, a GCS HEARTBEAT at 1 Hz, as
every MAVLink component must (seed 001, line 149) and as real autopilots need before they
route to a new GCS. Every frame from the target is kept, with its arrival time, for the
script's expectations; frames from anyone else (another tester, stray senders) are not.
"""

from __future__ import annotations

from typing import Any, Callable

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.wire.frame import Frame



class TesterNode:
    """A `DatagramNode`. `target` (system, component) filters what is kept; until it is
    known (discovery), every frame is kept."""

    def __init__(self, name: str, system: int, component: int) -> None:
        self.name = name
        self.endpoint = MavlinkEndpoint(system, component)
        self.target: tuple[int, int] | None = None
        self.inbox: list[tuple[float, Frame]] = []
        self.last_heard: float | None = None
        self.on_frame: Callable[[str, float, Frame], None] | None = None
        self.on_send: Callable[[str, Any], None] | None = None
        self.heartbeats = True
        self._next_heartbeat: float | None = 0.0

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        target = self.target
        for frame in self.endpoint.receive(data, source):
            if target is not None and (frame.src_system, frame.src_component) != target:
                continue
            self.last_heard = now
            self.inbox.append((now, frame))
            if self.on_frame is not None:
                self.on_frame(self.name, now, frame)

    def poll(self, now: float) -> None:
        if self.heartbeats and self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = now + m.HEARTBEAT_PERIOD
            self.endpoint.send(m.gcs_heartbeat_message(), self.target)

    def next_deadline(self) -> float | None:
        return self._next_heartbeat if self.heartbeats else None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- scripted sending -----------------------------------------------------------------
    def send(self, msg: Any) -> None:
        """Queue `msg` for the target: once its HEARTBEAT has been seen, to the address it
        speaks from only (a configured `localhost` and the learned 127.0.0.1 are one target,
        and strays we have heard from are not targets); before that, to the configured one."""
        self.endpoint.send(msg, self.target)
        if self.on_send is not None:
            self.on_send(self.name, msg)
