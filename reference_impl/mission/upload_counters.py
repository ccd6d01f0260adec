"""INAV 9.1's upload state: two counters that outlive the upload they counted.

INAV keeps no upload state but `incomingMissionWpCount` and `incomingMissionWpSequence`
(src/main/telemetry/mavlink.c:1035-1036). MISSION_COUNT (within capacity) sets them to
(count, 0); every item whose seq equals the sequence counter is taken, whenever it comes,
and moves it on (1121-1123). An item is stored through setWaypoint(seq + 1): number 1 starts
a new plan, the stored count + 1 appends, any other number is dropped unstored
(src/main/navigation/navigation.c:3988-4001). So after an upload of 3 items a stray
MISSION_ITEM seq 3 is appended and answered ACCEPTED (seen on the 9.1.0 SITL: 3 items, then
4), and a stray item 0 is answered INVALID_SEQUENCE (1155-1159).

The server asks `stray` about an item that arrives with no upload running; the counters are
told of every MISSION_COUNT that opens an upload and every item an upload takes.
"""

from __future__ import annotations

from dataclasses import dataclass

from .constants import MissionResult


@dataclass(frozen=True)
class StrayVerdict:
    reply: MissionResult | None   # the MISSION_ACK; None: a MISSION_REQUEST for `request`
    store: str | None             # "replace" (the item is the whole plan now), "append", None
    request: int = 0


class UploadCounters:
    def __init__(self) -> None:
        self.count = 0      # incomingMissionWpCount
        self.seq = 0        # incomingMissionWpSequence: the item seq taken next

    def opened(self, count: int) -> None:
        self.count, self.seq = count, 0

    def took(self, seq: int) -> None:
        self.seq = seq + 1

    def stray(self, seq: int, stored: int) -> StrayVerdict:
        """An item `seq` outside any upload, with `stored` items in the plan."""
        if seq != self.seq:
            return StrayVerdict(MissionResult.INVALID_SEQUENCE, None)
        self.seq += 1
        number = self.seq   # setWaypoint's waypoint number
        store = "replace" if number == 1 else "append" if number == stored + 1 else None
        if self.seq < self.count:
            return StrayVerdict(None, store, request=self.seq)
        # the last item: INAV answers by its list-valid flag, which a stored last item sets
        # and a dropped one leaves as it was (set by a plan it holds, cleared by a clear)
        valid = store is not None or stored > 0
        return StrayVerdict(MissionResult.ACCEPTED if valid else MissionResult.INVALID, store)
