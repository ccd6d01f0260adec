"""A UDP socket's receive queue as the kernel keeps it: how big it may grow, what it dropped.

A busy target fills a default-sized queue fast (PX4's fixed-wing SIH streams ~360 frames/s;
Linux's default 208 KiB holds a few hundred small datagrams, each charged ~1 KiB), and once
it is full the kernel drops what arrives before we read it. The packet sequence of what we
did read then has gaps that are ours, not the target's. So every socket asks for a generous
buffer (`RECEIVE_BUFFER`; the kernel caps it at net.core.rmem_max and `granted` says what
it gave), and, on Linux, for the queue's drop counter (SO_RXQ_OVFL: each datagram read
carries, as ancillary data, how many the socket had dropped when it was queued, a
cumulative uint32, absent while still 0). Drops are therefore learnt with the next datagram
read after them, which is exactly what a gap between two frames we read needs.

Where the platform cannot tell (not Linux, or the option refused) `drops` is None:
unknown, never a pretended 0.
"""

from __future__ import annotations

import socket
import struct
import sys

RECEIVE_BUFFER = 4 * 1024 * 1024   # bytes asked for; Linux grants up to twice rmem_max
SO_RXQ_OVFL = getattr(socket, "SO_RXQ_OVFL", 40) if sys.platform.startswith("linux") else None
ANCILLARY_SPACE = socket.CMSG_SPACE(4) if hasattr(socket, "CMSG_SPACE") else 0
_COUNTER = struct.Struct("=I")
_WRAP = 1 << 32


class ReceiveQueue:
    """One socket's queue: the buffer the kernel granted and the datagrams it dropped
    (None: the platform does not say)."""

    __slots__ = ("granted", "drops", "_raw")

    def __init__(self, granted: int | None, counted: bool) -> None:
        self.granted = granted
        self.drops: int | None = 0 if counted else None
        self._raw = 0

    @property
    def counted(self) -> bool:
        return self.drops is not None

    def note(self, ancillary: list[tuple[int, int, bytes]]) -> None:
        """Take the drop counter from a datagram's ancillary data (recvmsg's third item)."""
        for level, kind, data in ancillary:
            if level == socket.SOL_SOCKET and kind == SO_RXQ_OVFL and len(data) >= 4:
                raw = _COUNTER.unpack_from(data)[0]
                self.drops += (raw - self._raw) % _WRAP   # the counter wraps at 2**32
                self._raw = raw


def open_queue(sock: socket.socket, wanted: int | None = None) -> ReceiveQueue:
    """Ask for a `wanted`-byte receive buffer (default `RECEIVE_BUFFER`) and the drop counter
    on `sock`; say what the kernel granted. A refusal is not an error: the socket works as it
    is, and says so."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, RECEIVE_BUFFER if wanted is None else wanted)
    except OSError:
        pass   # the system's default stays; `granted` reads it
    try:
        granted: int | None = sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
    except OSError:
        granted = None
    counted = False
    if SO_RXQ_OVFL is not None and ANCILLARY_SPACE:
        try:
            sock.setsockopt(socket.SOL_SOCKET, SO_RXQ_OVFL, 1)
            counted = True
        except OSError:
            pass
    return ReceiveQueue(granted, counted)


def resize(sock: socket.socket, queue: ReceiveQueue, wanted: int) -> int | None:
    """Ask for a `wanted`-byte buffer on an open socket (tests make it tiny); the granted size."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, wanted)
        queue.granted = sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
    except OSError:
        pass
    return queue.granted


def total_drops(queues: list[ReceiveQueue]) -> int | None:
    """Datagrams the queues dropped together; None if any of them cannot tell."""
    total = 0
    for queue in queues:
        if queue.drops is None:
            return None
        total += queue.drops
    return total
