"""Serial links: `serial:DEVICE[:BAUD]` through pyserial, and a pseudo-terminal we make.

A flight controller on a bench is a serial port (USB `/dev/ttyACM0`, a telemetry radio at
57600 baud). pyserial (the field's serial library) opens and configures the port (raw,
8N1, the baud rate, input flushed); the link then reads and writes its file descriptor
without blocking, paced at the baud rate (stream_link.py). A port that fails (a USB
device unplugged) is closed and reopened on a bounded back-off, as a GCS does; one that
cannot be opened at the start is the user's mistake (`UsageError`, one line).

`PtyLink` is the other end of a pseudo-terminal pair it creates: `mavconform vehicle
--listen pty:57600` serves the reference vehicle there and prints the device the GCS (or
the suite, `--target serial:/dev/pts/N:57600`) opens. It keeps the pair's terminal end
open itself, in raw mode, so a GCS may come and go without the line failing.
"""

from __future__ import annotations

import fcntl
import os
import termios
import tty
from typing import Any

from ..errors import UsageError
from .stream_link import StreamLink

DEFAULT_BAUD = 57600
RETRY_DELAYS = (0.5, 1.0) + (2.0,) * 28    # s between reopen attempts, then give up


def bytes_per_second(baud: int) -> float:
    """8N1: a start bit, 8 data bits, a stop bit."""
    return baud / 10.0


def paced_queue_limit(baud: int) -> int:
    """A UART's transmit queue holds about half a second of line time (at least 2 KiB):
    what is sent while nobody reads waits there, not for minutes."""
    return max(2048, int(bytes_per_second(baud) * 0.5))


class SerialLink(StreamLink):
    kind = "serial"

    def __init__(self, device: str, baud: int, now: float) -> None:
        label = f"serial:{device}:{baud}"
        super().__init__(label, f"serial:{device}", f"host end of {device}",
                         bytes_per_second=bytes_per_second(baud))
        self.max_queued = paced_queue_limit(baud)
        self.device, self.baud = device, baud
        self._port: Any = None
        self._retry_at: float | None = None
        self._failures = 0
        self.gave_up = False
        try:
            self._open(now)
        except (OSError, ValueError) as exc:
            raise UsageError(f"cannot open serial port {device}: {_reason(exc)}") from None

    def _open(self, now: float) -> None:
        import serial   # pyserial
        port = serial.Serial(port=self.device, baudrate=self.baud, timeout=0, write_timeout=0)
        self._port = port
        self._failures = 0
        self._connected(port.fileno(), now, f"opened at {self.baud} baud")

    def _close_fd(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except OSError:
                pass

    def on_lost(self, now: float) -> None:
        self._failures = 0
        self._retry_at = now + RETRY_DELAYS[0]

    def next_deadline(self) -> float | None:
        own = super().next_deadline()
        if self._retry_at is None:
            return own
        return self._retry_at if own is None else min(own, self._retry_at)

    def poll(self, now: float) -> None:
        if self._retry_at is not None and now >= self._retry_at:
            self._retry_at = None
            try:
                self._open(now)
            except (OSError, ValueError) as exc:
                self._failures += 1
                if self._failures == 1:
                    self.note(now, f"reopen failed: {_reason(exc)}")
                if self._failures >= len(RETRY_DELAYS):
                    self.gave_up = True
                    self.note(now, f"gave up after {self._failures} attempts")
                else:
                    self._retry_at = now + RETRY_DELAYS[self._failures]
        super().poll(now)

    def close(self) -> None:
        self._retry_at = None
        super().close()


class PtyLink(StreamLink):
    """The controlling end of a new pseudo-terminal pair; `device` is the end to open."""

    kind = "pty"

    def __init__(self, baud: int, now: float) -> None:
        master, slave = os.openpty()
        tty.setraw(slave)
        attrs = termios.tcgetattr(slave)
        speed = getattr(termios, f"B{baud}", None)
        if speed is not None:   # cosmetic on a pty (it moves bytes at memory speed): we pace
            attrs[4] = attrs[5] = speed
            termios.tcsetattr(slave, termios.TCSANOW, attrs)
        flags = fcntl.fcntl(master, fcntl.F_GETFL)
        fcntl.fcntl(master, fcntl.F_SETFL, flags | os.O_NONBLOCK)
        self.device = os.ttyname(slave)
        self.baud = baud
        super().__init__(f"serial:{self.device}:{baud}", f"serial:{self.device}", "pty",
                         bytes_per_second=bytes_per_second(baud))
        self.max_queued = paced_queue_limit(baud)
        self._slave = slave
        self._connected(master, now, f"pseudo-terminal {self.device} at {baud} baud")

    def close(self) -> None:
        super().close()
        if self._slave is not None:
            os.close(self._slave)
            self._slave = None


def _reason(exc: BaseException) -> str:
    text = getattr(exc, "strerror", None) or str(exc)
    return text.split(": ", 1)[-1] if text.startswith("could not open port") else text
