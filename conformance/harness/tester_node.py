"""The tester's datagram node: a GCS that sends only what the script says.

Besides the scripted messages it sends one thing by itself, a GCS HEARTBEAT at 1 Hz, as
every MAVLink component must (seed 001, line 149) and as real autopilots need before they
route to a new GCS. Every frame from the target is kept, with its arrival time, for the
script's expectations; frames from anyone else (another tester, stray senders) are not.

What of the target's we did not read is kept track of too, for the packet-sequence check:
the most frames one datagram from each source held (a datagram the kernel dropped before
we read it may have held that many frames), and, while `arrivals` is a list, each kept
frame with the frames its source had lost to us by then: decode errors before and after its
datagram (a frame of a message our dialect lacks is one) and the datagrams the socket's
receive queue had dropped (`receive_queue`, set by the session; None: unknown).
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.net.receive_queue import ReceiveQueue
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.wire.frame import Frame


class Arrival(NamedTuple):
    """A frame from the target, and what of its source's we had lost when it came."""

    frame: Frame
    undecoded_before: int   # decode errors from its source before its datagram
    undecoded_after: int    # ... and with those in its datagram
    dropped: int | None     # datagrams our socket had dropped (None: the platform cannot tell)



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
        self._most_per_datagram: dict[Address, int] = {}
        self.receive_queue: ReceiveQueue | None = None   # of the socket this node reads from
        self.arrivals: list[Arrival] | None = None       # a list: every kept frame is logged

    def frames_per_datagram(self, source: Address | None) -> int:
        """The most frames (decoded or not) one datagram from `source` held so far; from
        any source if None. At least 1."""
        most = self._most_per_datagram
        seen = most.get(source, 0) if source is not None else max(most.values(), default=0)
        return max(1, seen)

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        target = self.target
        endpoint = self.endpoint
        errors_before = endpoint.decode_error_counts[source]
        frames = endpoint.receive(data, source)
        errors_after = endpoint.decode_error_counts[source]
        held = len(frames) + errors_after - errors_before
        if held > self._most_per_datagram.get(source, 0):
            self._most_per_datagram[source] = held
        arrivals = self.arrivals
        for frame in frames:
            if target is not None and (frame.src_system, frame.src_component) != target:
                continue
            self.last_heard = now
            self.inbox.append((now, frame))
            if arrivals is not None:
                queue = self.receive_queue
                arrivals.append(Arrival(frame, errors_before, errors_after,
                                        queue.drops if queue is not None else None))
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
