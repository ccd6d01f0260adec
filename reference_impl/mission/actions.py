"""What the sans-IO engines ask their node to do: send a message, report a result.

Engines return lists of these from `handle()` and `poll()`; they never touch a socket.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

Peer = tuple[int, int]  # (system id, component id)


@dataclass(frozen=True, slots=True)
class Send:
    """Send `msg` to `to` (a peer), or broadcast it to every known peer when `to` is None."""

    msg: Any
    to: Peer | None = None


@dataclass(frozen=True, slots=True)
class Finished:
    """A client operation ended; `result` is its one and only result."""

    result: Any
