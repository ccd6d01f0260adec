"""The MSP commands a mission needs, and their payloads, as data with their sources.

Seed 004 (ch. 2) maps MAVLink's mission messages onto MSP_SET_WP (209), MSP_WP (118) and
MSP_NAV_STATUS (121); the numbers, layouts and answers below are INAV 9.1's, read in
`src/main/msp/msp_protocol.h` and `src/main/fc/fc_msp.c` (VARIANTS.md M1-M4). Where seed 004
says otherwise the row says so: it gives p1..p3 as u16 (INAV stores int16_t,
navigation.h:553) and lat/lon as u32 in one table, i32 in another (INAV: int32_t, sent
through sbufWriteU32, so the bytes are the same and the sign is INAV's).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

INAV = "INAV 9.1 src/main"


@dataclass(frozen=True)
class Command:
    name: str
    code: int
    request: str          # struct format of the request payload ("" for none)
    reply: str            # struct format of the reply payload ("" for an empty ACK)
    source: str
    note: str = ""

    @property
    def request_size(self) -> int:
        return struct.calcsize(self.request) if self.request else 0

    @property
    def reply_size(self) -> int:
        return struct.calcsize(self.reply) if self.reply else 0


WAYPOINT_FORMAT = "<BBiiihhhB"   # wp_no, action, lat, lon, alt (cm), p1, p2, p3, flag: 21 bytes

COMMANDS: dict[str, Command] = {c.name: c for c in (
    Command("MSP_API_VERSION", 1, "", "<BBB", f"{INAV}/msp/msp_protocol.h:95; fc/fc_msp.c:393-396",
            "protocol version, API major, API minor"),
    Command("MSP_WP_MISSION_LOAD", 18, "<B", "", f"{INAV}/msp/msp_protocol.h:116; fc/fc_msp.c:3381-3385",
            "mission id (reserved, 0); loads the list from non-volatile memory; a size other than 1: `!`"),
    Command("MSP_WP_MISSION_SAVE", 19, "<B", "", f"{INAV}/msp/msp_protocol.h:117; fc/fc_msp.c:3387-3391",
            "mission id (reserved, 0); saves the list; a size other than 1, or a save refused: `!`"),
    Command("MSP_WP_GETINFO", 20, "", "<BBBB", f"{INAV}/msp/msp_protocol.h:118; fc/fc_msp.c:1501-1506",
            "reserved 0, max waypoints (120), mission valid, waypoint count (VARIANTS M4)"),
    Command("MSP_WP", 118, "<B", WAYPOINT_FORMAT, f"{INAV}/msp/msp_protocol.h:249; fc/fc_msp.c:1924-1938, 4447-4450",
            "request: the waypoint number; reply: the 21-byte waypoint record (VARIANTS M2)"),
    Command("MSP_NAV_STATUS", 121, "", "<BBBBBh", f"{INAV}/msp/msp_protocol.h:252; fc/fc_msp.c:990-997",
            "mode, state, active waypoint action, active waypoint number, error, heading-hold target "
            "(seed 004: target_bearing)"),
    Command("MSP2_INAV_SET_WP_INDEX", 0x2221, "<B", "", f"{INAV}/msp/msp_protocol_v2_inav.h:132; fc/fc_msp.c:3814-3823",
            "MSP v2 only: the 0-based index of the waypoint to fly to; taken only while armed and flying a "
            "WP mission (navigation.c:3895-3907), else `!` (seed 004 maps MISSION_SET_CURRENT onto "
            "MSP_SET_WP's wp_no, which INAV takes as a waypoint to store)"),
    Command("MSP_SET_WP", 209, WAYPOINT_FORMAT, "", f"{INAV}/msp/msp_protocol.h:268; fc/fc_msp.c:3082-3112",
            "the 21-byte record; answered `>` even when setWaypoint ignored it (only a size other than "
            "21 is `!`), so only a read-back tells"),
)}
BY_CODE = {c.code: c for c in COMMANDS.values()}


@dataclass(frozen=True)
class Waypoint:
    """INAV's waypoint record (navWaypoint_t, navigation/navigation.h:549-556, sent in the
    order of fc_msp.c:1929-1937). Number 0 is home, 1..120 the mission, 254/255 special."""

    number: int
    action: int
    lat: int          # degrees * 1e7
    lon: int
    alt: int          # centimetres
    p1: int = 0
    p2: int = 0
    p3: int = 0
    flag: int = 0     # 0xA5: the last waypoint of the mission (NAV_WP_FLAG_LAST)

    def pack(self) -> bytes:
        return struct.pack(WAYPOINT_FORMAT, self.number, self.action, self.lat, self.lon, self.alt,
                           self.p1, self.p2, self.p3, self.flag)

    @classmethod
    def unpack(cls, payload: bytes) -> Waypoint:
        """The record in an MSP_WP reply or MSP_SET_WP request; ValueError if it is not 21 bytes."""
        if len(payload) != struct.calcsize(WAYPOINT_FORMAT):
            raise ValueError(f"a waypoint record is 21 bytes, not {len(payload)}")
        return cls(*struct.unpack(WAYPOINT_FORMAT, payload))


FLAG_LAST = 0xA5               # navigation.h:537
CODE = {name: c.code for name, c in COMMANDS.items()}   # command name -> number
WAYPOINT_FIELDS = ("number", "action", "lat", "lon", "alt", "p1", "p2", "p3", "flag")


def waypoint_difference(sent: Waypoint, back: Waypoint, *, verb: str = "sent") -> str | None:
    """The first field a read-back lost, as "p2: sent 300, read back 0"; None if equal."""
    for name in WAYPOINT_FIELDS:
        a, b = getattr(sent, name), getattr(back, name)
        if a != b:
            return f"{name}: {verb} {a}, read back {b}"
    return None


@dataclass(frozen=True)
class WaypointInfo:
    reserved: int
    max_waypoints: int
    valid: bool
    count: int

    @classmethod
    def unpack(cls, payload: bytes) -> WaypointInfo:
        if len(payload) != 4:
            raise ValueError(f"MSP_WP_GETINFO's reply is 4 bytes, not {len(payload)}")
        reserved, top, valid, count = struct.unpack("<BBBB", payload)
        return cls(reserved, top, bool(valid), count)

    def pack(self) -> bytes:
        return struct.pack("<BBBB", self.reserved, self.max_waypoints, int(self.valid), self.count)
