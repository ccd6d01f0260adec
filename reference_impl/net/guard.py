"""GuardedNode: a node whose exceptions stop it instead of the whole driver.

An in-process target that raises is a crashed target: from outside it falls silent, as a
crashed autopilot would, and the exception is kept for the report. Without the guard one
broken node would unwind the driver's loop and take the tester (and the run) down with it.
"""

from __future__ import annotations

import traceback

from .node import Address, DatagramNode


class GuardedNode:
    def __init__(self, node: DatagramNode) -> None:
        self.node = node
        self.crash: str | None = None    # "TypeError: ... (file.py:123)" once it has raised
        self.exception: BaseException | None = None   # the exception itself, traceback included

    def _died(self, exc: BaseException) -> None:
        self.exception = exc
        where = traceback.extract_tb(exc.__traceback__)[-1]
        self.crash = f"{type(exc).__name__}: {exc} ({where.filename}:{where.lineno})"

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        if self.crash is None:
            try:
                self.node.datagram_received(data, source, now)
            except Exception as exc:
                self._died(exc)

    def poll(self, now: float) -> None:
        if self.crash is None:
            try:
                self.node.poll(now)
            except Exception as exc:
                self._died(exc)

    def next_deadline(self) -> float | None:
        return None if self.crash is not None else self.node.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out = self.node.take_outgoing()
        return [] if self.crash is not None else out
