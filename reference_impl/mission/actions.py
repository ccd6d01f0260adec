"""What the sans-IO engines ask their node to do: send a message, report a result.

Engines return lists of these from `handle()` and `poll()`; they never touch a socket.
"""

from __future__ import annotations

from typing import Any, NamedTuple

Peer = tuple[int, int]  # (system id, component id)


class Send(NamedTuple):
    """Send `msg` to `to` (a peer), or broadcast it to every known peer when `to` is None.

    A NamedTuple: engines make one per message, and it is several times cheaper to build
    than a frozen dataclass."""

    msg: Any
    to: Peer | None = None


class Finished(NamedTuple):
    """A client operation ended; `result` is its one and only result."""

    result: Any
