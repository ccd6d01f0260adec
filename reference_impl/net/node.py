"""The contract between a runnable node and whatever moves its datagrams.

A node is sans-IO at the datagram level: drivers (`SimNetwork` in virtual time, the UDP
driver in real time) hand it datagrams and the time, ask when it next wants to be woken,
and take what it wants sent. The same node object runs unchanged under either driver.
Addresses are opaque and hashable: names under SimNetwork, (host, port) under UDP.
"""

from __future__ import annotations

from typing import Hashable, Protocol

Address = Hashable


class DatagramNode(Protocol):
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        """A datagram arrived from `source` at time `now`."""

    def poll(self, now: float) -> None:
        """Time has reached `now`: run timers that are due."""

    def next_deadline(self) -> float | None:
        """The earliest time the node wants `poll` called, or None for never."""

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        """Datagrams queued since the last call, each with its destination; clears the queue."""
