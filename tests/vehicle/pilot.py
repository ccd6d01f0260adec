"""A GCS's hands on the reference vehicle for the autopilot tests: a builtin profile's vehicle
and the reference GCS on a SimNetwork (virtual time), commands sent as COMMAND_LONG and
answered by their COMMAND_ACK, the HEARTBEAT and STATUSTEXT read off the wire."""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

from mavconform.reference_impl.flight import Position, haversine_m
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcs

HOME = (47.397742, 8.545594)
M_PER_DEG = 111_195.0
ARMED = d.MAV_MODE_FLAG_SAFETY_ARMED
FORCE = 21196.0
NAV_LAST = 95                  # MAV_CMD_NAV_LAST: navigation commands are below it
FOLLOWS = 0.05                 # s after a COMMAND_ACK for what the vehicle sends with it (STATUSTEXT, HOME_POSITION)


def item(seq: int, command: int = Cmd.NAV_WAYPOINT, north_m: float | None = 0.0, alt: float = 20.0,
         **params: float) -> MissionItem:
    """A mission item `north_m` north of home (None: no position, as a take-off or landing may have)."""
    x = y = 0
    if north_m is not None:
        x, y = round((HOME[0] + north_m / M_PER_DEG) * 1e7), round(HOME[1] * 1e7)
    if command >= NAV_LAST:     # a DO or condition command: no place, MAV_FRAME_MISSION
        return MissionItem(seq, d.MAV_FRAME_MISSION, int(command), **params)
    return MissionItem(seq, d.MAV_FRAME_GLOBAL_RELATIVE_ALT, int(command), x=x, y=y, z=alt, **params)


def plan(*commands: tuple[int, float | None, float]) -> list[MissionItem]:
    """Items from (command, metres north or None, altitude), numbered in order."""
    return [item(i, c, n, a) for i, (c, n, a) in enumerate(commands)]


TAKEOFF_WP_LAND = plan((Cmd.NAV_TAKEOFF, None, 20.0), (Cmd.NAV_WAYPOINT, 100.0, 20.0),
                       (Cmd.NAV_WAYPOINT, 200.0, 20.0), (Cmd.NAV_LAND, 200.0, 0.0))
BARE_WAYPOINTS = plan((Cmd.NAV_WAYPOINT, 50.0, 20.0), (Cmd.NAV_WAYPOINT, 100.0, 20.0))


class Pilot:
    """One vehicle (a builtin profile's, or a config / builder) and one GCS."""

    def __init__(self, profile: str | VehicleConfig | Callable[[Callable[[], float]], VehicleNode] = "spec",
                 *, seed: int = 1, **config: Any) -> None:
        if isinstance(profile, str):
            base = load_profile(profile).config
            profile = dataclasses.replace(base, **config) if config else base
        self.rig = vehicle_and_gcs(profile, seed=seed)
        self.net, self.vehicle, self.gcs, self.session = self.rig.net, self.rig.vehicle, self.rig.gcs, self.rig.session
        self._read = 0

    @property
    def now(self) -> float:
        return self.net.clock.now()

    def run(self, seconds: float) -> None:
        self.net.run_for(seconds)

    def run_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        return self.net.run_until(condition, timeout=timeout)

    def command(self, command: int, *params: float) -> int:
        """Send COMMAND_LONG and return its COMMAND_ACK's result (AssertionError if none comes)."""
        start = len(self.gcs.received)
        self.gcs.send(m.command_long_message(command, (1, 1), *params))
        self.net.run_until(lambda: self._ack(start, command) is not None, timeout=2.0)
        ack = self._ack(start, command)
        assert ack is not None, f"no COMMAND_ACK for command {command}"
        self.net.run_for(FOLLOWS)
        return ack.result

    def _ack(self, start: int, command: int) -> Any:
        return next((x for x in self.gcs.received[start:] if x.get_type() == "COMMAND_ACK" and x.command == command),
                    None)

    def set_mode(self, number: int, sub: int = 0) -> int:
        """MAV_CMD_DO_SET_MODE with CUSTOM_MODE_ENABLED: (number) ArduPilot's, (main, sub) PX4's."""
        return self.command(Cmd.DO_SET_MODE, d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, number, sub)

    def arm(self, force: bool = False) -> int:
        return self.command(Cmd.COMPONENT_ARM_DISARM, 1, FORCE if force else 0)

    def disarm(self, force: bool = False) -> int:
        return self.command(Cmd.COMPONENT_ARM_DISARM, 0, FORCE if force else 0)

    def upload(self, items: list[MissionItem]) -> None:
        result = self.session.upload(MissionType.MISSION, items)
        assert result.ok, result.summary()
        self.net.run_for(FOLLOWS)

    def beat(self) -> Any:
        """The next HEARTBEAT."""
        start = len(self.gcs.received)
        assert self.net.run_until(lambda: any(x.get_type() == "HEARTBEAT" for x in self.gcs.received[start:]),
                                  timeout=1.5)
        return [x for x in self.gcs.received[start:] if x.get_type() == "HEARTBEAT"][-1]

    def armed(self) -> bool:
        """Armed now, as the next HEARTBEAT will say (`beat()` reads the HEARTBEAT itself)."""
        return self.vehicle.autopilot.armed

    def mode(self) -> int:
        return self.beat().custom_mode

    def texts(self) -> list[str]:
        """Every STATUSTEXT so far, chunks of a long one joined."""
        out: list[str] = []
        for x in self.gcs.received:
            if x.get_type() != "STATUSTEXT":
                continue
            text = x.text if isinstance(x.text, str) else bytes(x.text).decode(errors="replace")
            text = text.split("\0", 1)[0]
            if x.id and x.chunk_seq:
                out[-1] += text
            else:
                out.append(text)
        return out

    def reached(self) -> list[int]:
        return [x.seq for x in self.gcs.received if x.get_type() == "MISSION_ITEM_REACHED"]

    def currents(self) -> list[int]:
        return [x.seq for x in self.gcs.received if x.get_type() == "MISSION_CURRENT"]

    def where(self) -> Position:
        return self.vehicle.flight.where(self.now)

    def north(self) -> float:
        p = self.where()
        return haversine_m(HOME[0], HOME[1], p.lat, p.lon)

    def altitude(self) -> float:
        """Metres above home, as GLOBAL_POSITION_INT.relative_alt says it (read from the model)."""
        return self.where().alt - self.vehicle.config.home.alt

    def airborne(self) -> bool:
        return self.vehicle.flight.airborne(self.now)
