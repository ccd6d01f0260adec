"""MAVLink mission items <-> MSP waypoints: seed 004's mapping as data, and the conversion.

Each `ROWS` entry says what seed 004 claims, what INAV 9.1 does (with its source) and which
the code follows; `docs/msp-mapping.md` is generated from them (`render_markdown`). The
conversion is exact where it can be and refuses where it cannot, with the MISSION_ACK error
a vehicle would send and the row that says why: an item MSP cannot hold is never changed
silently. `to_waypoint` / `to_item` are inverse on every item `to_waypoint` accepts, up to
the frame synonyms MAVLink itself declares (GLOBAL_INT = GLOBAL, GLOBAL_RELATIVE_ALT_INT =
GLOBAL_RELATIVE_ALT: common.xml), a NaN param4 (MAVLink's "unchanged") and the `current`
flag, which come back as the plain frame, 0 and 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..mission.constants import Cmd, MissionResult
from ..mission.items import FRAME_MISSION, MissionItem, MissionType, to_float32
from .commands import FLAG_LAST, Waypoint

MAX_WAYPOINTS = 120          # INAV 9.1 src/main/target/common.h:162 (NAV_MAX_WAYPOINTS)
GLOBAL, RELATIVE = 0, 3      # MAV_FRAME_GLOBAL, MAV_FRAME_GLOBAL_RELATIVE_ALT
SYNONYMS = {5: GLOBAL, 6: RELATIVE}
ALT_AMSL = 0x01              # p3 bit 0: altitude is AMSL, else relative to home (INAV docs/Navigation.md)
I16 = (-32768, 32767)

SEED = "seed 004 ch. 2"
NAV_DOC = "INAV 9.1 docs/Navigation.md (`wp` parameters)"
NAV_H = "INAV 9.1 src/main/navigation/navigation.h"
NAV_C = "INAV 9.1 src/main/navigation/navigation.c"


@dataclass(frozen=True)
class Row:
    id: str               # what an expectations entry of the bridge names (its `variant`)
    mavlink: str
    msp: str
    seed: str             # what seed 004 says
    inav: str             # what INAV 9.1 does, with its source
    follows: str          # "INAV", "seed 004" or "both"
    conversion: str
    lost: str             # what the trip loses, or why an item is refused


@dataclass(frozen=True)
class Action:
    """A MAV_CMD that has an INAV waypoint action, and what its params become."""

    command: int
    action: int
    positional: bool      # carries lat/lon/alt
    p1: str | None        # "param": p1 = param1; "jump": p1 = param1 + 1 (a number); None: param1 must be 0
    p2: str | None        # "param": p2 = param2; None: param2 must be 0

    @property
    def name(self) -> str:
        return Cmd(self.command).name if self.command in Cmd._value2member_map_ else "DO_SET_ROI_LOCATION"


ACTIONS: dict[int, Action] = {a.command: a for a in (
    Action(Cmd.NAV_WAYPOINT, 1, True, None, None),
    Action(Cmd.NAV_LOITER_TIME, 3, True, "param", None),
    Action(Cmd.NAV_RETURN_TO_LAUNCH, 4, False, None, None),
    Action(195, 5, True, None, None),                         # MAV_CMD_DO_SET_ROI_LOCATION
    Action(Cmd.DO_JUMP, 6, False, "jump", "param"),
    Action(Cmd.CONDITION_YAW, 7, False, "param", None),
    Action(Cmd.NAV_LAND, 8, True, None, None),
)}
BY_ACTION = {a.action: a for a in ACTIONS.values()}

ROWS: tuple[Row, ...] = (
    Row("seq", "seq (u16, 0..n-1)", "wp_no (u8, 1..n)", f"{SEED}: seq u16 <-> wp_no u8, partially",
        f"number 0 is home, 1..{MAX_WAYPOINTS} the mission, 254/255 special ({NAV_C}:3957-3988)",
        "INAV", "wp_no = seq + 1", f"more than {MAX_WAYPOINTS} items: NO_SPACE"),
    Row("command", "command", "action", f"{SEED}: no action table",
        f"WAYPOINT 1, HOLD_TIME 3, RTH 4, SET_POI 5, JUMP 6, SET_HEAD 7, LAND 8 ({NAV_H}:520-526)",
        "INAV", "NAV_WAYPOINT 1, NAV_LOITER_TIME 3, NAV_RETURN_TO_LAUNCH 4, DO_SET_ROI_LOCATION 5, "
        "DO_JUMP 6, CONDITION_YAW 7, NAV_LAND 8", "any other command: UNSUPPORTED"),
    Row("position", "x, y (i32 degE7)", "lat, lon (i32 deg*1e7)", f"{SEED}: i32 in one table, u32 in another",
        f"int32_t, written with sbufWriteU32 ({NAV_H}:549-556; fc/fc_msp.c:1931-1932)", "INAV",
        "the same integer", "nothing (a non-positional action sends 0: x, y must be 0)"),
    Row("altitude", "z (float, m)", "alt (i32, cm)", f"{SEED}: z float <-> altitude i32, partially",
        f"centimetres, relative or AMSL by p3 bit 0 ({NAV_DOC})", "INAV",
        "alt = z * 100", "an altitude that is not whole centimetres (as float32): INVALID_PARAM7"),
    Row("frame", "frame", "p3 bit 0", f"{SEED}: param3 <-> p3",
        f"p3 is a bitfield; bit 0: altitude AMSL (1) or relative to home (0) ({NAV_DOC})", "INAV",
        "GLOBAL(_INT) -> 1, GLOBAL_RELATIVE_ALT(_INT) -> 0; MISSION for a non-positional action",
        "any other frame: UNSUPPORTED_FRAME; p3 bits 1-4 (user actions) have no MAVLink field"),
    Row("param1", "param1", "p1 (i16)", f"{SEED}: param1 f <-> p1 u16, partially",
        f"int16_t ({NAV_H}:553): HOLD_TIME seconds, JUMP target number, SET_HEAD degrees (-1 cancels), "
        f"WAYPOINT speed cm/s, RTH land flag ({NAV_DOC})", "INAV",
        "HOLD_TIME, SET_HEAD: p1 = param1; JUMP: p1 = param1 + 1 (a number, not a seq); others 0",
        "not integral or outside -32768..32767, or set where the action has no slot: INVALID_PARAM1"),
    Row("param2", "param2", "p2 (i16)", f"{SEED}: param2 f <-> p2 u16, partially",
        f"JUMP repeat count ({NAV_DOC})", "INAV", "JUMP: p2 = param2; others 0",
        "as param1: INVALID_PARAM2"),
    Row("param3", "param3", "p3 (i16)", f"{SEED}: param3 f <-> p3 u16 (one table says i32)",
        f"p3 holds the altitude datum and user bits ({NAV_DOC})", "INAV", "none: param3 must be 0",
        "a non-zero param3: INVALID_PARAM3"),
    Row("param4", "param4", "(none)", f"{SEED}: not mapped", "no slot", "both", "none: param4 must be 0 or NaN",
        "another param4: INVALID_PARAM4"),
    Row("autocontinue", "autocontinue", "(none)", f"{SEED}: not mapped",
        "INAV flies on from every waypoint (its MAVLink side refuses 0: telemetry/mavlink.c:1110)", "INAV",
        "must be 1", "autocontinue 0: UNSUPPORTED"),
    Row("current", "current", "(none)", f"{SEED}: MISSION_SET_CURRENT <-> MSP_SET_WP wp_no", "no stored field",
        "INAV", "not stored; comes back 0", "the flag (set-current is its own operation)"),
    Row("last-item", "last item", "flag (u8)", f"{SEED}: flag, partially",
        f"0xA5 marks the last waypoint; the list is valid only then ({NAV_H}:537; {NAV_C}:4001)", "INAV",
        "flag = 0xA5 on item n-1, else 0", "nothing"),
    Row("plan-types", "mission_type", "(none)", f"{SEED}: not mapped", "MSP holds one waypoint mission", "both",
        "MAV_MISSION_TYPE_MISSION only", "a fence or rally plan: UNSUPPORTED"),
    Row("empty-mission", "an empty mission (MISSION_CLEAR_ALL, MISSION_COUNT 0)",
        "waypoint 1: RTH of zeros, flag 0xA5", f"{SEED}: not mapped",
        "no MSP command empties the list (only the CLI's `wp reset` and MAVLink's MISSION_CLEAR_ALL call "
        "resetWaypointList: fc/cli.c:1901, telemetry/mavlink.c:1026); the MultiWii NAV convention "
        "(mwptools' MSP notes) stores one RTH flagged 0xA5 for \"no mission\", which is also what MSP_WP "
        "returns for a waypoint that does not exist (navigation.c:3822-3830)", "INAV",
        "a clear writes that record; that record alone reads back as no mission",
        "a mission of exactly one plain NAV_RETURN_TO_LAUNCH: UNSUPPORTED (it would read back as empty)"),
    Row("set-current", "MISSION_SET_CURRENT seq, MAV_CMD_DO_SET_MISSION_CURRENT",
        "MSP2_INAV_SET_WP_INDEX (v2, u8 index)", f"{SEED}: MISSION_SET_CURRENT seq <-> MSP_SET_WP wp_no",
        "MSP_SET_WP n stores waypoint n; the index is set by MSP2_INAV_SET_WP_INDEX, taken only while armed "
        "flying a WP mission (msp_protocol_v2_inav.h:132; navigation.c:3895-3907)", "INAV", "index = seq",
        "on the ground: refused (STATUSTEXT; the command: TEMPORARILY_REJECTED), MISSION_CURRENT unchanged"),
    Row("home", "HOME_POSITION, MAV_CMD_DO_SET_HOME (lat, lon: degE7; alt: mm)", "MSP_WP / MSP_SET_WP of waypoint 0",
        f"{SEED}: HOME_POSITION lat, lon, alt <-> MSP_WP lat, lon, altitude; SET_HOME_POSITION <-> MSP_SET_WP",
        "MSP_WP 0 holds GPS_home once there is a home fix, else zeros (navigation.c:3832-3838); MSP_SET_WP 0 "
        "sets home only while armed with a usable position (navigation.c:3958-3962)", "INAV",
        "alt (cm) = altitude (mm) / 10", "no home yet, or a new one on the ground: TEMPORARILY_REJECTED"),
    Row("heartbeat", "HEARTBEAT type, mavlink_version", "(none)",
        f"{SEED}: type <- MSP_IDENT (100) MULTITYPE, mavlink version <- MSP_IDENT MSP VERSION",
        "INAV 9.1 has no MSP_IDENT (msp/msp_protocol.h defines none; a request is answered `!`)", "INAV",
        "the bridge's HEARTBEAT: MAV_TYPE_GENERIC, MAV_AUTOPILOT_GENERIC_MISSION_FULL, MAVLink 2",
        "the vehicle's type"),
    Row("mission-current", "MISSION_CURRENT seq", "MSP_NAV_STATUS active waypoint number (u8)",
        f"{SEED}: MISSION_CURRENT seq <-> MSP_WP wp_no",
        "activeWpNumber = active index + 1 (navigation.c:2701-2702), sent by MSP_NAV_STATUS (fc/fc_msp.c:990-997)",
        "INAV", "seq = number - 1 (number 0: seq 0)", "nothing"),
)
ROW_IDS = frozenset(r.id for r in ROWS)


@dataclass(frozen=True)
class Refusal:
    code: MissionResult
    why: str


def _i16(value: float, code: MissionResult, what: str) -> int | Refusal:
    if not math.isfinite(value) or value != int(value) or not I16[0] <= value <= I16[1]:
        return Refusal(code, f"{what} {value!r} is no 16-bit integer")
    return int(value)


def to_waypoint(item: MissionItem, count: int) -> Waypoint | Refusal:
    """The waypoint for `item`, the item `item.seq` of a `count`-item mission, or why not."""
    if item.mission_type is not MissionType.MISSION:
        return Refusal(MissionResult.UNSUPPORTED, "MSP holds waypoint missions only, no fence or rally")
    if count > MAX_WAYPOINTS or not 0 <= item.seq < count:
        return Refusal(MissionResult.NO_SPACE, f"MSP holds {MAX_WAYPOINTS} waypoints")
    action = ACTIONS.get(item.command)
    if action is None:
        return Refusal(MissionResult.UNSUPPORTED, f"command {item.command} has no INAV waypoint action")
    if item.autocontinue != 1:
        return Refusal(MissionResult.UNSUPPORTED, "autocontinue 0: INAV flies on from every waypoint")
    frame = SYNONYMS.get(item.frame, item.frame)
    if action.positional and frame not in (GLOBAL, RELATIVE):
        return Refusal(MissionResult.UNSUPPORTED_FRAME, f"frame {item.frame}: MSP altitudes are relative or AMSL")
    if not action.positional and frame != FRAME_MISSION:
        return Refusal(MissionResult.UNSUPPORTED_FRAME, f"frame {item.frame}: a non-positional action is frame 2")
    slots: list[int] = []
    for n, source, mine in ((1, action.p1, item.param1), (2, action.p2, item.param2)):
        code = MissionResult.INVALID_PARAM1 if n == 1 else MissionResult.INVALID_PARAM2
        if source is None:
            if mine != 0:
                return Refusal(code, f"param{n} {mine!r}: the action has no slot for it")
            slots.append(0)
            continue
        got = _i16(mine + 1 if source == "jump" else mine, code, f"param{n}")
        if isinstance(got, Refusal):
            return got
        if source == "jump" and not 1 <= got <= count:
            return Refusal(code, f"DO_JUMP to seq {mine!r}: not an item of this mission")
        slots.append(got)
    if item.param3 != 0:
        return Refusal(MissionResult.INVALID_PARAM3, "param3: p3 holds the altitude datum in INAV")
    if not (item.param4 == 0 or math.isnan(item.param4)):
        return Refusal(MissionResult.INVALID_PARAM4, "param4 has no MSP slot")
    if action.positional:
        cm = round(item.z * 100) if math.isfinite(item.z) else None
        if cm is None or to_float32(cm / 100) != to_float32(item.z) or abs(cm) > 2**31 - 1:
            return Refusal(MissionResult.INVALID_PARAM7, f"altitude {item.z!r} m is not whole centimetres")
        x, y, alt, p3 = item.x, item.y, cm, ALT_AMSL if frame == GLOBAL else 0
    else:
        if item.x or item.y or item.z:
            return Refusal(MissionResult.INVALID_PARAM5_X if item.x else MissionResult.INVALID_PARAM6_Y
                           if item.y else MissionResult.INVALID_PARAM7, "a non-positional action has no location")
        x = y = alt = p3 = 0
    return Waypoint(item.seq + 1, action.action, x, y, alt, slots[0], slots[1], p3,
                    FLAG_LAST if item.seq == count - 1 else 0)


def to_item(wp: Waypoint) -> MissionItem | Refusal:
    """The mission item for a waypoint of the list (number 1..120), or why not."""
    action = BY_ACTION.get(wp.action)
    if action is None:
        return Refusal(MissionResult.UNSUPPORTED, f"waypoint action {wp.action} has no MAVLink command")
    if not 1 <= wp.number <= MAX_WAYPOINTS:
        return Refusal(MissionResult.INVALID_SEQUENCE, f"waypoint number {wp.number} is not a mission waypoint")
    p1 = float(wp.p1 - 1 if action.p1 == "jump" else wp.p1) if action.p1 else 0.0
    p2 = float(wp.p2) if action.p2 else 0.0
    if action.positional:
        frame = GLOBAL if wp.p3 & ALT_AMSL else RELATIVE
        return MissionItem(wp.number - 1, frame, action.command, p1, p2, 0.0, 0.0, wp.lat, wp.lon,
                           wp.alt / 100, 0, 1)
    return MissionItem(wp.number - 1, FRAME_MISSION, action.command, p1, p2, 0.0, 0.0, 0, 0, 0.0, 0, 1)


def render_markdown() -> str:
    """docs/msp-mapping.md, from ROWS and ACTIONS (tests/msp/test_mapping.py keeps it current)."""
    out = ["# MAVLink mission items and MSP waypoints", "",
           "Generated from `reference_impl/msp/mapping.py` (`python -m mavconform.reference_impl.msp.mapping`): "
           "each row says what seed 004 claims, what INAV 9.1 does and which the code follows. An item that "
           "does not fit is refused with the MISSION_ACK error in the last column, never changed.", "",
           "| row | MAVLink | MSP | seed 004 | INAV 9.1 | follows | conversion | lost or refused |",
           "|---|---|---|---|---|---|---|---|"]
    out += [f"| `{r.id}` | {r.mavlink} | {r.msp} | {r.seed} | {r.inav} | {r.follows} | {r.conversion} | {r.lost} |"
            for r in ROWS]
    out += ["", "| MAV_CMD | INAV action | location | p1 | p2 |", "|--:|--:|---|---|---|"]
    for a in ACTIONS.values():
        p1 = {"param": "param1", "jump": "param1 + 1 (a number)", None: "0"}[a.p1]
        p2 = {"param": "param2", None: "0"}[a.p2]
        out.append(f"| {int(a.command)} {a.name} | {a.action} | {'yes' if a.positional else 'no (frame 2)'} | {p1} | {p2} |")
    return "\n".join(out) + "\n"


if __name__ == "__main__":   # pragma: no cover - regenerates the page
    print(render_markdown(), end="")
