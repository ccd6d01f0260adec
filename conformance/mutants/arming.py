"""Vehicles that stay armed (issue 23): the hooks for a clause on the suite's own flight, which
must never leave a vehicle armed and must say so loudly when it cannot disarm one.

Not registered as mutants (`mutant(...)`): no clause judges the flight's disarming yet. The
clause that will (or a test) builds them with `arming_mutant(...)` and registers them with
the clauses they break. Each is a builtin profile's vehicle (builtin:ardupilot by default:
GUIDED, arm, MISSION_START) with one autopilot behaviour broken through
`VehicleNode(autopilot_class=...)`, and the flight rules it needs changed (`RULES`):

- `RefusesMissionStartArmed`: arms when told to, then refuses MAV_CMD_MISSION_START with its
  rules' refusal (FAILED on ArduPilot), and never disarms by itself on the ground: the
  vehicle stays armed until the GCS disarms it.
- `IgnoresDisarm`: answers a disarm (forced or not) ACCEPTED (`answer`; None: no COMMAND_ACK
  at all) and stays armed, and never disarms by itself, not even after landing.
"""

from __future__ import annotations

import dataclasses
from typing import Any, Callable

from mavconform.reference_impl.autopilot import Autopilot
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Peer, Send
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode


class RefusesMissionStartArmed(Autopilot):
    """MAV_CMD_MISSION_START is refused once the vehicle is armed."""

    RULES: dict[str, Any] = {"disarm_idle_after": None}

    def command(self, msg: Any, source: Peer, now: float) -> list[Send] | None:
        if msg.command == Cmd.MISSION_START and self._armed:
            return [Send(m.command_ack_message(msg.command, self.rules.refusal, source), source)]
        return super().command(msg, source, now)


class IgnoresDisarm(Autopilot):
    """A disarm is answered `answer` (None: no COMMAND_ACK) and changes nothing."""

    RULES: dict[str, Any] = {"disarm_idle_after": None, "disarm_after_landing": None}
    answer: int | None = R.ACCEPTED

    def command(self, msg: Any, source: Peer, now: float) -> list[Send] | None:
        if msg.command == Cmd.COMPONENT_ARM_DISARM and msg.param1 == 0 and self._armed:
            if self.answer is None:
                return []
            return [Send(m.command_ack_message(msg.command, self.answer, source), source)]
        return super().command(msg, source, now)


def arming_mutant(autopilot_class: type[RefusesMissionStartArmed] | type[IgnoresDisarm], *,
                  profile: str = "ardupilot", **rules: Any) -> Callable[[VehicleConfig], VehicleNode]:
    """A builder, as `mutant(...)` takes one: `profile`'s vehicle, with what the given config
    sets apart from the defaults (a test's system id, say), its flight rules changed by the
    class's RULES and `rules`, and `autopilot_class` plugged in."""
    def build(config: VehicleConfig) -> VehicleNode:
        default = VehicleConfig()
        own = {f.name: getattr(config, f.name) for f in dataclasses.fields(config)
               if f.name != "behaviour" and getattr(config, f.name) != getattr(default, f.name)}
        base = dataclasses.replace(load_profile(profile).config, **own)
        flight = dataclasses.replace(base.flight_rules, **{**autopilot_class.RULES, **rules})
        return VehicleNode(dataclasses.replace(base, flight_rules=flight), autopilot_class=autopilot_class)
    return build
