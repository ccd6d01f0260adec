"""What the vehicle tells a GCS that asks about it: its home (HOME_POSITION) and the parameters
its profile lists (PARAM_VALUE), as real autopilots answer (issue 23).

A GCS lays a flight out from the vehicle's home and sizes its legs by the vehicle's acceptance
and loiter radii; a flight laid out from a position before home was set can be anywhere (a
real ArduPlane reported lat 0.0003, lon -0.0001 then). Both answers are sans-IO builders: the
vehicle node sends them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from .wire.dialect import mavlink as _d

PARAM_ID_LEN = 16


@dataclass(frozen=True)
class Param:
    """One parameter as PARAM_VALUE carries it: the value as a float, its type (MAV_PARAM_TYPE)
    saying how the autopilot stores it (an integer parameter's value is its number as a float,
    the ArduPilot way, MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST; the profiles list only
    PX4 parameters that are floats)."""
    name: str
    value: float
    type: int = _d.MAV_PARAM_TYPE_REAL32

    def __post_init__(self) -> None:
        if not self.name or len(self.name.encode()) > PARAM_ID_LEN:
            raise ValueError(f"a parameter name has 1 to {PARAM_ID_LEN} bytes, got {self.name!r}")
        if not math.isfinite(self.value):
            raise ValueError(f"{self.name}: a parameter value is a finite number, got {self.value!r}")


def home_position_message(lat: float, lon: float, alt: float, now: float) -> Any:
    """HOME_POSITION for a home at `lat`, `lon` (degrees) and `alt` (m above mean sea level).
    The local position is 0, 0, 0: the flight model's local origin is home. The quaternion is
    NaN, as upstream asks when heading and slope are not known (ArduPilot sends it so);
    time_usec is time since boot (`now`)."""
    nan = float("nan")
    return _d.MAVLink_home_position_message(
        round(lat * 1e7), round(lon * 1e7), round(alt * 1000), 0.0, 0.0, 0.0, [nan] * 4, 0.0, 0.0, 0.0,
        max(0, int(now * 1e6)))


def param_id(raw: Any) -> str:
    """PARAM_REQUEST_READ.param_id as text (NUL-terminated, or all 16 bytes)."""
    text = raw.decode(errors="replace") if isinstance(raw, (bytes, bytearray)) else str(raw)
    return text.split("\0", 1)[0]


def param_value_message(params: tuple[Param, ...], request: Any) -> Any | None:
    """PARAM_VALUE for a PARAM_REQUEST_READ (by param_index, or by param_id when the index is
    -1); None for a parameter the vehicle does not have: real autopilots do not answer then."""
    index = request.param_index
    if index >= 0:
        if index >= len(params):
            return None
    else:
        wanted = param_id(request.param_id)
        index = next((i for i, p in enumerate(params) if p.name == wanted), -1)
        if index < 0:
            return None
    p = params[index]
    return _d.MAVLink_param_value_message(p.name.encode(), p.value, p.type, len(params), index)
