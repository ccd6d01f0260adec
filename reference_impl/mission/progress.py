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
REACHED_REPEAT_PERIOD = 1.0   # s between repeats of MISSION_ITEM_REACHED (item_reached_repeats)
# s a reached report waits in its slot (reached_one_slot): the next time the autopilot's link
# sends it, about one of its loops later. An item done within it of the one before (a DO
# command right after a waypoint, 0.1 s in the flight model) takes the slot over, and the
# MISSION_CURRENT the flight owes goes out with it: both autopilots send the two from one
# snapshot of mission progress (PX4 mavlink_mission.cpp check_active_mission; ArduPilot's
# deferred MSG_CURRENT_WAYPOINT and MSG_MISSION_ITEM_REACHED), so an intermediate current
# item is not announced either. The report goes first, so the last item's is out before the
# MISSION_CURRENT that says the mission is complete (PX4 sends that one with its 1 Hz stream).
REACHED_SLOT_DELAY = 0.25


class MissionProgress:
    """`home_at_seq0`: item 0 is the vehicle's home, so the mission starts at 1 and
    MISSION_CURRENT.total is count - 1 (VARIANTS.md A1). `report_ids`: MISSION_CURRENT
    carries the plan ids (else zero: A19). `reached_repeats`: MISSION_ITEM_REACHED is sent
    this many times, 1 s apart (P13). `reached_one_slot`: the report is not sent at once but
    kept in one slot until REACHED_SLOT_DELAY later, and a later item reached by then
    replaces it (PX4 and ArduPilot keep one pending reached index per link)."""

    def __init__(self, store: MissionStore, period: float | None, *, home_at_seq0: bool = False,
                 report_ids: bool = True, reached_repeats: int = 1, reached_one_slot: bool = False,
                 unreported: frozenset[int] = frozenset()) -> None:
        self.store = store
        self.period = period
        self.home_at_seq0 = home_at_seq0
        self.report_ids = report_ids
        self.reached_repeats = reached_repeats
        self.reached_one_slot = reached_one_slot
        self.unreported = unreported
        self.seq = 0
        self.running = False
        self.complete = False
        self._next_stream: float | None = 0.0 if period is not None else None   # None: never sent
        self._repeat: tuple[int, int, float] | None = None   # (seq, sends left, next at)
        self._slot: tuple[int, float] | None = None            # (seq, send at): reached_one_slot
        self._announce_due = False                              # a MISSION_CURRENT to send with the slot

    @property
    def first_seq(self) -> int:
        """Where a flight of the stored plan starts."""
        return 1 if self.home_at_seq0 and self.store.count(MissionType.MISSION) > 1 else 0

    @property
    def state(self) -> MissionState:
        if self.store.count(MissionType.MISSION) == 0:
            return MissionState.NO_MISSION
        if self.complete:
            return MissionState.COMPLETE
        if self.running:
            return MissionState.ACTIVE
        return MissionState.NOT_STARTED if self.seq == self.first_seq else MissionState.PAUSED

    def current_message(self):
        store = self.store
        count = store.count(MissionType.MISSION)
        total = count if count else 0xFFFF  # upstream: UINT16_MAX if no mission is present
        if count and self.home_at_seq0:
            total = count - 1
        ids = (store.opaque_id(MissionType.MISSION), store.opaque_id(MissionType.FENCE),
               store.opaque_id(MissionType.RALLY)) if self.report_ids else (0, 0, 0)
        mode = MODE_MISSION if self.running else MODE_SUSPENDED
        return m.current_message(self.seq, total, int(self.state), mode, ids)

    def announce(self, now: float) -> list[Send]:
        """Broadcast MISSION_CURRENT now and restart the stream period (a vehicle without
        MISSION_CURRENT, period None: nothing)."""
        if self.period is None:
            return []
        self._next_stream = now + self.period
        return [Send(self.current_message())]

    def set_current(self, seq: int, now: float) -> list[Send]:
        self.seq = seq
        self.complete = False
        self._announce_due = False
        return self.announce(now)

    def plan_replaced(self, now: float) -> list[Send]:
        """A new flight plan was committed (or cleared): start again from item 0."""
        self.seq, self.running, self.complete = self.first_seq, False, False
        self._repeat = self._slot = None
        self._announce_due = False
        return self.announce(now)

    def reached(self, seq: int, now: float, *, ends: bool = False, command: int | None = None) -> list[Send]:
        """The vehicle reached item `seq` (its `command`): say so, then move on to the next
        item (`ends`: the mission is over at this item, as after a landing, whatever follows
        it). A command in `unreported` moves on without a report."""
        if seq + 1 < self.store.count(MissionType.MISSION) and not ends:
            self.seq = seq + 1
        else:
            self.running, self.complete = False, True
        if command in self.unreported:
            if self.reached_one_slot and self._slot is not None:
                self._announce_due = True
                return []
            return self.announce(now)
        if self.reached_one_slot:   # report and announcement wait for the slot's send
            self._slot = (seq, self._slot[1] if self._slot is not None else now + REACHED_SLOT_DELAY)
            self._announce_due = True
            return []
        return self._report(seq, now) + self.announce(now)

    def _report(self, seq: int, now: float) -> list[Send]:
        """MISSION_ITEM_REACHED for `seq` now, and its repeats from now on."""
        if self.reached_repeats > 1:
            self._repeat = (seq, self.reached_repeats - 1, now + REACHED_REPEAT_PERIOD)
        return [Send(m.item_reached_message(seq))]

    def next_deadline(self) -> float | None:
        # asked after every frame the vehicle handles: plain comparisons, no list or generator
        best = self._next_stream
        if self._repeat is not None and (best is None or self._repeat[2] < best):
            best = self._repeat[2]
        if self._slot is not None and (best is None or self._slot[1] < best):
            best = self._slot[1]
        return best

    def poll(self, now: float) -> list[Send]:
        out: list[Send] = []
        if self._slot is not None and now >= self._slot[1]:
            seq, self._slot = self._slot[0], None
            out += self._report(seq, now)
            if self._announce_due:
                self._announce_due = False
                out += self.announce(now)
        elif self._repeat is not None and now >= self._repeat[2]:
            seq, left, _ = self._repeat
            out.append(Send(m.item_reached_message(seq)))
            self._repeat = (seq, left - 1, now + REACHED_REPEAT_PERIOD) if left > 1 else None
        if self._next_stream is not None and now >= self._next_stream:
            out += self.announce(now)
        return out
