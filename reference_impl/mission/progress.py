"""Which mission item is current, and telling everyone when that changes.

Seed 000, "Monitor Mission Progress": the vehicle must broadcast MISSION_ITEM_REACHED when
an item is reached and MISSION_CURRENT when the current item changes; upstream asks for
MISSION_CURRENT to be streamed at about 1 Hz as well. The flight simulation moves the
vehicle; this object only keeps the numbers and emits the messages.
"""

from __future__ import annotations

from . import messages as m
from .actions import Send
from .constants import MissionState
from .items import MissionType
from .store import MissionStore

MODE_UNKNOWN, MODE_MISSION, MODE_SUSPENDED = 0, 1, 2


class MissionProgress:
    def __init__(self, store: MissionStore, period: float) -> None:
        self.store = store
        self.period = period
        self.seq = 0
        self.running = False
        self.complete = False
        self._next_stream: float | None = 0.0

    @property
    def state(self) -> MissionState:
        if self.store.count(MissionType.MISSION) == 0:
            return MissionState.NO_MISSION
        if self.complete:
            return MissionState.COMPLETE
        if self.running:
            return MissionState.ACTIVE
        return MissionState.NOT_STARTED if self.seq == 0 else MissionState.PAUSED

    def current_message(self):
        store = self.store
        count = store.count(MissionType.MISSION)
        total = count if count else 0xFFFF  # upstream: UINT16_MAX if no mission is present
        ids = (store.opaque_id(MissionType.MISSION), store.opaque_id(MissionType.FENCE),
               store.opaque_id(MissionType.RALLY))
        mode = MODE_MISSION if self.running else MODE_SUSPENDED
        return m.current_message(self.seq, total, int(self.state), mode, ids)

    def announce(self, now: float) -> list[Send]:
        """Broadcast MISSION_CURRENT now and restart the stream period."""
        self._next_stream = now + self.period
        return [Send(self.current_message())]

    def set_current(self, seq: int, now: float) -> list[Send]:
        self.seq = seq
        self.complete = False
        return self.announce(now)

    def plan_replaced(self, now: float) -> list[Send]:
        """A new flight plan was committed (or cleared): start again from item 0."""
        self.seq, self.running, self.complete = 0, False, False
        return self.announce(now)

    def reached(self, seq: int, now: float) -> list[Send]:
        """The vehicle reached item `seq`: say so, then move on to the next item."""
        out = [Send(m.item_reached_message(seq))]
        if seq + 1 < self.store.count(MissionType.MISSION):
            self.seq = seq + 1
        else:
            self.running, self.complete = False, True
        return out + self.announce(now)

    def next_deadline(self) -> float | None:
        return self._next_stream

    def poll(self, now: float) -> list[Send]:
        if self._next_stream is not None and now >= self._next_stream:
            return self.announce(now)
        return []
