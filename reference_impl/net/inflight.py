"""InFlight: tells a capture which reports are of a datagram it has already written.

A driver reports a datagram up to twice: `tx` when a node sends it, then `rx` when it
arrives or `drop` when a fault eats it. With both ends on one driver (a built-in target over
UDP loopback, every SimNetwork run) `tx` and `rx` are the same frame, and writing both put
every frame in a capture twice. So a capture writes the `tx` and remembers the datagram here,
per direction, until its `rx` or `drop` settles it. Matching is by bytes, so a copy the link
made (a duplicate, a corrupted copy) settles nothing and is written as what it is: bytes the
receiver got that the sender never sent. A datagram to a peer outside the driver never
settles, so each direction keeps only the newest `limit`.
"""

from __future__ import annotations

from collections import deque

from .node import Address

MAX_IN_FLIGHT = 4096  # per direction: far more than any driver has undelivered at once


class InFlight:
    """Datagrams written as sent whose arrival or loss has not been reported yet."""

    def __init__(self, limit: int = MAX_IN_FLIGHT) -> None:
        if limit < 1:
            raise ValueError(f"InFlight needs limit >= 1, got {limit}")
        self.limit = limit
        self._queues: dict[tuple[Address, Address], deque[bytes]] = {}

    def sent(self, src: Address, dst: Address, data: bytes) -> None:
        queue = self._queues.get((src, dst))
        if queue is None:
            queue = self._queues[(src, dst)] = deque(maxlen=self.limit)
        queue.append(data)

    def settle(self, src: Address, dst: Address, data: bytes) -> bool:
        """True if `data` was sent src -> dst and not settled yet; it is settled now."""
        queue = self._queues.get((src, dst))
        if not queue:
            return False
        try:
            queue.remove(data)  # the oldest equal copy: datagrams mostly arrive in order
        except ValueError:
            return False
        return True

    def __len__(self) -> int:
        return sum(len(q) for q in self._queues.values())
