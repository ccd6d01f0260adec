"""Builders and readers for the operator-control messages, and the XML's numbers.

One place builds MAV_CMD_REQUEST_OPERATOR_CONTROL, its COMMAND_ACK and CONTROL_STATUS, so the
param meanings are written down once. Values come from the dialect (`_d`); the request
timeout bounds come from the dialect XML's `minValue` / `maxValue` of param 3, not from a
hand copy.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

from ..mission.actions import Peer
from ..wire.dialect import XML_PATH
from ..wire.dialect import mavlink as _d

REQUEST_CONTROL = _d.MAV_CMD_REQUEST_OPERATOR_CONTROL
FLAG_SYSTEM_MANAGER = _d.GCS_CONTROL_STATUS_FLAGS_SYSTEM_MANAGER
FLAG_TAKEOVER_ALLOWED = _d.GCS_CONTROL_STATUS_FLAGS_TAKEOVER_ALLOWED
ACTION_RELEASE, ACTION_REQUEST = 0.0, 1.0   # param 1: "0: release control, 1: request control"
SECONDARY_NONE = (0,) * 10                  # gcs_secondary: "all zero in single-owner mode"


def _param_bounds(command: str, index: int) -> tuple[float, float]:
    """(minValue, maxValue) of a command param, as the dialect XML declares them."""
    for entry in ET.parse(XML_PATH).getroot().iter("entry"):
        if entry.get("name") == command:
            for param in entry.iter("param"):
                if param.get("index") == str(index):
                    return float(param.get("minValue")), float(param.get("maxValue"))
    raise LookupError(f"{command} param {index} has no bounds in {XML_PATH.name}")


# param 3 "Request timeout" (s): minValue / maxValue in the XML
TIMEOUT_MIN, TIMEOUT_MAX = _param_bounds("MAV_CMD_REQUEST_OPERATOR_CONTROL", 3)
DEFAULT_REQUEST_TIMEOUT = 10.0   # s: param 3 when a request leaves it 0 / NaN (QGC's default)
# "the requester GCS will only have 10 seconds to get control" (development.xml, 32100)
TAKEOVER_WINDOW = 10.0


def clamp_timeout(value: float) -> float:
    """Param 3 of a request as the manager applies it: within the XML's bounds; the default
    when absent (0, NaN, +-inf), since the field has no "not set" value of its own."""
    if not math.isfinite(value) or value <= 0:
        return DEFAULT_REQUEST_TIMEOUT
    return min(max(value, TIMEOUT_MIN), TIMEOUT_MAX)


def request_command(target: Peer, action: float, allow_takeover: bool, timeout: float, sysid: int,
                    confirmation: int = 0) -> Any:
    """COMMAND_LONG MAV_CMD_REQUEST_OPERATOR_CONTROL (params 1-4; 5-7 reserved, 0)."""
    return _d.MAVLink_command_long_message(target[0], target[1], REQUEST_CONTROL, confirmation,
                                          action, 1.0 if allow_takeover else 0.0, float(timeout),
                                          float(sysid), 0.0, 0.0, 0.0)


def command_ack(command: int, result: int, target: Peer) -> Any:
    return _d.MAVLink_command_ack_message(command, result, 0, 0, target[0], target[1])


def mission_ack(result: int, mission_type: int, target: Peer) -> Any:
    return _d.MAVLink_mission_ack_message(target[0], target[1], result, mission_type, 0)


def statustext(severity: int, text: str) -> Any:
    return _d.MAVLink_statustext_message(severity, text.encode()[:50], 0, 0)


def control_status(gcs_main: int, *, takeover_allowed: bool, system_manager: bool = True) -> Any:
    """CONTROL_STATUS in single-owner mode (`gcs_secondary` all zero)."""
    flags = (FLAG_SYSTEM_MANAGER if system_manager else 0) | (FLAG_TAKEOVER_ALLOWED if takeover_allowed else 0)
    return _d.MAVLink_control_status_message(flags, gcs_main, SECONDARY_NONE)


def is_request_control(msg: Any) -> bool:
    """A COMMAND_LONG or COMMAND_INT carrying MAV_CMD_REQUEST_OPERATOR_CONTROL."""
    return msg._type in ("COMMAND_LONG", "COMMAND_INT") and msg.command == REQUEST_CONTROL


def addressed_to(msg: Any, system: int, component: int) -> bool:
    """Target fields name us or broadcast (0); messages without them are broadcasts."""
    return (getattr(msg, "target_system", 0) in (0, system)
            and getattr(msg, "target_component", 0) in (0, component))
