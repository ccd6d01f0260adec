"""Time on a slow link: what a serial line's bandwidth adds to each reply the suite waits for.

At 57600 baud a line moves 5760 bytes a second: a request and its answer (up to 280 bytes
each, a MAVLink 2 frame's most) take up to 0.1 s on the wire, and a vehicle's telemetry
queued ahead of the answer (`BACKLOG` bytes allowed for) more. The suite's reply waits are
the spec's (1500 ms), for a link whose transfer time is nothing; on a paced link each one
gets this allowance on top, so no clause passes or fails for the line's speed alone. The
bandwidth comes from the baud rate (8N1: ten bits a byte). TCP and UDP links are network
links: nothing is added, and the report says so. The windows a clause sits out (the
silences it requires, the retries it counts) are the protocol's and are not stretched:
the link delays what is in them alike.
"""

from __future__ import annotations

from typing import Any

MAX_FRAME = 280    # bytes: a signed MAVLink 2 frame with a 255-byte payload
BACKLOG = 1024     # bytes of the vehicle's other traffic allowed for ahead of an answer


def reply_allowance(bytes_per_second: float | None) -> float:
    """Seconds a reply may take beyond the protocol's own timeout on this link."""
    if bytes_per_second is None:
        return 0.0
    return round((2 * MAX_FRAME + BACKLOG) / bytes_per_second, 3)


def stream_events(stream: Any, start: float) -> dict[str, Any] | None:
    """The run document's volatile `link`: what happened to a stream link during the run
    (connections, losses, bytes, frames dropped while it was down), times from `start`;
    None for UDP or an in-process link."""
    if stream is None:
        return None
    facts = stream.describe()
    for key in ("uri", "kind", "bytes_per_second"):   # run.link holds those
        facts.pop(key)
    facts["history"] = [{**h, "t": round(h["t"] - start, 3)} for h in facts["history"]]
    return facts


def link_facts(kind: str, stream: Any) -> dict[str, Any]:
    """The run document's `run.link`: what the link is and the timing the suite used.
    `stream`: the target's StreamLink, or None (UDP, or an in-process target)."""
    rate = stream.bytes_per_second if stream is not None else None
    return {"kind": kind, "bytes_per_second": rate, "reply_allowance_s": reply_allowance(rate)}
