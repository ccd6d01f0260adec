"""The evidence of one clause: what the tester sent, what the target sent back, and notes.

It is what the HTML report draws as a sequence diagram. Only mission traffic and the
messages mission clauses look at are kept: a SITL's telemetry would bury the exchange.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.net.capture import json_safe

MAX_EVENTS = 400
KEPT_NAMES = frozenset({"STATUSTEXT", "COMMAND_ACK", "COMMAND_LONG"})


def relevant(name: str) -> bool:
    return name.startswith("MISSION_") or name in KEPT_NAMES


def message_fields(msg: Any) -> dict[str, Any]:
    return {name: json_safe(getattr(msg, name)) for name in msg.get_fieldnames()}


class Exchange:
    def __init__(self, start: float) -> None:
        self.start = start
        self.events: list[dict[str, Any]] = []
        self.omitted = 0

    def add(self, now: float, direction: str, peer: str, name: str, fields: dict[str, Any]) -> None:
        if len(self.events) >= MAX_EVENTS:
            self.omitted += 1
            return
        self.events.append({"t": round(now - self.start, 6), "dir": direction, "peer": peer,
                            "msg": name, "fields": fields})

    def note(self, now: float, peer: str, text: str) -> None:
        self.add(now, "note", peer, text, {})

    def finish(self, now: float) -> list[dict[str, Any]]:
        if self.omitted:
            self.events.append({"t": round(now - self.start, 6), "dir": "note", "peer": "tester",
                                "msg": f"... {self.omitted} more events not kept", "fields": {}})
            self.omitted = 0
        return self.events
