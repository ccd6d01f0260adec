"""TCP links: `tcp:HOST:PORT` (we connect, and reconnect) and `tcpin:[HOST:]PORT` (we listen).

ArduPilot SITL serves its first serial port on TCP 5760 and INAV's SITL speaks MAVLink
only over TCP, so a target on TCP is a common case. A connection refused or dropped is
what a target that went away does: the client retries on a bounded back-off
(`RETRY_DELAYS`, then gives up, said in its history) and never blocks; the listener
takes one peer at a time (a second is closed at once and counted) and listens again when
its peer leaves. A listener that cannot bind (port in use) is the user's mistake.
"""

from __future__ import annotations

import errno
import os
import socket
from typing import Any

from ..errors import UsageError
from .stream_link import StreamLink

RETRY_DELAYS = (0.25, 0.5, 1.0) + (2.0,) * 27   # s between connection attempts, then give up


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def _nodelay(sock: socket.socket) -> None:
    try:   # a MAVLink frame is a message: send it now, not when Nagle thinks best
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    except OSError:
        pass


def _bracketed(host: str) -> str:
    return f"[{host}]" if ":" in host else host


class TcpClientLink(StreamLink):
    """We connect to a listening target; every loss starts the retries over."""

    kind = "tcp"

    def __init__(self, host: str, port: int, now: float) -> None:
        where = f"{_bracketed(host)}:{port}"
        super().__init__(f"tcp:{where}", f"tcp:{where}", f"tcp client of {where}")
        self.host, self.port = host, port
        self._connecting: socket.socket | None = None
        self._retry_at: float | None = None
        self._failures = 0
        self.gave_up = False
        self._attempt(now)

    def wanted(self, now: float) -> list[tuple[Any, bool, bool]]:
        if self._connecting is not None:
            return [(self._connecting, False, True)]
        return super().wanted(now)

    def ready(self, fileobj: Any, readable: bool, writable: bool, now: float) -> bytes:
        if self._connecting is not None and fileobj is self._connecting:
            self._finish_connect(now)
            return b""
        return super().ready(fileobj, readable, writable, now)

    def next_deadline(self) -> float | None:
        own = super().next_deadline()
        if self._retry_at is None:
            return own
        return self._retry_at if own is None else min(own, self._retry_at)

    def poll(self, now: float) -> None:
        if self._retry_at is not None and now >= self._retry_at:
            self._retry_at = None
            self._attempt(now)
        super().poll(now)

    def on_lost(self, now: float) -> None:
        self._failures = 0
        self._schedule_retry(now)

    def close(self) -> None:
        self._retry_at = None
        if self._connecting is not None:
            self._connecting.close()
            self._connecting = None
        super().close()

    def _attempt(self, now: float) -> None:
        sock = socket.socket(_family(self.host), socket.SOCK_STREAM)
        sock.setblocking(False)
        code = sock.connect_ex((self.host, self.port))
        if code in (0, errno.EINPROGRESS, errno.EWOULDBLOCK):
            self._connecting = sock
            if code == 0:
                self._finish_connect(now)
            return
        sock.close()
        self._failed(now, os.strerror(code))

    def _finish_connect(self, now: float) -> None:
        sock, self._connecting = self._connecting, None
        assert sock is not None
        code = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
        if code:
            sock.close()
            self._failed(now, os.strerror(code))
            return
        _nodelay(sock)
        self._failures = 0
        self._connected(sock.detach(), now, "connected")

    def _failed(self, now: float, why: str) -> None:
        self._failures += 1
        if self._failures == 1 or self._failures == len(RETRY_DELAYS):
            self.note(now, f"connection failed: {why}")
        self._schedule_retry(now)

    def _schedule_retry(self, now: float) -> None:
        if self._failures >= len(RETRY_DELAYS):
            self.gave_up = True
            self.note(now, f"gave up after {self._failures} attempts")
            return
        self._retry_at = now + RETRY_DELAYS[self._failures]


class TcpServerLink(StreamLink):
    """We listen; one peer at a time."""

    kind = "tcpin"

    def __init__(self, host: str, port: int, now: float) -> None:
        sock = socket.socket(_family(host), socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, port))
            sock.listen(4)
        except (OSError, OverflowError) as exc:
            sock.close()
            reason = getattr(exc, "strerror", None) or str(exc)
            raise UsageError(f"cannot listen on TCP {_bracketed(host)}:{port}: {reason}") from None
        sock.setblocking(False)
        self.address = sock.getsockname()[:2]
        where = f"{_bracketed(self.address[0])}:{self.address[1]}"
        super().__init__(f"tcpin:{where}", f"tcp peer of {where}", f"tcpin:{where}")
        self._listener = sock
        self.refused_peers = 0
        self.note(now, "listening")

    def wanted(self, now: float) -> list[tuple[Any, bool, bool]]:
        return [(self._listener, True, False)] + super().wanted(now)

    def ready(self, fileobj: Any, readable: bool, writable: bool, now: float) -> bytes:
        if fileobj is self._listener:
            self._accept(now)
            return b""
        return super().ready(fileobj, readable, writable, now)

    def close(self) -> None:
        self._listener.close()
        super().close()

    def describe(self) -> dict[str, Any]:
        return {**super().describe(), "refused_peers": self.refused_peers}

    def _accept(self, now: float) -> None:
        for _ in range(16):   # bounded: a burst of connections cannot hold the loop
            try:
                conn, addr = self._listener.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            if self.up:
                conn.close()
                self.refused_peers += 1
                self.note(now, f"refused a second peer from {addr[0]}:{addr[1]}")
                continue
            conn.setblocking(False)
            _nodelay(conn)
            self._connected(conn.detach(), now, f"peer connected from {addr[0]}:{addr[1]}")

