"""The evidence of one clause: what the tester sent, what the target sent back, and notes.

It is what the HTML report draws as a sequence diagram. Only mission traffic and the
messages mission clauses look at are kept: a SITL's telemetry would bury the exchange.
It also holds which of its events decided the clause (`decide`), so the report marks the
message the check judged instead of guessing it from the verdict's text.

A message the target streams at its own rate (MISSION_CURRENT, about 1 Hz) lands in an
exchange when its period says, not when the clause asks: one run catches one more inside a
window than the next. Such an event is marked `ambient` until a check consumes it or it
decides the clause; the run document keeps the ambient ones apart, with the volatile values,
so two runs of the same target still compare equal (conformance/document.py).
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.net.capture import json_safe
from mavconform.reports.run_document import AMBIENT   # the key marking a streamed event nothing used

MAX_EVENTS = 400
KEPT_NAMES = frozenset({"STATUSTEXT", "COMMAND_ACK", "COMMAND_LONG"})
STREAMED = frozenset({"MISSION_CURRENT"})   # kept messages a target sends on its own clock


def relevant(name: str) -> bool:
    return name.startswith("MISSION_") or name in KEPT_NAMES


def message_fields(msg: Any) -> dict[str, Any]:
    return {name: json_safe(getattr(msg, name)) for name in msg.get_fieldnames()}


def used(event: dict[str, Any] | None) -> None:
    """A check consumed the event's frame, or it decided the clause: it is evidence, not
    ambient."""
    if event is not None:
        event.pop(AMBIENT, None)


class Exchange:
    def __init__(self, start: float) -> None:
        self.start = start
        self.events: list[dict[str, Any]] = []
        self.omitted = 0
        # The deciding event itself, not its index: a shared observation copies its events
        # (the same objects) into a later clause's exchange, where they have other indices.
        self._decided: dict[str, Any] | None = None

    def add(self, now: float, direction: str, peer: str, name: str, fields: dict[str, Any]) -> int | None:
        """Append an event; its index, or None if the exchange is full and it was not kept.
        A streamed message received is ambient until it is `used`."""
        if len(self.events) >= MAX_EVENTS:
            self.omitted += 1
            return None
        event = {"t": round(now - self.start, 6), "dir": direction, "peer": peer, "msg": name, "fields": fields}
        if direction == "rx" and name in STREAMED:
            event[AMBIENT] = True
        self.events.append(event)
        return len(self.events) - 1

    def note(self, now: float, peer: str, text: str) -> int | None:
        return self.add(now, "note", peer, text, {})

    def decide(self, event: dict[str, Any] | int | None) -> None:
        """Make `event` (an event, or its index here) the one that decided the clause; None
        forgets the choice. The last call before the verdict wins."""
        if isinstance(event, int):
            event = self.events[event] if 0 <= event < len(self.events) else None
        used(event)
        self._decided = event

    @property
    def decided_by(self) -> int | None:
        """The index of the deciding event, or None. The last copy if it occurs twice (a
        shared observation used twice in one clause)."""
        if self._decided is None:
            return None
        for index in range(len(self.events) - 1, -1, -1):
            if self.events[index] is self._decided:
                return index
        return None

    def finish(self, now: float) -> list[dict[str, Any]]:
        if self.omitted:
            self.events.append({"t": round(now - self.start, 6), "dir": "note", "peer": "tester",
                                "msg": f"... {self.omitted} more events not kept", "fields": {}})
            self.omitted = 0
        return self.events
