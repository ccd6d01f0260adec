"""Protocol numbers the engines speak in (MAV_MISSION_RESULT, MISSION_STATE, commands).

Facts from the MAVLink definitions (our dialect carries the same values); kept here as
IntEnums so engine code and reports read as words, not numbers. `Cmd` names only the
commands the engines act on; which commands a plan may hold comes from the upstream XML
(commands.py).
"""

from enum import IntEnum

from .commands import DESTINATION_COMMANDS, PLAN_COMMANDS


class MissionResult(IntEnum):
    """MAV_MISSION_RESULT: the `type` of a MISSION_ACK."""

    ACCEPTED = 0
    ERROR = 1
    UNSUPPORTED_FRAME = 2
    UNSUPPORTED = 3
    NO_SPACE = 4
    INVALID = 5
    INVALID_PARAM1 = 6
    INVALID_PARAM2 = 7
    INVALID_PARAM3 = 8
    INVALID_PARAM4 = 9
    INVALID_PARAM5_X = 10
    INVALID_PARAM6_Y = 11
    INVALID_PARAM7 = 12
    INVALID_SEQUENCE = 13
    DENIED = 14
    OPERATION_CANCELLED = 15

    @classmethod
    def describe(cls, value: int) -> str:
        try:
            return cls(value).name
        except ValueError:
            return f"unknown result {value}"


class MissionState(IntEnum):
    """MISSION_STATE, reported in MISSION_CURRENT.mission_state."""

    UNKNOWN = 0
    NO_MISSION = 1
    NOT_STARTED = 2
    ACTIVE = 3
    PAUSED = 4
    COMPLETE = 5


class CommandResult(IntEnum):
    """MAV_RESULT, carried in COMMAND_ACK."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4
    IN_PROGRESS = 5
    CANCELLED = 6
    NOT_IN_CONTROL = 10


class Severity(IntEnum):
    """MAV_SEVERITY for STATUSTEXT."""

    EMERGENCY = 0
    ALERT = 1
    CRITICAL = 2
    ERROR = 3
    WARNING = 4
    NOTICE = 5
    INFO = 6
    DEBUG = 7


class Cmd(IntEnum):
    """The MAV_CMD values the reference implementation itself acts on or validates by name."""

    NAV_WAYPOINT = 16
    NAV_LOITER_UNLIM = 17
    NAV_LOITER_TURNS = 18
    NAV_LOITER_TIME = 19
    NAV_RETURN_TO_LAUNCH = 20
    NAV_LAND = 21
    NAV_TAKEOFF = 22
    NAV_LOITER_TO_ALT = 31
    NAV_ROI = 80
    NAV_SPLINE_WAYPOINT = 82
    NAV_VTOL_TAKEOFF = 84
    NAV_VTOL_LAND = 85
    NAV_DELAY = 93
    CONDITION_DELAY = 112
    CONDITION_DISTANCE = 114
    CONDITION_YAW = 115
    DO_SET_MODE = 176
    DO_JUMP = 177
    DO_CHANGE_SPEED = 178
    DO_SET_HOME = 179
    DO_SET_SERVO = 183
    DO_SET_ROI = 201
    DO_LAND_START = 189
    DO_SET_MISSION_CURRENT = 224
    MISSION_START = 300
    COMPONENT_ARM_DISARM = 400
    GET_HOME_POSITION = 410
    SET_MESSAGE_INTERVAL = 511
    REQUEST_MESSAGE = 512
    NAV_FENCE_RETURN_POINT = 5000
    NAV_FENCE_POLYGON_VERTEX_INCLUSION = 5001
    NAV_FENCE_POLYGON_VERTEX_EXCLUSION = 5002
    NAV_FENCE_CIRCLE_INCLUSION = 5003
    NAV_FENCE_CIRCLE_EXCLUSION = 5004
    NAV_RALLY_POINT = 5100
    REQUEST_OPERATOR_CONTROL = 32100


FENCE_COMMANDS = frozenset({
    Cmd.NAV_FENCE_RETURN_POINT, Cmd.NAV_FENCE_POLYGON_VERTEX_INCLUSION,
    Cmd.NAV_FENCE_POLYGON_VERTEX_EXCLUSION, Cmd.NAV_FENCE_CIRCLE_INCLUSION,
    Cmd.NAV_FENCE_CIRCLE_EXCLUSION,
})
RALLY_COMMANDS = frozenset({Cmd.NAV_RALLY_POINT})
# Mission commands the reference vehicle accepts: every command the upstream MAV_CMD enum
# defines for a mission (commands.py, generated from the XML), not a hand list; a profile
# narrows it (the `mission_commands` knob).
MISSION_COMMANDS: frozenset[int] = PLAN_COMMANDS
# Commands whose x/y/z are a position the vehicle flies to (XML hasLocation and isDestination).
POSITIONAL_COMMANDS: frozenset[int] = DESTINATION_COMMANDS
