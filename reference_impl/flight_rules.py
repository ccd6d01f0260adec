"""How an autopilot lets itself be flown, as data: flight modes, arming, starting a mission,
take-off, landing, return (issue 23).

A real autopilot flies a mission only in the right mode, armed, and by its vehicle type's
rules; a GCS that gets this wrong leaves a vehicle armed in a mode it never meant (copter
GUIDED = 4 is ACRO on ArduPlane). `FlightRules` holds one autopilot's answers, each set by a
profile knob with its source (profiles/*.toml); `autopilot.py` acts on them. The default is
the spec vehicle as it always was: no flight modes (MAV_CMD_DO_SET_MODE is UNSUPPORTED), no
arming (it flies on MAV_CMD_MISSION_START and reports itself armed while it flies), no
return or landing commands.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from .mission.constants import CommandResult


class ModeKind(Enum):
    """What the vehicle does by itself in a mode (the flight model has no pilot)."""
    MANUAL = "manual"      # nothing: a pilot would fly it; the model holds where it is
    MISSION = "mission"    # flies the stored mission while armed (ArduPilot AUTO, PX4 AUTO.MISSION)
    GUIDED = "guided"      # holds; takes MAV_CMD_NAV_TAKEOFF when takeoff_command = "guided-climb"
    HOLD = "hold"          # stays where it is: hover, loiter, a rover's hold
    RTL = "rtl"            # back to home; lands there if rtl_lands (a ground vehicle stops there)
    LAND = "land"          # lands where it is
    TAKEOFF = "takeoff"    # climbs to the take-off altitude and holds there (PX4 AUTO.TAKEOFF, ArduPlane TAKEOFF)


@dataclass(frozen=True)
class Mode:
    name: str              # as the autopilot names it ("AUTO", "AUTO.MISSION")
    number: int            # HEARTBEAT.custom_mode in the autopilot's own numbering
    kind: ModeKind


# How MAV_CMD_DO_SET_MODE names a mode (param1 is base_mode, with MAV_MODE_FLAG_CUSTOM_MODE_ENABLED):
SET_MODE_ENCODINGS = ("custom-mode",   # param2 is the custom mode number (ArduPilot)
                      "px4")           # param2 main mode, param3 sub mode: custom = main << 16 | sub << 24
# What MAV_CMD_MISSION_START does:
MISSION_STARTS = ("flies",                  # flies the mission from the current item (the spec vehicle)
                  "mission-mode",           # params 1, 2 must be 0 (else DENIED); sets the mission mode,
                                            # which flies only armed (ArduPilot)
                  "mission-mode-and-arm")   # needs a valid plan and param1 in it (else DENIED); sets the
                                            # mission mode and arms (PX4)
# What MAV_CMD_NAV_TAKEOFF (as a command) does:
TAKEOFF_COMMANDS = ("unsupported",     # MAV_RESULT_UNSUPPORTED
                    "guided-climb",    # in a GUIDED mode, armed on the ground: climbs to param7 (ArduCopter)
                    "takeoff-mode",    # switches to the TAKEOFF mode, climbing to param7 (PX4)
                    "refused")         # refused (ArduPlane without a quadplane: MAV_RESULT_FAILED)
# When a disarm puts the mission back to its first item:
MISSION_RESETS = ("never", "always", "outside-mission-mode")
# The STATUSTEXTs a profile may give its autopilot's words for ({mode}: the current mode's name):
TEXT_EVENTS = (
    "arm-refused-mode",      # arming refused in this mode
    "arm-refused-plan",      # arming refused for the plan (no landing where one is required; DO_LAND_START)
    "plan-refused",          # a plan that cannot be flown was stored (no landing where one is required)
    "mission-start-refused",  # MAV_CMD_MISSION_START refused for want of a valid plan
    "disarm-refused",        # disarming refused in the air
    "missing-takeoff",       # the mission mode refused on the ground armed: the next item is no take-off
    "auto-disarmed",         # disarmed by itself after landing
    "idle-disarmed",         # disarmed by itself after idling armed on the ground
    "mission-complete",      # the last item is done, in the air
    "mission-landed",        # the mission ended with a landing
)


@dataclass(frozen=True)
class FlightRules:
    """One autopilot's way of being flown (knobs in profiles/knobs.py say what each is)."""
    modes: tuple[Mode, ...] = ()
    set_mode_params: str = "custom-mode"
    boot_mode: str = ""
    mission_end_mode: str = ""          # "": stays in its mission mode, holding where it ended
    refusal: CommandResult = CommandResult.FAILED   # the COMMAND_ACK of a mode, arming or start refused
    arming: bool = False                # flies only armed; COMPONENT_ARM_DISARM handled
    no_arming_modes: frozenset[str] = frozenset()
    landing_required: bool = False      # a plan without a landing item cannot be flown (arming, start)
    land_start_blocks_arming: bool = False   # a plan with DO_LAND_START refuses arming
    mission_start: str = "flies"
    takeoff_first: bool = False         # the mission mode, entered armed on the ground, needs a take-off next
    takeoff_command: str = "unsupported"
    takeoff_altitude: float = 10.0      # m above home: a take-off mode or command that names none
    rtl_lands: bool = True
    disarm_after_landing: float | None = None   # s after touching down, armed: disarms by itself
    disarm_idle_after: float | None = None      # s armed on the ground without taking off: disarms
    disarm_resets_mission: str = "never"
    texts: tuple[tuple[str, str], ...] = ()     # (event, STATUSTEXT)

    def __post_init__(self) -> None:
        names = [m.name for m in self.modes]
        if len(set(names)) != len(names) or len({m.number for m in self.modes}) != len(self.modes):
            raise ValueError("modes: each mode needs its own name and number")
        if self.modes and not self.boot_mode:
            raise ValueError("a mode table needs boot_mode (the mode the vehicle starts in)")
        for what, name in (("boot_mode", self.boot_mode), ("mission_end_mode", self.mission_end_mode),
                           *(("no_arming_modes", n) for n in sorted(self.no_arming_modes))):
            if name and name not in names:
                raise ValueError(f"{what}: {name!r} is not in the mode table ({', '.join(names) or 'none'})")
        checks = ((self.set_mode_params, SET_MODE_ENCODINGS, "set_mode_params"),
                  (self.mission_start, MISSION_STARTS, "mission_start"),
                  (self.takeoff_command, TAKEOFF_COMMANDS, "takeoff_command"),
                  (self.disarm_resets_mission, MISSION_RESETS, "disarm_resets_mission"))
        for value, allowed, what in checks:
            if value not in allowed:
                raise ValueError(f"{what} must be one of {', '.join(allowed)}, got {value!r}")
        if self.mission_start != "flies" and self.mode_of(ModeKind.MISSION) is None:
            raise ValueError(f"mission_start = {self.mission_start!r} needs a mission mode in the mode table")
        if self.takeoff_command == "takeoff-mode" and self.mode_of(ModeKind.TAKEOFF) is None:
            raise ValueError("takeoff_command = 'takeoff-mode' needs a takeoff mode in the mode table")
        unknown = {e for e, _ in self.texts} - set(TEXT_EVENTS)
        if unknown:
            raise ValueError(f"texts: unknown event {sorted(unknown)[0]!r} (known: {', '.join(TEXT_EVENTS)})")

    def mode_of(self, kind: ModeKind) -> Mode | None:
        """The first mode of that kind in the table."""
        return next((m for m in self.modes if m.kind is kind), None)

    def mode_named(self, name: str) -> Mode | None:
        return next((m for m in self.modes if m.name == name), None)

    def mode_numbered(self, number: int) -> Mode | None:
        return next((m for m in self.modes if m.number == number), None)

    def text(self, event: str) -> str:
        """The STATUSTEXT for `event`, "" for none."""
        return next((t for e, t in self.texts if e == event), "")
