"""What each MAV_CMD is, as the upstream XML says (commands_data.py), and the command sets
derived from it.

The vehicle's accepted mission commands used to be a hand list of 18; QGroundControl
missions carry ROI, camera and gimbal items too, and a vehicle that refuses them is no use
to a GCS test. So the spec vehicle takes every command the upstream definitions have (a
profile narrows that with the `mission_commands` knob, from its autopilot's source, per frame
where the autopilot has one list for global frames and another for MAV_FRAME_MISSION), and
"has a position" comes from the XML's `hasLocation` / `isDestination` attributes.
"""

from __future__ import annotations

from dataclasses import dataclass

from .commands_data import ROWS, SOURCE

__all__ = ["COMMANDS", "SOURCE", "CommandFacts", "DESTINATION_COMMANDS", "FENCE_PLAN_COMMANDS",
           "LOCATION_COMMANDS", "PLAN_COMMANDS", "RALLY_PLAN_COMMANDS", "by_name", "name_of"]

# The plan types' own commands: fence items (5000-5004) and rally points (5100) belong to
# those plans, never to a mission (MAVLink Mission Protocol, "Mission Types").
_FENCE_NAMES = ("NAV_FENCE_RETURN_POINT", "NAV_FENCE_POLYGON_VERTEX_INCLUSION",
                "NAV_FENCE_POLYGON_VERTEX_EXCLUSION", "NAV_FENCE_CIRCLE_INCLUSION",
                "NAV_FENCE_CIRCLE_EXCLUSION")
_RALLY_NAMES = ("NAV_RALLY_POINT",)
# Range markers, not commands: the XML describes each as "NOP - This command is only used
# to mark the upper limit of the ... commands in the enumeration".
_MARKER_NAMES = ("NAV_LAST", "CONDITION_LAST", "DO_LAST")


@dataclass(frozen=True)
class CommandFacts:
    """One MAV_CMD entry of the upstream XML."""

    value: int
    name: str                    # without the MAV_CMD_ prefix
    has_location: bool           # hasLocation: params 5-7 are latitude, longitude, altitude
    is_destination: bool         # isDestination: the vehicle goes there
    mission_only: bool           # missionOnly: meaningless as a COMMAND_LONG
    status: str                  # "", "deprecated", "superseded" or "wip"
    params: tuple[tuple[int, str, bool], ...]   # (index 1-7, label, reserved)

    def label(self, index: int) -> str:
        """The XML's label of param `index` (1-7), "" if it has none."""
        return next((label for i, label, _ in self.params if i == index), "")


COMMANDS: dict[int, CommandFacts] = {row[0]: CommandFacts(*row) for row in ROWS}
_BY_NAME: dict[str, CommandFacts] = {facts.name: facts for facts in COMMANDS.values()}


def by_name(name: str) -> CommandFacts | None:
    """The command called `name`, with or without its MAV_CMD_ prefix (None if unknown)."""
    return _BY_NAME.get(name.upper().removeprefix("MAV_CMD_"))


def name_of(value: int) -> str:
    """MAV_CMD_<NAME> for a command value, or "command <value>" when the XML has none."""
    facts = COMMANDS.get(value)
    return f"MAV_CMD_{facts.name}" if facts is not None else f"command {value}"


def _values(names: tuple[str, ...]) -> frozenset[int]:
    return frozenset(_BY_NAME[n].value for n in names)


FENCE_PLAN_COMMANDS = _values(_FENCE_NAMES)
RALLY_PLAN_COMMANDS = _values(_RALLY_NAMES)
# Every command a mission plan may hold as far as the definitions go: all MAV_CMD entries
# except the fence and rally plans' own, the range markers and the deprecated ones.
PLAN_COMMANDS: frozenset[int] = frozenset(
    facts.value for facts in COMMANDS.values()
    if facts.status != "deprecated" and facts.name not in _MARKER_NAMES
    and facts.value not in FENCE_PLAN_COMMANDS | RALLY_PLAN_COMMANDS)
# Params 5-7 are a location (latitude, longitude, altitude in a global frame).
LOCATION_COMMANDS: frozenset[int] = frozenset(f.value for f in COMMANDS.values() if f.has_location)
# ...which the vehicle flies to (a waypoint, a landing spot), not just looks at (an ROI).
DESTINATION_COMMANDS: frozenset[int] = frozenset(
    f.value for f in COMMANDS.values() if f.has_location and f.is_destination)
