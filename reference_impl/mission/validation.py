"""What the reference vehicle accepts in an uploaded item, as a table of rules.

The spec lets a vehicle refuse an item with a MISSION_ACK error that names the defect
(MAV_MISSION_UNSUPPORTED, _UNSUPPORTED_FRAME, _INVALID_PARAMn, ...), which cancels the
upload and leaves the old plan in place. The rules are data so a profile can swap them
and a report can print them; the first rule an item breaks decides the code. Which mission
commands are known is a set a profile may narrow, or a table of sets chosen by the item's
frame (`CommandList`, as PX4's parser has), and the frames an item with a location may use
are a set a profile may widen (`rules_for`); the spec vehicle knows every mission command of
the upstream XML (commands.py) in any global frame or MAV_FRAME_MISSION. A NaN in params 1-4
means "use the default" to the spec vehicle; a profile may say which params of which commands
may be NaN (`param_rules`, checked before anything else, as ArduPilot does), cap the
altitude of a location (`altitude_rules`), leave latitude and longitude unchecked (PX4), and
refuse autocontinue 0 or allow each command only some frames (`command_frame_rules`, INAV).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from operator import attrgetter
from typing import AbstractSet, Callable, Mapping, Sequence

from .c_numbers import i32, u16
from .commands import LOCATION_COMMANDS
from .constants import (
    FENCE_COMMANDS, MISSION_COMMANDS, POSITIONAL_COMMANDS, RALLY_COMMANDS, Cmd, MissionResult,
)
from .items import FRAME_MISSION, GLOBAL_FRAMES, MISSION_PLAN, MissionItem, MissionType

COMMANDS_BY_TYPE = {
    MissionType.MISSION: MISSION_COMMANDS,
    MissionType.FENCE: FENCE_COMMANDS,
    MissionType.RALLY: RALLY_COMMANDS,
}
# Enum members the rules read for every item, bound once: on Python 3.11 each read of a
# member off its class (`Cmd.DO_JUMP`) goes through the enum metaclass's slow attribute hook.
_NAV_WAYPOINT, _DO_JUMP = Cmd.NAV_WAYPOINT, Cmd.DO_JUMP
_POLYGON_VERTICES = (Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION, Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION)
_CIRCLES = (Cmd.NAV_FENCE_CIRCLE_INCLUSION, Cmd.NAV_FENCE_CIRCLE_EXCLUSION)
_ROI_COMMANDS = (Cmd.NAV_ROI, Cmd.DO_SET_ROI)
COMMAND_RULE = "command known for its mission type"
FRAME_LIST_RULE = "frame selects a command list"
LOCATION_FRAME_RULE = "a location in a frame the vehicle takes"
_PARAM_CODES = {
    1: MissionResult.INVALID_PARAM1, 2: MissionResult.INVALID_PARAM2,
    3: MissionResult.INVALID_PARAM3, 4: MissionResult.INVALID_PARAM4,
}


@dataclass(frozen=True)
class ItemRule:
    """One acceptance rule: items it `applies` to must satisfy `holds`, else `code`."""

    name: str
    code: MissionResult
    applies: Callable[[MissionItem], bool]
    holds: Callable[[MissionItem], bool]


NanParams = Mapping[int, AbstractSet[int]]   # mission command -> its params (1-4) that may be NaN


def _not_inf(v: float) -> bool:
    return not math.isinf(v)  # NaN means "use the default" (upstream MISSION_ITEM text)


def _count_ok(v: float) -> bool:
    return math.isfinite(v) and v >= 3 and v == int(v)


_PARAM_GETTERS = {n: attrgetter(f"param{n}") for n in (1, 2, 3, 4)}


def _param(n: int) -> Callable[[MissionItem], float]:
    """Reads param n of an item (made once: rules run for every item of every upload)."""
    return _PARAM_GETTERS[n]


def _positional(it: MissionItem) -> bool:
    return it.command in POSITIONAL_COMMANDS or it.mission_type != MISSION_PLAN


def _in_mission(it: MissionItem) -> bool:
    return it.mission_type is MISSION_PLAN


@dataclass(frozen=True)
class CommandList:
    """The mission commands a vehicle stores for items in `frames` (None: in any frame)."""

    frames: frozenset[int] | None
    commands: frozenset[int]


MissionCommands = AbstractSet[int] | Sequence[CommandList] | None


def command_rules(mission_commands: MissionCommands, all_plans: bool = False) -> tuple[ItemRule, ...]:
    """MAV_MISSION_UNSUPPORTED for a command the plan type does not hold. `mission_commands`:
    the mission commands this vehicle stores, in any frame; or a table of `CommandList`s,
    where the first list whose frames hold the item's frame decides, and a mission item in a
    frame no list has gets UNSUPPORTED_FRAME first; None: any command in a mission (fence and
    rally items must still carry their own). `all_plans`: the table decides fence and rally
    items too (their commands must then be in the frame's list), as PX4's one parser does."""
    if mission_commands is None:
        return (ItemRule("fence and rally commands known", MissionResult.UNSUPPORTED,
                         lambda it: it.mission_type is not MISSION_PLAN,
                         lambda it: it.command in COMMANDS_BY_TYPE[it.mission_type]),)
    if isinstance(mission_commands, AbstractSet):
        mission_commands = (CommandList(None, frozenset(mission_commands)),)
    table = tuple(mission_commands)

    chosen_for: dict[int, CommandList | None] = {}   # frame -> its list, found once per frame

    def selected(frame: int) -> CommandList | None:
        try:
            return chosen_for[frame]
        except KeyError:
            chosen = chosen_for[frame] = next((c for c in table if c.frames is None or frame in c.frames), None)
            return chosen

    def known(it: MissionItem) -> bool:
        if it.mission_type is not MISSION_PLAN or all_plans:
            # a table shared by every plan type still holds each type to its own commands
            if it.command not in COMMANDS_BY_TYPE[it.mission_type]:
                return False
            if it.mission_type is not MISSION_PLAN and not all_plans:
                return True
        chosen = selected(it.frame)
        return chosen is not None and it.command in chosen.commands

    command = ItemRule(COMMAND_RULE, MissionResult.UNSUPPORTED, lambda it: True, known)
    if all(c.frames is None for c in table):
        return (command,)
    return (ItemRule(FRAME_LIST_RULE, MissionResult.UNSUPPORTED_FRAME, (lambda it: True) if all_plans else _in_mission,
                     lambda it: selected(it.frame) is not None), command)


def command_frame_rules(command_frames: Mapping[int, AbstractSet[int]] | None,
                        autocontinue_required: bool = False) -> tuple[ItemRule, ...]:
    """Rules checked right after the command. `autocontinue_required`: a mission item with
    autocontinue 0 gets MAV_MISSION_UNSUPPORTED, as an unknown command does. `command_frames`
    (command -> frames): a mission item with a listed command in another frame gets
    UNSUPPORTED_FRAME (INAV 9.1: NAV_WAYPOINT only in frame 3, RTL in 3 or 2)."""
    rules: tuple[ItemRule, ...] = ()
    if autocontinue_required:
        rules += (ItemRule("autocontinue set", MissionResult.UNSUPPORTED, _in_mission,
                           lambda it: it.autocontinue != 0),)
    if command_frames is not None:
        table = {command: frozenset(frames) for command, frames in command_frames.items()}
        rules += (ItemRule("a frame its command takes", MissionResult.UNSUPPORTED_FRAME,
                           lambda it: _in_mission(it) and it.command in table,
                           lambda it: it.frame in table[it.command]),)
    return rules


_FRAME_KNOWN = ItemRule("frame known", MissionResult.UNSUPPORTED_FRAME,
                        lambda it: True, lambda it: it.frame in GLOBAL_FRAMES or it.frame == FRAME_MISSION)
_POSITIONS_GLOBAL = ItemRule("positions use a global frame", MissionResult.UNSUPPORTED_FRAME,
                             _positional, lambda it: it.frame in GLOBAL_FRAMES)


def frame_rules(location_frames: AbstractSet[int] | None) -> tuple[ItemRule, ...]:
    """UNSUPPORTED_FRAME rules. None: the spec's (any item in a global frame or
    MAV_FRAME_MISSION, a destination in a global frame). A set: a mission item whose command
    has a location (the XML's hasLocation) must use one of these frames, and the frame of one
    without a location is not looked at; fence and rally items keep the spec's rules."""
    if location_frames is None:
        return (_FRAME_KNOWN, _POSITIONS_GLOBAL)
    frames = frozenset(location_frames)
    return (
        ItemRule(_FRAME_KNOWN.name, _FRAME_KNOWN.code,
                 lambda it: not _in_mission(it), _FRAME_KNOWN.holds),
        ItemRule(_POSITIONS_GLOBAL.name, _POSITIONS_GLOBAL.code,
                 lambda it: not _in_mission(it), _POSITIONS_GLOBAL.holds),
        ItemRule(LOCATION_FRAME_RULE, MissionResult.UNSUPPORTED_FRAME,
                 lambda it: _in_mission(it) and it.command in LOCATION_COMMANDS,
                 lambda it: it.frame in frames),
    )


def param_rules(nan_params: NanParams | None) -> tuple[ItemRule, ...]:
    """Rules put before all others. None: none (the spec's +-inf rules come with the values,
    and NaN is taken). A table: in a mission item, params 1-4 must be finite, or NaN where
    the table lists that param for the item's command; the first bad one gives
    INVALID_PARAMn, whatever else is wrong with the item (ArduPilot's sanity_check_params)."""
    if nan_params is None:
        return ()
    table = {command: frozenset(params) for command, params in nan_params.items()}

    def ok(n: int) -> Callable[[MissionItem], bool]:
        param = _param(n)

        def holds(it: MissionItem) -> bool:
            v = param(it)
            return math.isfinite(v) or (math.isnan(v) and n in table.get(it.command, ()))
        return holds

    return tuple(ItemRule(f"param{n} finite, NaN only where the command takes it", _PARAM_CODES[n],
                          _in_mission, ok(n)) for n in (1, 2, 3, 4))


def altitude_rules(location_alt_max: float | None) -> tuple[ItemRule, ...]:
    """None: none beyond the spec's finite altitude of a destination. A number (m): a mission
    item whose command has a location (the XML's hasLocation) needs a finite z below it in
    magnitude, else INVALID_PARAM7."""
    if location_alt_max is None:
        return ()
    return (ItemRule(f"location altitude finite and below {location_alt_max:g} m", MissionResult.INVALID_PARAM7,
                     lambda it: _in_mission(it) and it.command in LOCATION_COMMANDS,
                     lambda it: math.isfinite(it.z) and abs(it.z) < location_alt_max),)


_FIELD_RULES: tuple[ItemRule, ...] = (
    ItemRule("current and autocontinue are 0 or 1", MissionResult.INVALID,
             lambda it: True, lambda it: it.current in (0, 1) and it.autocontinue in (0, 1)),
    *(ItemRule(f"param{n} is not infinite", _PARAM_CODES[n],
               lambda it: True, (lambda param: lambda it: _not_inf(param(it)))(_param(n)))
      for n in (1, 2, 3, 4)),
)
_LAT_LON_RULES: tuple[ItemRule, ...] = (
    ItemRule("latitude within +-90 deg", MissionResult.INVALID_PARAM5_X,
             lambda it: it.frame in GLOBAL_FRAMES, lambda it: -900_000_000 <= it.x <= 900_000_000),
    ItemRule("longitude within +-180 deg", MissionResult.INVALID_PARAM6_Y,
             lambda it: it.frame in GLOBAL_FRAMES,
             lambda it: -1_800_000_000 <= it.y <= 1_800_000_000),
)
_ALTITUDE_FINITE = ItemRule("altitude finite", MissionResult.INVALID_PARAM7,
                            _positional, lambda it: math.isfinite(it.z))
_HOLD_TIME = ItemRule("waypoint hold time >= 0", MissionResult.INVALID_PARAM1,
                      lambda it: it.command == _NAV_WAYPOINT,
                      lambda it: math.isnan(it.param1) or it.param1 >= 0)
_FENCE_VALUE_RULES: tuple[ItemRule, ...] = (
    ItemRule("fence polygon vertex count is an integer >= 3", MissionResult.INVALID_PARAM1,
             lambda it: it.command in _POLYGON_VERTICES,
             lambda it: _count_ok(it.param1)),
    ItemRule("fence circle radius > 0", MissionResult.INVALID_PARAM1,
             lambda it: it.command in _CIRCLES,
             lambda it: math.isfinite(it.param1) and it.param1 > 0),
)
_JUMP_RULES: tuple[ItemRule, ...] = (
    ItemRule("jump target is a whole seq >= 0", MissionResult.INVALID_PARAM1,
             lambda it: it.command == _DO_JUMP,
             lambda it: math.isfinite(it.param1) and it.param1 >= 0 and it.param1 == int(it.param1)),
    ItemRule("jump repeat count >= -1", MissionResult.INVALID_PARAM2,
             lambda it: it.command == _DO_JUMP,
             lambda it: math.isfinite(it.param2) and it.param2 >= -1),
)
_COMMAND_VALUE_RULES: tuple[ItemRule, ...] = (_HOLD_TIME, *_FENCE_VALUE_RULES, *_JUMP_RULES)


def rules_for(mission_commands: MissionCommands = MISSION_COMMANDS,
              location_frames: AbstractSet[int] | None = None,
              nan_params: NanParams | None = None,
              location_alt_max: float | None = None,
              lat_lon_range_check: bool = True,
              command_frames: Mapping[int, AbstractSet[int]] | None = None,
              autocontinue_required: bool = False,
              frame_lists_all_plans: bool = False,
              value_rules: str = "spec") -> tuple[ItemRule, ...]:
    """The spec rules with another set (or frame table) of mission commands (None: any
    command, see `command_rules`), other frames for items with a location (`frame_rules`),
    params that may be NaN (`param_rules`), an altitude cap (`altitude_rules`), and without
    the latitude/longitude range check (`lat_lon_range_check=False`: PX4 takes them as sent),
    with per-command frames and autocontinue required (`command_frame_rules`), and the frame
    table deciding fence and rally items too (`frame_lists_all_plans`, `command_rules`), and
    another autopilot's checks of param values (`value_rules`, a VALUE_RULES key)."""
    lat_lon = _LAT_LON_RULES if lat_lon_range_check else ()
    finite, values = VALUE_RULES[value_rules]
    return (*param_rules(nan_params), *command_rules(mission_commands, frame_lists_all_plans),
            *command_frame_rules(command_frames, autocontinue_required), *frame_rules(location_frames),
            *_FIELD_RULES, *lat_lon, *finite, *altitude_rules(location_alt_max), *values)


# PX4 v1.16.0 parse_mavlink_mission_item (P28): no check of a hold time, a jump or an altitude;
# a region of interest's mode must be one its frame knows (L1480-1491: global frames
# MAV_ROI_LOCATION or NONE; L1574-1581: MAV_FRAME_MISSION NONE, WPNEXT or WPINDEX)
_PX4_ROI = ItemRule("region-of-interest mode known for the frame", MissionResult.INVALID_PARAM1,
                    lambda it: _in_mission(it) and it.command in _ROI_COMMANDS,
                    lambda it: i32(it.param1) in ((0, 1, 2) if it.frame == FRAME_MISSION else (0, 3)))
# ArduCopter (531699d6): a waypoint's hold time is a uint16 (AP_Mission.cpp L1104-1106:
# INVALID_PARAM1 outside 0..65535); DO_JUMP's target is a uint16 and must name an item after
# home (MissionItemProtocol_Waypoints.cpp L40-44: target 0 gets MAV_MISSION_ERROR; a target past
# the upload's end too, which one item cannot show); its repeat count is not checked
_AP_HOLD = ItemRule("waypoint hold time within 0..65535 s", MissionResult.INVALID_PARAM1,
                    lambda it: it.command == _NAV_WAYPOINT and _in_mission(it),
                    lambda it: math.isnan(it.param1) or 0 <= it.param1 <= 65535)
_AP_JUMP = ItemRule("jump target after home", MissionResult.ERROR,
                    lambda it: it.command == _DO_JUMP and _in_mission(it),
                    lambda it: u16(it.param1) != 0)
# value_rules -> (the altitude rule, the per-command value rules)
VALUE_RULES: dict[str, tuple[tuple[ItemRule, ...], tuple[ItemRule, ...]]] = {
    "spec": ((_ALTITUDE_FINITE,), _COMMAND_VALUE_RULES),
    "px4": ((), (*_FENCE_VALUE_RULES, _PX4_ROI)),
    "ardupilot": ((_ALTITUDE_FINITE,), (_AP_HOLD, *_FENCE_VALUE_RULES, _AP_JUMP)),
    "ardupilot-plane": ((_ALTITUDE_FINITE,), (*_FENCE_VALUE_RULES, _AP_JUMP)),    # no hold time kept
}

SPEC_RULES: tuple[ItemRule, ...] = rules_for(MISSION_COMMANDS)


def first_defect(item: MissionItem, rules: tuple[ItemRule, ...] = SPEC_RULES) -> ItemRule | None:
    """The first rule `item` breaks, or None if the vehicle accepts it."""
    for rule in rules:
        if rule.applies(item) and not rule.holds(item):
            return rule
    return None
