"""`StreamLink`: one byte-stream connection (TCP, a serial line) as the real-time driver runs it.

The driver (udp.py) owns the loop; a link says what it wants to wait on (`wanted`), takes
readiness (`ready`), queues bytes (`send`) and writes what may go (`flush`). Everything is
non-blocking and every wait is the driver's bounded select. What subclasses add is how
the connection is made and remade (tcp_link.py, serial_link.py).

A link that is down is not an error: it is what a target that went away does. Bytes sent
while it is down are dropped and counted, as a UART with nothing attached drops them,
and `history` keeps each connect and loss, bounded, for the report. A serial line is paced
at its baud rate (10 bits a byte, 8N1), as a UART sends: a pseudo-terminal would otherwise
move 57600-baud traffic at memory speed and hide what a slow link does to the protocol.
"""

from __future__ import annotations

import os
from typing import Any

READ_CHUNK = 65536
MAX_QUEUED = 256 * 1024   # bytes waiting to be written; beyond, whole frames are dropped
PACE_SLICE = 0.005        # s of line time written at once on a paced link
MAX_HISTORY = 200         # connection events kept for the report


class StreamLink:
    kind = "stream"

    def __init__(self, uri: str, peer: str, local: str, *, bytes_per_second: float | None = None) -> None:
        self.uri = uri                      # as the user wrote it, normalised
        self.peer = peer                    # the address the node sends to and hears from
        self.local = local                  # our end, for captures and link statistics
        self.bytes_per_second = bytes_per_second   # None: not limited here (a network link)
        self.max_queued = MAX_QUEUED
        self.generation = 0                 # +1 on each new connection: the framer starts over
        self.history: list[tuple[float, str]] = []
        self.dropped_down = 0               # frames sent while the link was down
        self.dropped_full = 0               # frames dropped because the write queue was full
        self.written = 0
        self.read = 0
        self._fd: int | None = None         # the connected stream, when up
        self._out = bytearray()
        self._line_free_at = 0.0            # paced: when the line has sent what was written
        self._blocked = False               # the kernel took no more: wait until it is writable

    # --- state ----------------------------------------------------------------------------
    @property
    def up(self) -> bool:
        return self._fd is not None

    def note(self, now: float, what: str) -> None:
        if len(self.history) < MAX_HISTORY:
            self.history.append((now, what))
        elif len(self.history) == MAX_HISTORY:
            self.history.append((now, "(later connection events not kept)"))

    def _connected(self, fd: int, now: float, what: str) -> None:
        self._fd = fd
        self.generation += 1
        self._out.clear()
        self._blocked = False
        self._line_free_at = now
        self.note(now, what)

    def _lost(self, now: float, why: str) -> None:
        """The stream ended (peer closed, reset, device gone): drop it and what was queued."""
        if self._fd is not None:
            self._close_fd()
            self._fd = None
        self._out.clear()
        self.note(now, why)

    def _close_fd(self) -> None:
        assert self._fd is not None
        try:
            os.close(self._fd)
        except OSError:
            pass

    # --- the driver's side ----------------------------------------------------------------
    def wanted(self, now: float) -> list[tuple[Any, bool, bool]]:
        """(file object or fd, read?, write?) to wait on now. A paced link waits to write
        only once its line is free (until then `next_deadline` brings the driver back)."""
        if self._fd is None:
            return []
        paced = self.bytes_per_second is not None and now < self._line_free_at
        return [(self._fd, True, bool(self._out) and (self._blocked or not paced))]

    def ready(self, fileobj: Any, readable: bool, writable: bool, now: float) -> bytes:
        """`fileobj` is ready: read what is there (returned), write what may go."""
        data = b""
        if readable and self._fd is not None and fileobj == self._fd:
            data = self._read(now)
        if writable and self._fd is not None:
            self.flush(now)
        return data

    @property
    def queued(self) -> int:
        """Bytes waiting to be written (a writer that must not overrun the queue waits on it)."""
        return len(self._out)

    def send(self, data: bytes, now: float) -> bool:
        """Queue one frame; False (dropped, counted) if the link is down or its queue full."""
        if self._fd is None:
            self.dropped_down += 1
            return False
        if len(self._out) + len(data) > self.max_queued:
            self.dropped_full += 1
            return False
        self._out += data
        return True

    def flush(self, now: float) -> None:
        """Write what the kernel takes and, on a paced link, what the line has sent by now."""
        if not self._out or self._fd is None:
            return
        n = len(self._out)
        rate = self.bytes_per_second
        if rate is not None:
            if now < self._line_free_at:
                return
            n = min(n, max(1, int(rate * PACE_SLICE)))
        try:
            sent = os.write(self._fd, self._out[:n])
        except (BlockingIOError, InterruptedError):
            self._blocked = True   # no deadline until it is writable: no busy loop on a full line
            return
        except OSError as exc:
            self._lost(now, f"write failed: {exc.strerror or exc}")
            self.on_lost(now)
            return
        self._blocked = False
        del self._out[:sent]
        self.written += sent
        if rate is not None:
            self._line_free_at = max(now, self._line_free_at) + sent / rate

    def next_deadline(self) -> float | None:
        """When the link wants the driver back: the paced line is free again, or a retry."""
        if self._out and self._fd is not None and self.bytes_per_second is not None and not self._blocked:
            return self._line_free_at
        return None

    def poll(self, now: float) -> None:
        """A deadline passed: subclasses retry here; the paced writer writes."""
        self.flush(now)

    def close(self) -> None:
        if self._fd is not None:
            self._close_fd()
            self._fd = None

    def describe(self) -> dict[str, Any]:
        """For the report: what the link is, how fast, and what happened to it."""
        return {"uri": self.uri, "kind": self.kind, "bytes_per_second": self.bytes_per_second,
                "bytes_written": self.written, "bytes_read": self.read,
                "frames_dropped_link_down": self.dropped_down, "frames_dropped_queue_full": self.dropped_full,
                "connections": self.generation,
                "history": [{"t": round(t, 3), "event": what} for t, what in self.history]}

    # --- internals ------------------------------------------------------------------------
    def _read(self, now: float) -> bytes:
        try:
            data = os.read(self._fd, READ_CHUNK)   # type: ignore[arg-type]
        except (BlockingIOError, InterruptedError):
            return b""
        except OSError as exc:
            self._lost(now, f"read failed: {exc.strerror or exc}")
            self.on_lost(now)
            return b""
        if not data:
            self._lost(now, "closed by the peer")
            self.on_lost(now)
            return b""
        self.read += len(data)
        return data

    def on_lost(self, now: float) -> None:
        """Subclasses schedule a reconnect (or listen again) here."""

