"""Waypoint lists the MSP checks write: every field set, so a read-back that loses one shows.

Each waypoint differs from the others and from what MSP_WP returns for a waypoint that does
not exist (an RTH record of zeros flagged 0xA5), so "stored" and "not stored" can be told
from a read-back alone, without trusting MSP_WP_GETINFO (its own clause judges that).
Values cover INAV's types: negative lat/lon/p1 (int32 and int16 are signed), p3's AMSL bit,
a JUMP (INAV stores its target as an index and sends it back as a number), the last
waypoint flagged 0xA5.
"""

from __future__ import annotations

from mavconform.reference_impl.msp.commands import FLAG_LAST, Waypoint

HOME_LAT, HOME_LON = 473_977_420, 85_455_940      # deg * 1e7 (PX4's default home, Zurich)
WAYPOINT, HOLD_TIME, SET_POI, JUMP, SET_HEAD, LAND = 1, 3, 5, 6, 7, 8


def waypoint(number: int, variant: int = 0, *, last: bool = False) -> Waypoint:
    """A waypoint to store as `number`; `variant` tells apart lists written to the same numbers."""
    k = number + 1000 * variant
    kind = number % 5
    flag = FLAG_LAST if last else 0
    lat, lon, alt = HOME_LAT + 137 * k, HOME_LON - 91 * k, 1000 + 25 * k
    if kind == 1:
        return Waypoint(number, WAYPOINT, lat, lon, alt, 150 + variant, 0, 1, flag)     # speed cm/s, AMSL
    if kind == 2:
        return Waypoint(number, HOLD_TIME, lat, lon, alt, 12 + variant, 300, 0, flag)   # 12 s, speed 300
    if kind == 3:
        return Waypoint(number, SET_HEAD, 0, 0, 0, -1 if variant % 2 == 0 else 90, 0, 0, flag)
    if kind == 4:
        return Waypoint(number, SET_POI, -lat, -lon, alt, 0, 0, 0, flag)
    return Waypoint(number, LAND, lat, lon, alt + 7, 0, 0, 1, flag)


def mission(count: int, variant: int = 0) -> list[Waypoint]:
    """Waypoints 1..count, the last flagged; with a JUMP back to 1 at 3 when there is room."""
    out = [waypoint(n, variant, last=n == count) for n in range(1, count + 1)]
    if count >= 4:
        out[2] = Waypoint(3, JUMP, 0, 0, 0, 1, 2 + variant, 0, 0)    # jump to waypoint 1, twice
    return out

