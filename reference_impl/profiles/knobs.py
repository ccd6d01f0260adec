"""Every knob a profile file may set: its name, where it lands, how its value is read.

A knob lands in `ServerBehaviour` (the mission engine), in its `Timings`, in
`VehicleConfig` (the node around it), in its `FlightRules` (FLIGHT: how the autopilot lets
itself be flown; parsers in flight_knobs.py), or in the item rules (RULES: each such knob is
one argument of `validation.rules_for`, which builds `ServerBehaviour.item_rules` from them
all). Values come from TOML; each parser turns one into the engine's type or raises
`ValueError` with what was expected, which the loader turns into a one-line `UsageError`
naming the file and the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

from ..mission.commands import by_name
from ..mission.constants import MISSION_COMMANDS, MissionResult
from ..mission.items import PLAN_TYPES, MissionType
from ..mission.store import STORAGE_FORMS
from ..mission.validation import VALUE_RULES, CommandList
from ..wire.dialect import mavlink as _d
from . import flight_knobs as fk

BEHAVIOUR, TIMINGS, CONFIG, RULES, FLIGHT = "behaviour", "timings", "config", "rules", "flight"
_TYPE_BY_NAME = {t.label: t for t in PLAN_TYPES}
_FRAME_BY_NAME = {e.name.removeprefix("MAV_FRAME_"): value for value, e in _d.enums["MAV_FRAME"].items()
                  if not e.name.endswith("_ENUM_END")}


@dataclass(frozen=True)
class Knob:
    name: str
    where: str                       # BEHAVIOUR | TIMINGS | CONFIG | RULES | FLIGHT
    field: str                       # the dataclass field it sets
    parse: Callable[[Any], Any]      # TOML value -> engine value (ValueError if bad)
    doc: str


def _bool(v: Any) -> bool:
    if not isinstance(v, bool):
        raise ValueError(f"expected true or false, got {v!r}")
    return v


def _seconds(v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"expected a number of seconds > 0, got {v!r}")
    return float(v)


def _seconds_or_none(v: Any) -> float | None:
    return None if v == "none" else _seconds(v)


def _count(low: int, high: int) -> Callable[[Any], int]:
    def parse(v: Any) -> int:
        if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
            raise ValueError(f"expected a whole number in {low}..{high}, got {v!r}")
        return v
    return parse


def _result(v: Any) -> MissionResult:
    try:
        return MissionResult[str(v).upper()]
    except KeyError:
        raise ValueError(f"expected a MAV_MISSION_RESULT name (e.g. ERROR, DENIED), got {v!r}") from None


def _result_or_none(v: Any) -> MissionResult | None:
    return None if v == "none" else _result(v)


def _types(v: Any) -> frozenset[MissionType]:
    if not isinstance(v, list) or not all(isinstance(x, str) and x in _TYPE_BY_NAME for x in v):
        raise ValueError(f"expected a list of plan types from {sorted(_TYPE_BY_NAME)}, got {v!r}")
    return frozenset(_TYPE_BY_NAME[x] for x in v)


def _capacity(v: Any) -> dict[MissionType, int]:
    if not isinstance(v, dict) or set(v) != set(_TYPE_BY_NAME):
        raise ValueError(f"expected a table with keys {sorted(_TYPE_BY_NAME)}, got {v!r}")
    parse = _count(0, 0xFFFF)
    return {_TYPE_BY_NAME[k]: parse(n) for k, n in v.items()}


def _value_rules(v: Any) -> str:
    if v not in VALUE_RULES:
        raise ValueError(f"expected one of {sorted(VALUE_RULES)}, got {v!r}")
    return v


def _storage(v: Any) -> str:
    if v not in STORAGE_FORMS:
        raise ValueError(f"expected one of {sorted(STORAGE_FORMS)}, got {v!r}")
    return v


def _text(v: Any) -> str:
    if not isinstance(v, str) or len(v.encode()) > 50:
        raise ValueError(f"expected a string of at most 50 bytes (a STATUSTEXT), got {v!r}")
    return v


def _unknown_commands(v: Any) -> frozenset[int] | None:
    """accept_unknown_commands = true: mission items with any command are accepted (fence
    and rally items must still carry their own commands)."""
    return None if _bool(v) else MISSION_COMMANDS


def _command_value(v: Any) -> int:
    """A MAV_CMD by its upstream name (with or without MAV_CMD_) or by number; a number need
    not be in common.xml (an autopilot's own dialect has more, e.g. ardupilotmega.xml)."""
    if isinstance(v, str):
        facts = by_name(v)
        if facts is None:
            raise ValueError(f"{v!r} is no MAV_CMD of the upstream common.xml (give its number instead)")
        return facts.value
    return _count(0, 0xFFFF)(v)


def _values(v: Any, what: str, parse: Callable[[Any], int]) -> list[int]:
    if not isinstance(v, list) or not v:
        raise ValueError(f"expected a non-empty list of {what}, got {v!r}")
    values = [parse(x) for x in v]
    if len(set(values)) != len(values):
        twice = next(x for x, n in zip(v, values) if values.count(n) > 1)
        raise ValueError(f"{twice!r} is listed twice")
    return values


def _frame_value(v: Any) -> int:
    """A MAV_FRAME by name (with or without MAV_FRAME_) or by number."""
    if isinstance(v, str):
        value = _FRAME_BY_NAME.get(v.upper().removeprefix("MAV_FRAME_"))
        if value is None:
            raise ValueError(f"{v!r} is no MAV_FRAME of the upstream common.xml")
        return value
    return _count(0, 255)(v)


def _frames(v: Any) -> frozenset[int]:
    """location_frames = [MAV_FRAME names or numbers]."""
    return frozenset(_values(v, "MAV_FRAME names or numbers", _frame_value))


def _command_set(v: Any) -> frozenset[int]:
    """[MAV_CMD names or numbers]."""
    return frozenset(_values(v, "MAV_CMD names or numbers", _command_value))


def _mission_commands(v: Any) -> frozenset[int] | tuple[CommandList, ...]:
    """mission_commands = [names or numbers]: the mission commands the vehicle stores, in any
    frame; or [{frames = [...], commands = [...]}, ...]: one list per set of frames (a
    mission item in a frame no list has gets UNSUPPORTED_FRAME). Any other command in a
    mission upload gets MAV_MISSION_UNSUPPORTED."""
    what = "MAV_CMD names or numbers"
    if not (isinstance(v, list) and v and all(isinstance(x, dict) for x in v)):
        return frozenset(_values(v, f"{what} (or of tables with frames and commands)", _command_value))
    table, seen = [], set()
    for i, entry in enumerate(v):
        if set(entry) != {"frames", "commands"}:
            raise ValueError(f"list {i}: expected the keys frames and commands, got {sorted(entry)}")
        try:
            frames, commands = _frames(entry["frames"]), _values(entry["commands"], what, _command_value)
        except ValueError as exc:
            raise ValueError(f"list {i}: {exc}") from None
        if frames & seen:
            raise ValueError(f"list {i}: frame {min(frames & seen)} is in an earlier list too")
        seen |= frames
        table.append(CommandList(frames, frozenset(commands)))
    return tuple(table)


def _nan_params(v: Any) -> dict[int, frozenset[int]]:
    """nan_params = {COMMAND = [params], ...}: the params (1-4) of each mission command (a
    MAV_CMD name, or its number quoted) that may be NaN; {} = none may."""
    if not isinstance(v, dict):
        raise ValueError(f"expected a table of MAV_CMD names -> lists of params 1-4, got {v!r}")
    table: dict[int, frozenset[int]] = {}
    for key, params in v.items():
        command = _command_value(int(key) if key.isdigit() else key)
        if command in table:
            raise ValueError(f"{key!r}: command {command} is listed twice")
        try:
            table[command] = frozenset(_values(params, "params 1-4", _count(1, 4)))
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None
    return table


def _command_frames(v: Any) -> dict[int, frozenset[int]]:
    """command_frames = {COMMAND = [frames], ...}: the only frames each listed mission command
    (a MAV_CMD name, or its number quoted) may use."""
    if not isinstance(v, dict) or not v:
        raise ValueError(f"expected a table of MAV_CMD names -> lists of MAV_FRAME names or numbers, got {v!r}")
    table: dict[int, frozenset[int]] = {}
    for key, frames in v.items():
        command = _command_value(int(key) if key.isdigit() else key)
        if command in table:
            raise ValueError(f"{key!r}: command {command} is listed twice")
        try:
            table[command] = _frames(frames)
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None
    return table


_MESSAGE_NAMES = frozenset(cls.msgname for cls in _d.mavlink_map.values())


def _message_names(v: Any) -> frozenset[str]:
    """[MAVLink message names], e.g. ["MISSION_ITEM_INT", "COMMAND_LONG"]."""
    def known(name: Any) -> str:
        if not isinstance(name, str) or name.upper() not in _MESSAGE_NAMES:
            raise ValueError(f"{name!r} is no message of the dialect (e.g. MISSION_ITEM_INT, COMMAND_LONG)")
        return name.upper()
    return frozenset(_values(v, "MAVLink message names", known))


_MAV_TYPE_BY_NAME = {e.name.removeprefix("MAV_TYPE_"): value for value, e in _d.enums["MAV_TYPE"].items()
                     if not e.name.endswith("_ENUM_END")}


def _mav_type(v: Any) -> int:
    """vehicle_type = a MAV_TYPE by name (with or without MAV_TYPE_, e.g. "FIXED_WING") or number."""
    if isinstance(v, str):
        value = _MAV_TYPE_BY_NAME.get(v.upper().removeprefix("MAV_TYPE_"))
        if value is None:
            raise ValueError(f"{v!r} is no MAV_TYPE of the upstream common.xml (e.g. QUADROTOR, FIXED_WING, "
                             "VTOL_FIXEDROTOR, GROUND_ROVER; or give its number)")
        return value
    return _count(0, 255)(v)


def _metres(v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ValueError(f"expected a number of metres > 0, got {v!r}")
    return float(v)


_KNOBS = (
    # timings
    Knob("default_timeout", TIMINGS, "default_timeout", _seconds, "s: response timeout (spec 1.5)"),
    Knob("item_timeout", TIMINGS, "item_timeout", _seconds, "s: the vehicle re-requests a missing item after this (spec 0.25)"),
    Knob("max_retries", TIMINGS, "max_retries", _count(0, 1000), "resends of one request before giving up (spec 5)"),
    Knob("protocol_timeout", TIMINGS, "protocol_timeout", _seconds_or_none,
         "s without any message from the partner after which an upload is given up; \"none\": after max_retries"),
    # behaviour
    Knob("retry_cap", BEHAVIOUR, "retry_cap", _bool, "resends are capped at max_retries (false: until protocol_timeout)"),
    Knob("capacity", BEHAVIOUR, "capacity", _capacity, "most items per plan type; more gets NO_SPACE"),
    Knob("supported_types", BEHAVIOUR, "supported_types", _types, "plan types stored; others get UNSUPPORTED"),
    Knob("request_int", BEHAVIOUR, "request_int", _bool, "request items with MISSION_REQUEST_INT (false: MISSION_REQUEST)"),
    Knob("accept_unknown_commands", RULES, "mission_commands", _unknown_commands,
         "mission items with commands the vehicle does not know are accepted (skipped when flown)"),
    Knob("mission_commands", RULES, "mission_commands", _mission_commands,
         "the mission commands stored (MAV_CMD names or numbers), or one list per set of frames "
         "([{frames, commands}]: other frames get UNSUPPORTED_FRAME); others get UNSUPPORTED "
         "(default: every mission command of the upstream common.xml, in any frame)"),
    Knob("frame_lists_all_plans", RULES, "frame_lists_all_plans", _bool,
         "with mission_commands as one list per set of frames: the lists decide fence and rally "
         "items too (their commands must be in the frame's list; other frames: UNSUPPORTED_FRAME)"),
    Knob("location_frames", RULES, "location_frames", _frames,
         "frames a mission item whose command has a location may use (others: UNSUPPORTED_FRAME); "
         "the frame of an item without one is not checked (default: global frames or "
         "MAV_FRAME_MISSION for every item, a global frame for a destination)"),
    Knob("nan_params", RULES, "nan_params", _nan_params,
         "which params (1-4) of which mission commands may be NaN ({COMMAND = [params]}); any other "
         "NaN, and +-inf in any, gets INVALID_PARAMn (the first bad n) before any other check "
         "(default: NaN anywhere means \"use the default\"; +-inf refused after command and frame)"),
    Knob("location_alt_max", RULES, "location_alt_max", _metres,
         "m: a mission item whose command has a location needs a finite altitude below this in "
         "magnitude (else INVALID_PARAM7; default: a destination's altitude need only be finite)"),
    Knob("command_frames", RULES, "command_frames", _command_frames,
         "the only frames each listed mission command may use ({COMMAND = [frames]}; others: "
         "UNSUPPORTED_FRAME, checked right after the command)"),
    Knob("autocontinue_required", RULES, "autocontinue_required", _bool,
         "a mission item with autocontinue 0 gets UNSUPPORTED, checked with the command"),
    Knob("value_rules", RULES, "value_rules", _value_rules,
         "which checks of param values refuse an item: spec (a finite altitude for a destination, a "
         "hold time >= 0, a whole jump target >= 0 and a repeat count >= -1, a fence polygon's vertex "
         "count and a circle's radius), px4 (the fence checks and a region of interest's mode only) or "
         "ardupilot (the spec's but a hold time within 0..65535 s, a jump target other than 0, MAV_MISSION_"
         "ERROR, and no check of a repeat count), or ardupilot-plane (those but no hold time check)"),
    Knob("lat_lon_range_check", RULES, "lat_lon_range_check", _bool,
         "a mission item in a global frame needs a latitude within +-90 and a longitude within "
         "+-180 degrees (else INVALID_PARAM5_X / INVALID_PARAM6_Y); false: taken as sent"),
    Knob("idle_reply", BEHAVIOUR, "idle_reply", _result_or_none, "MISSION_ACK for a stray item/request in idle (\"none\": silence)"),
    Knob("reack_last_item", BEHAVIOUR, "reack_last_item", _bool, "a late copy of the last item draws ACCEPTED again"),
    Knob("notify_upload_give_up", BEHAVIOUR, "notify_upload_give_up", _bool,
         "a given-up upload is ended with MISSION_ACK OPERATION_CANCELLED"),
    Knob("give_up_statustext", BEHAVIOUR, "give_up_statustext", _text, "STATUSTEXT sent when an upload is given up (\"\": none)"),
    Knob("current_period", BEHAVIOUR, "current_period", _seconds_or_none,
         "s between streamed MISSION_CURRENTs (\"none\": MISSION_CURRENT is never sent, not even on a change)"),
    Knob("mission_type_ignored", BEHAVIOUR, "mission_type_ignored", _bool,
         "every mission message is about the mission, whatever its mission_type: replies carry 0, and a "
         "fence, rally or ALL request, clear or upload reads, clears or replaces the mission"),
    Knob("target_system_only", BEHAVIOUR, "target_system_only", _bool,
         "a mission message is for the vehicle only when its target_system is the vehicle's own: no "
         "broadcast (0), and target_component is not read"),
    Knob("atomic_upload", BEHAVIOUR, "atomic_upload", _bool, "an upload replaces the plan whole after its last item"),
    Knob("item0_clears_plan", BEHAVIOUR, "item0_clears_plan", _bool,
         "with atomic_upload = false: MISSION_COUNT leaves the stored plan alone, item 0 clears it and each "
         "item is appended (false: MISSION_COUNT truncates the plan, items overwrite it in place)"),
    Knob("count0_opens_upload", BEHAVIOUR, "count0_opens_upload", _bool,
         "MISSION_COUNT 0 is answered with a MISSION_REQUEST for item 0, which is then the last "
         "(false: it clears the plan, ACCEPTED)"),
    Knob("upload_counters_persist", BEHAVIOUR, "upload_counters_persist", _bool,
         "the upload's item counter outlives the upload: an item with none running is taken if its seq is "
         "the counter's (after n items: seq n is appended, ACCEPTED); another seq is INVALID_SEQUENCE"),
    Knob("transfer_owner", BEHAVIOUR, "transfer_owner", _bool,
         "a transfer belongs to the GCS that opened it (false: any GCS's message acts on it, replies go to the sender)"),
    Knob("upload_timers", BEHAVIOUR, "upload_timers", _bool,
         "the vehicle times an upload (re-requests, gives up); false: no timer at all, a stalled upload "
         "is never re-requested and never ended"),
    Knob("nack_ends_upload", BEHAVIOUR, "nack_ends_upload", _bool, "a refused item ends the upload"),
    Knob("out_of_sequence_reply", BEHAVIOUR, "out_of_sequence_reply", _result_or_none,
         "MISSION_ACK for an out-of-sequence item (\"none\": dropped silently)"),
    Knob("rerequest_gap", BEHAVIOUR, "rerequest_gap", _bool, "an item past the expected one draws an immediate re-request"),
    Knob("honour_cancel_upload", BEHAVIOUR, "honour_cancel_upload", _bool, "an error MISSION_ACK from the GCS ends its upload"),
    Knob("error_ack_ends_upload", BEHAVIOUR, "error_ack_ends_upload", _bool,
         "error codes other than OPERATION_CANCELLED end the upload too (false: ignored)"),
    Knob("busy_reply", BEHAVIOUR, "busy_reply", _result, "MISSION_ACK for another GCS while a transfer holds the plan type"),
    Knob("unknown_type_count0", BEHAVIOUR, "unknown_type_count0", _bool,
         "MISSION_REQUEST_LIST for an unknown mission_type draws MISSION_COUNT 0 (false: UNSUPPORTED)"),
    Knob("set_current_failure_text", BEHAVIOUR, "set_current_failure_text", _bool,
         "a MISSION_SET_CURRENT that cannot be done draws a STATUSTEXT (false: nothing)"),
    Knob("set_current_command", BEHAVIOUR, "set_current_command", _bool,
         "MAV_CMD_DO_SET_MISSION_CURRENT is handled (false: MAV_RESULT_UNSUPPORTED)"),
    Knob("foreign_type_item_reply", BEHAVIOUR, "foreign_type_item_reply", _result_or_none,
         "MISSION_ACK for an item of another plan type during an upload (\"none\": a stray)"),
    Knob("follow_gcs_int_mode", BEHAVIOUR, "follow_gcs_int_mode", _bool,
         "requests follow the GCS's item form; MISSION_ACK UNSUPPORTED flips int/float"),
    Knob("partial_write", BEHAVIOUR, "partial_write", _bool, "MISSION_WRITE_PARTIAL_LIST is supported"),
    Knob("stateful_download", BEHAVIOUR, "stateful_download", _bool,
         "a download is a transfer the GCS's ACK ends (false: requests answered any time, ACK ignored)"),
    Knob("sequential_download", BEHAVIOUR, "sequential_download", _bool,
         "requests must come in order (seq-1 resends; other seqs end the download with ERROR)"),
    Knob("deny_reads_during_upload", BEHAVIOUR, "deny_reads_during_upload", _bool,
         "reads (REQUEST_LIST, REQUEST, WRITE_PARTIAL_LIST) get DENIED while the type uploads"),
    Knob("download_current_flag", BEHAVIOUR, "download_current_flag", _bool,
         "a downloaded mission item has current=1 exactly when it is the current item (false: never)"),
    Knob("home_at_seq0", BEHAVIOUR, "home_at_seq0", _bool, "mission item 0 is the vehicle's home"),
    Knob("item_storage", BEHAVIOUR, "item_storage", _storage,
         "how items are kept: exact, compact15 (ArduPilot's 15-byte record), compact15-plane "
         "(ArduPlane's: a waypoint keeps its radius and pass-by distance, not its hold time), "
         "float32-cm (INAV's waypoint record), px4 (PX4's mission_item_s: params it has no field "
         "for come back 0, flags 0 or 1, a yaw wrapped to [0, 360)), ardupilot (ArduCopter's "
         "and ArduRover's per-command packing of the 15-byte record, fence items rebuilt) or "
         "ardupilot-plane (ArduPlane's: a waypoint keeps its radius and pass-by distance)"),
    Knob("opaque_id_fields", BEHAVIOUR, "opaque_id_fields", _bool, "plan ids are reported (false: the older dialect)"),
    Knob("clear_all_supported", BEHAVIOUR, "clear_all_supported", _bool, "MISSION_CLEAR_ALL with MAV_MISSION_TYPE_ALL works"),
    Knob("clear_while_flying", BEHAVIOUR, "clear_while_flying", _bool, "the mission may be cleared while flown"),
    Knob("set_current_only_idle", BEHAVIOUR, "set_current_only_idle", _bool, "MISSION_SET_CURRENT is refused during a transfer"),
    Knob("item_reached_repeats", BEHAVIOUR, "item_reached_repeats", _count(1, 100),
         "MISSION_ITEM_REACHED is sent this many times, 1 s apart"),
    Knob("item_reached_one_slot", BEHAVIOUR, "item_reached_one_slot", _bool,
         "MISSION_ITEM_REACHED waits in one slot until the next send (0.25 s): an item reached meanwhile "
         "(a DO command right after a waypoint) replaces it, so only the later one is reported"),
    Knob("item_reached_unreported", BEHAVIOUR, "item_reached_unreported", _command_set,
         "commands (MAV_CMD names or numbers) whose completion sends no MISSION_ITEM_REACHED "
         "(a pending one in the slot stays)"),
    Knob("mavlink2_types", BEHAVIOUR, "mavlink2_types", _types, "plan types whose transfers need MAVLink 2"),
    Knob("legacy_warnings", BEHAVIOUR, "legacy_warnings", _bool, "STATUSTEXT warning for MISSION_REQUEST / MISSION_ITEM"),
    # vehicle
    Knob("autopilot", CONFIG, "autopilot", _count(0, 255), "HEARTBEAT.autopilot (MAV_AUTOPILOT)"),
    Knob("custom_mode_idle", CONFIG, "custom_mode_idle", _count(0, 0xFFFFFFFF),
         "HEARTBEAT.custom_mode when not flying the mission (the autopilot's own mode number), "
         "for a vehicle without modes"),
    Knob("custom_mode_mission", CONFIG, "custom_mode_mission", _count(0, 0xFFFFFFFF),
         "HEARTBEAT.custom_mode while flying the mission (the autopilot's own mode number), "
         "for a vehicle without modes"),
    Knob("single_peer_link", CONFIG, "single_peer_link", _bool,
         "the GCS link is bound to the first peer address: other senders are never read"),
    Knob("ignored_messages", CONFIG, "ignored_messages", _message_names,
         "messages (MAVLink names) the autopilot has no handler for: dropped unread, never answered"),
    # --- the vehicle model: what flies, and how the autopilot flies it (issue 23) ---
    Knob("vehicle_type", CONFIG, "vehicle_type", _mav_type,
         "HEARTBEAT.type (MAV_TYPE, by name or number); its class (vehicle_class.py) says how it flies: "
         "a ground vehicle never climbs (default QUADROTOR)"),
    Knob("cruise_speed", CONFIG, "speed", fk.speed, "m/s: the flight's ground speed between items (default 10)"),
    Knob("params", CONFIG, "params", fk.params,
         "the parameters PARAM_REQUEST_READ is answered for ({NAME = value} or {NAME = {value, type}}); "
         "any other name gets no answer (default: none)"),
    Knob("modes", FLIGHT, "modes", fk.modes,
         "the flight modes ([{name, number, does}]: HEARTBEAT.custom_mode and what the vehicle does in "
         "it: manual, mission, guided, hold, rtl, land, takeoff); default: none, DO_SET_MODE is UNSUPPORTED "
         "and custom_mode_idle / custom_mode_mission say the HEARTBEAT's mode"),
    Knob("set_mode_params", FLIGHT, "set_mode_params", fk.set_mode_params,
         "how MAV_CMD_DO_SET_MODE names a mode: custom-mode (param2 is its number) or px4 (param2 main, "
         "param3 sub mode: number = main << 16 | sub << 24)"),
    Knob("boot_mode", FLIGHT, "boot_mode", fk.mode_name, "the mode the vehicle starts in (needed with modes)"),
    Knob("mission_end_mode", FLIGHT, "mission_end_mode", fk.mode_or_stay,
         "the mode the vehicle switches to when its mission ends in the air (\"stay\": its mission mode, holding)"),
    Knob("command_refusal", FLIGHT, "refusal", fk.command_result,
         "COMMAND_ACK result of a refused mode change, arming, disarming or start (default FAILED)"),
    Knob("arming", FLIGHT, "arming", fk.flag,
         "the vehicle flies only armed and takes MAV_CMD_COMPONENT_ARM_DISARM (false: UNSUPPORTED; it "
         "counts as armed while it flies)"),
    Knob("no_arming_modes", FLIGHT, "no_arming_modes", fk.mode_names, "modes in which arming is refused"),
    Knob("landing_required", FLIGHT, "landing_required", fk.flag,
         "a mission without a landing item cannot be flown: arming in the mission mode and MISSION_START "
         "are refused, and storing one draws the plan-refused STATUSTEXT"),
    Knob("land_start_blocks_arming", FLIGHT, "land_start_blocks_arming", fk.flag,
         "a mission with DO_LAND_START refuses arming (arm-refused-plan)"),
    Knob("mission_start", FLIGHT, "mission_start", fk.mission_start,
         "what MAV_CMD_MISSION_START does: flies (at once), mission-mode (params 1-2 must be 0, else "
         "DENIED; the mission mode, flown once armed) or mission-mode-and-arm (a valid plan and param1 "
         "within it, else DENIED; the mission mode, and arms)"),
    Knob("takeoff_first", FLIGHT, "takeoff_first", fk.flag,
         "the mission mode, entered armed on the ground, needs a take-off as the next navigation item "
         "(else refused, missing-takeoff STATUSTEXT)"),
    Knob("takeoff_command", FLIGHT, "takeoff_command", fk.takeoff_command,
         "what MAV_CMD_NAV_TAKEOFF does: unsupported, guided-climb (armed on the ground in a guided mode: "
         "climbs to param7), takeoff-mode (switches to the takeoff mode) or refused"),
    Knob("takeoff_altitude", FLIGHT, "takeoff_altitude", fk.metres,
         "m above home a take-off mode or command climbs to when it names no altitude (default 10)"),
    Knob("rtl_lands", FLIGHT, "rtl_lands", fk.flag,
         "the return mode lands at home (false: it stays there, loitering; a ground vehicle stops)"),
    Knob("disarm_after_landing", FLIGHT, "disarm_after_landing", fk.seconds_or_none,
         "s after touching down the vehicle disarms by itself (\"none\": it stays armed)"),
    Knob("disarm_idle_after", FLIGHT, "disarm_idle_after", fk.seconds_or_none,
         "s armed on the ground without taking off before it disarms by itself (\"none\": never)"),
    Knob("disarm_resets_mission", FLIGHT, "disarm_resets_mission", fk.disarm_resets_mission,
         "a disarm makes the first item current again: never, always or outside-mission-mode"),
    Knob("statustexts", FLIGHT, "texts", fk.texts,
         "the autopilot's words for its refusals and news ({event = text}; events in flight_rules.py "
         "TEXT_EVENTS; {mode} is the current mode's name); default: none"),
)

KNOBS: dict[str, Knob] = {k.name: k for k in _KNOBS}
assert len(KNOBS) == len(_KNOBS), "duplicate knob name"
