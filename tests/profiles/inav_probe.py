"""A GCS's hands for probing the inav profile's vehicle message by message, as the SITL probes
did (/work/sitl/inav-probes): the vehicle and a GCS on a SimNetwork (virtual time), raw
MAVLink sent with the float mission messages, and the vehicle's answers read back."""

from __future__ import annotations

import dataclasses
from typing import Any, Iterable

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.profiles import build_config, load_profile
from mavconform.reference_impl.vehicle import VehicleConfig
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcs

VEHICLE = (1, 1)
TELEMETRY = {"HEARTBEAT", "GLOBAL_POSITION_INT"}   # streamed, not answers
ANSWER_WAIT = 0.2                                  # s: every answer comes at once (no timers)
LAT, LON = 47.3977419, 8.5455938


def inav_config(without: Iterable[str] = (), **overrides: Any) -> VehicleConfig:
    """The inav profile's vehicle config, with the knobs in `without` back at the spec default."""
    removed = set(without)
    settings = [s for s in load_profile("inav").settings if s.knob not in removed]
    config = build_config(settings, where="the inav profile without " + (", ".join(sorted(removed)) or "nothing"))
    return dataclasses.replace(config, **overrides) if overrides else config


class Probe:
    """One vehicle, one GCS (sysid 255, compid 190)."""

    def __init__(self, config: VehicleConfig) -> None:
        self.rig = vehicle_and_gcs(config, seed=1)
        self.net, self.gcs, self.vehicle = self.rig.net, self.rig.gcs, self.rig.vehicle

    def send(self, msg: Any, wait: float = ANSWER_WAIT) -> list[Any]:
        """Send `msg` and return what the vehicle sent in the next `wait` seconds (no telemetry)."""
        start = len(self.gcs.received)
        self.gcs.send(msg)
        self.net.run_for(wait)
        return [x for x in self.gcs.received[start:] if x.get_type() not in TELEMETRY]

    def run(self, seconds: float) -> list[Any]:
        start = len(self.gcs.received)
        self.net.run_for(seconds)
        return [x for x in self.gcs.received[start:] if x.get_type() not in TELEMETRY]

    def upload(self, items: list[Any], mission_type: int = 0) -> list[Any]:
        """MISSION_COUNT, then each MISSION_ITEM in turn; every answer."""
        out = self.send(count(len(items), mission_type))
        for it in items:
            out += self.send(it)
        return out

    def stored(self) -> int:
        """The count MISSION_REQUEST_LIST answers."""
        return one(self.send(request_list()), "MISSION_COUNT").count


def only(msgs: list[Any], name: str) -> list[Any]:
    return [x for x in msgs if x.get_type() == name]


def one(msgs: list[Any], name: str) -> Any:
    """The only message in `msgs`, which must be a `name`."""
    assert [x.get_type() for x in msgs] == [name], [x.get_type() for x in msgs]
    return msgs[0]


def summary(msgs: list[Any]) -> list[tuple]:
    """Each answer as (name, its deciding fields)."""
    out = []
    for x in msgs:
        name = x.get_type()
        if name == "MISSION_ACK":
            out.append((name, x.type, x.mission_type))
        elif name in ("MISSION_REQUEST", "MISSION_REQUEST_INT"):
            out.append((name, x.seq, x.mission_type))
        elif name == "MISSION_COUNT":
            out.append((name, x.count, x.mission_type))
        elif name == "COMMAND_ACK":
            out.append((name, x.command, x.result))
        else:
            out.append((name,))
    return out


# --- what the GCS sends ----------------------------------------------------------------------
def count(n: int, mission_type: int = 0, target: tuple[int, int] = VEHICLE) -> Any:
    return d.MAVLink_mission_count_message(target[0], target[1], n, mission_type, 0)


def wp(seq: int, north: int = 0, *, command: int = Cmd.NAV_WAYPOINT, frame: int = 3, z: float = 20.0,
       autocontinue: int = 1, current: int = 0, params: tuple[float, float, float, float] = (0, 0, 0, 0),
       x: float | None = None, y: float = LON, mission_type: int = 0, as_int: bool = False) -> Any:
    """A MISSION_ITEM (float; `as_int`: MISSION_ITEM_INT), `north` * 1e-4 degrees north of LAT."""
    lat = LAT + north * 1e-4 if x is None else x
    if as_int:
        return d.MAVLink_mission_item_int_message(1, 1, seq, frame, int(command), current, autocontinue, *params,
                                                  round(lat * 1e7), round(y * 1e7), z, mission_type)
    return d.MAVLink_mission_item_message(1, 1, seq, frame, int(command), current, autocontinue, *params,
                                          lat, y, z, mission_type)


def waypoints(n: int, start: int = 0) -> list[Any]:
    return [wp(i, start + i) for i in range(n)]


def request(seq: int, mission_type: int = 0, *, as_int: bool = False) -> Any:
    cls = d.MAVLink_mission_request_int_message if as_int else d.MAVLink_mission_request_message
    return cls(1, 1, seq, mission_type)


def request_list(mission_type: int = 0, target: tuple[int, int] = VEHICLE) -> Any:
    return d.MAVLink_mission_request_list_message(target[0], target[1], mission_type)


def clear_all(mission_type: int = 0, target: tuple[int, int] = VEHICLE) -> Any:
    return d.MAVLink_mission_clear_all_message(target[0], target[1], mission_type)


def ack(result: int, mission_type: int = 0) -> Any:
    return d.MAVLink_mission_ack_message(1, 1, result, mission_type, 0)


def set_current(seq: int) -> Any:
    return d.MAVLink_mission_set_current_message(1, 1, seq)


def command_long(command: int, *params: float) -> Any:
    return d.MAVLink_command_long_message(1, 1, command, 0, *params, *([0.0] * (7 - len(params))))


def command_int(command: int, param1: float = 0.0) -> Any:
    return d.MAVLink_command_int_message(1, 1, 0, command, 0, 0, param1, 0, 0, 0, 0, 0, 0.0)
