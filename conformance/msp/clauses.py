"""An MSP flight controller's waypoint store as clauses (MSP.*, role msp).

Seed 004 maps MAVLink's mission onto MSP_SET_WP and MSP_WP but says little about how a
flight controller keeps waypoints; the MSP that flies today is INAV's, so most clauses cite
INAV 9.1 (its docs/Navigation.md and source, `inav-9.1/...`, cited as facts: a claim about
what INAV does and documents, which any MSP waypoint store is held to). Each requirement
quotes its source between double quotes; tests/conformance/msp/test_msp_clauses.py checks
the quote is at the cited line (seed 004 always, INAV's tree where MAVCONFORM_INAV_SOURCE
points at it). Levels: MUST where the source states the behaviour, MAY for an optional
feature (non-volatile storage: compiled in with NAV_NON_VOLATILE_WAYPOINT_STORAGE).
"""

from __future__ import annotations

from ..clause import Clause, Level, Role

SEED_004 = "seeds/004_5e57ed2b9948c3d5.txt"
INAV = "inav-9.1"            # INAV 9.1.0's tree (e7d5cceb): source and docs
NAVIGATION_C = f"{INAV}/src/main/navigation/navigation.c"
FC_MSP_C = f"{INAV}/src/main/fc/fc_msp.c"
NAVIGATION_MD = f"{INAV}/docs/Navigation.md"
MSP_SERIAL_C = f"{INAV}/src/main/msp/msp_serial.c"

MUST, MAY = Level.MUST, Level.MAY


def _m(id: str, level: Level, title: str, source: str, requirement: str) -> Clause:
    return Clause(id, level, Role.MSP, title, source, requirement)


MSP_CLAUSES: tuple[Clause, ...] = (
    # --- the waypoint store --------------------------------------------------------------
    _m("MSP.WP.01", MUST, "A mission written with MSP_SET_WP 1..n reads back field for field with MSP_WP",
       f"{NAVIGATION_C}:3993", 'A waypoint taken is stored as it came, "posControl.waypointList[wpNumber - 1] '
       '= *wpData;", and MSP_WP sends the stored record back field by field (fc/fc_msp.c:1926-1937): what '
       'was accepted reads back as written.'),
    _m("MSP.WP.02", MUST, "MSP_WP_GETINFO reports the count and validity the list really has",
       f"{FC_MSP_C}:1504", 'MSP_WP_GETINFO answers "sbufWriteU8(dst, isWaypointListValid()); // Is current '
       'mission valid" and then the number of waypoints in the current mission (fc_msp.c:1505).'),
    _m("MSP.WP.03", MUST, "The waypoint flagged 0xA5 ends the mission: the list is valid once it is taken, not before",
       f"{NAVIGATION_MD}:103", 'The mission ends at its flagged waypoint: "Last waypoint must have `flag` set '
       'to 165 (0xA5)." The list is valid only once that waypoint is taken (navigation.c:4002).'),
    _m("MSP.WP.04", MUST, "The reported maximum is honoured: that many waypoints are stored, one more is not",
       f"{FC_MSP_C}:1503", 'MSP_WP_GETINFO reports "sbufWriteU8(dst, NAV_MAX_WAYPOINTS); // Maximum number of '
       'waypoints supported": a mission of that many is stored whole, and a waypoint past it is refused or '
       'ignored.'),
    _m("MSP.WP.05", MUST, "MSP_SET_WP with a payload that is not 21 bytes is answered `!` and stores nothing",
       f"{FC_MSP_C}:3083", 'MSP_SET_WP is taken only "if (dataSize == 21) {"; any other size returns '
       'MSP_RESULT_ERROR (fc_msp.c:3109-3110), which goes out as a `!` reply (msp_serial.c:306).'),
    _m("MSP.WP.06", MUST, "Waypoint numbers outside 1..max (0 is home; past the maximum) are not stored in the mission",
       f"{NAVIGATION_C}:3983", 'A mission waypoint is taken only "else if ((wpNumber >= 1) && (wpNumber <= '
       'NAV_MAX_WAYPOINTS)": number 0 (home, set only while armed) and a number past the maximum change nothing in the list.'),
    _m("MSP.WP.07", MUST, "Only number 1 (a new mission) or count + 1 (the next) is taken: a gap is not stored",
       f"{NAVIGATION_C}:3986", '"// Only allow upload next waypoint (continue upload mission) or first waypoint '
       '(new mission)": number 1 starts a new list, count + 1 appends, any other number is not stored.'),
    _m("MSP.WP.08", MUST, "MSP_WP past the end of the list returns no waypoint of an older, longer mission",
       f"{NAVIGATION_C}:3866", 'MSP_WP reads a stored waypoint only "if (wpNumber <= getWaypointCount()) {": '
       'once a shorter mission replaces a longer one, the numbers past its end do not read back the old '
       'waypoints.'),
    _m("MSP.WP.09", MAY, "A mission saved with MSP_WP_MISSION_SAVE comes back with MSP_WP_MISSION_LOAD",
       f"{NAVIGATION_MD}:105", '"`wp save` - Checks list of waypoints and save from FC to EEPROM", and `wp load` '
       'brings them back (Navigation.md:64; over MSP: MSP_WP_MISSION_SAVE and _LOAD, fc_msp.c:3381-3391): a '
       'mission saved, then overwritten, then loaded reads back as saved.'),
    # --- framing -------------------------------------------------------------------------
    _m("MSP.FR.01", MUST, "A request is answered in its own framing: v1, v2, and v2 inside v1",
       f"{MSP_SERIAL_C}:418", 'The reply goes out in the version the request came in: '
       '"mspSerialEncode(msp, &reply, msp->mspVersion);".'),
    _m("MSP.FR.02", MUST, "A request with a bad checksum is neither answered nor acted on",
       f"{SEED_004}:85", 'Seed 004: "The checksum is the XOR of size, type and payload bytes". A frame whose '
       'checksum differs is dropped and the parser waits for the next `$` (INAV msp_serial.c:173-178).'),
    _m("MSP.FR.03", MUST, "A command the flight controller does not know is answered `!`",
       f"{FC_MSP_C}:3825", 'The command dispatcher ends "default: return MSP_RESULT_ERROR;", which goes out as '
       'a `!` reply (msp_serial.c:306): the client learns the command is not there instead of waiting.'),
)
