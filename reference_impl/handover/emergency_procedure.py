"""The emergency procedure on the vehicle (seed 003, 4.7): when, where to, who may command.

The thesis leaves it to future work and says what it should do: when "the drone is flying
outside a coverage area" (`check_geofence`) or communication fails, "send the RTL command", or
with rally points "calculate the distance of the nearest rally point considering the amount of
battery remaining". `emergency.py` decides where (pure); this module is the part the mission
computer runs: its configuration, what it reports, the announcement, and the filter that keeps
GCSs from commanding the refuge flight. The mission computer's `on_emergency` state
(mission_computer_transitions.EMERGENCY_TRANSITIONS) ties them together.

Decisions, and why:

- **Commander lost is the system manager's owner loss** (`OwnerLost`), not a second timer in
  the mission computer. One clock decides "lost": two would disagree near the threshold (a
  manager that has dropped the owner while the mission computer still waits is a flight with
  no commander and no emergency; the other way round, an emergency while a GCS still commands).
  So `EmergencyConfig.policy.loss_timeout_s` must equal `ManagerConfig.owner_loss_timeout`
  (`check_loss_timeout`, called by the vehicle); it fires in the manager's own poll, so the
  emergency starts exactly `loss_timeout_s` after the commander's last HEARTBEAT reached the
  vehicle.
- **Outside every coverage** is judged at the mission computer's check (every `check_period`)
  on the latest position, with plain containment (no margin: the coverage is where a GCS has
  authority, and outside it nobody has); after `outside_grace_s` outside without a break it
  fires. Geographic methods only: waypoint ownership is not a place.
- **The refuge** is `choose_refuge` at the trigger's instant, with the battery the flight has
  left (the flight model drains it by distance flown, `flight.FlightBattery`); without a
  battery model the nearest refuge is taken (range is not limited). Home is the configured
  one, else where the flight started (RTL: return to *launch*).
- **Control is dropped**: `CONTROL_STATUS` with no owner ("If all owning GCS are
  disconnected the vehicle should GCS loss failsafe, and broadcast a CONTROL_STATUS indicating
  that it has no owner(s)"); for the outside trigger the vehicle revokes the owner itself
  (outside every coverage no GCS has authority).
- **No GCS command ends the refuge flight.** While on_emergency the vehicle refuses every
  state-changing message from every GCS (commands: COMMAND_ACK TEMPORARILY_REJECTED, mission
  writes: MISSION_ACK DENIED), whatever the manager's `open_when_unowned` says. The one
  exception (`takeback`, on by default): a *known* GCS (one with coverage in the mission) whose
  coverage holds the vehicle (any known GCS under the waypoint method) may request control, and
  the manager grants it as it grants any request when nobody owns control. The XML lets a GCS
  request control of an uncontrolled vehicle and the thesis says nothing; an operator who hears
  the vehicle and is heard by it, inside the area it has authority over, decides better than a
  failsafe, which is why autopilots let the pilot take over after a GCS failsafe. A GCS outside
  its coverage, or unknown, is refused (TEMPORARILY_REJECTED: it may ask again once the vehicle
  is in its coverage). Taking control ends on_emergency but not the refuge flight: the vehicle
  flies on to the refuge and lands unless the new commander resumes the mission
  (MAV_CMD_MISSION_START), as an autopilot stays in RTL after its failsafe until the pilot
  changes mode.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable, Iterable

from ..mission.actions import Send
from ..wire.dialect import mavlink as _d
from ..wire.frame import Frame
from . import control_messages as cm
from .control_manager import ControlManager, ManagerConfig, refuse_state_change
from .control_results import OwnerLost, Refusal
from .control_transitions import ControlEvent
from .emergency import (BatteryModel, BatteryState, Refuge, RefugeKind, Trigger, TriggerKind, TriggerPolicy,
                        choose_refuge, due_triggers)
from .geo import GeoPoint

__all__ = ["EmergencyConfig", "EmergencyEnded", "EmergencyStarted", "OutsideWatch", "RevokeControl",
           "announcement", "check_loss_timeout", "commander_lost", "refuge_for", "revoke_owner", "screen"]

BatteryReading = tuple[BatteryState, BatteryModel]
# No battery model: a range longer than any great-circle distance (half the Earth's circumference
# is about 2.0e7 m), so `choose_refuge` takes the nearest refuge whatever its distance.
_UNLIMITED = (BatteryState(1.0), BatteryModel(1.0, 1e-8))


@dataclass(frozen=True)
class EmergencyConfig:
    """The procedure's settings (`MissionComputerConfig.emergency`; None there: off).

    `policy`: the scenario's `timeouts.triggers()` (loss timeout = the manager's owner-loss
    timeout; outside grace). `rally`: the refuges besides home. `home`: None for where the
    flight started. `commander_lost` / `outside`: each trigger on or off (`outside` acts under
    the geographic methods only). `takeback`: a known GCS covering the vehicle may take control
    back during the emergency (module doc)."""

    policy: TriggerPolicy
    rally: tuple[GeoPoint, ...] = ()
    home: GeoPoint | None = None
    commander_lost: bool = True
    outside: bool = True
    takeback: bool = True

    def __post_init__(self) -> None:
        if not isinstance(self.policy, TriggerPolicy):
            raise TypeError(f"EmergencyConfig.policy must be a TriggerPolicy, got {self.policy!r}")
        rally = tuple(self.rally)
        for i, p in enumerate(rally):
            if not isinstance(p, GeoPoint):
                raise TypeError(f"EmergencyConfig.rally[{i}] must be a GeoPoint, got {p!r}")
        object.__setattr__(self, "rally", rally)
        if self.home is not None and not isinstance(self.home, GeoPoint):
            raise TypeError(f"EmergencyConfig.home must be a GeoPoint or None, got {self.home!r}")


def check_loss_timeout(emergency: EmergencyConfig, manager: ManagerConfig | None) -> None:
    """ValueError unless the commander-lost trigger and the manager's owner loss are one clock."""
    if manager is None or not emergency.commander_lost:
        return
    if emergency.policy.loss_timeout_s != manager.owner_loss_timeout:
        raise ValueError(f"the emergency's loss timeout ({emergency.policy.loss_timeout_s:g} s) must be the system "
                         f"manager's owner_loss_timeout ({manager.owner_loss_timeout:g} s): the commander is lost "
                         f"when the manager drops it")


# --- what the mission computer reports -----------------------------------------------------------
@dataclass(frozen=True)
class EmergencyStarted:
    """The vehicle diverts to `refuge` (the vehicle node flies it: `FlightSim.divert`)."""

    trigger: Trigger
    refuge: Refuge
    commander: int                  # gcs_main when it fired (the lost one for COMMANDER_LOST)
    position: GeoPoint
    battery_wh: float | None        # remaining at the decision (None: no battery model)
    at: float


@dataclass(frozen=True)
class RevokeControl:
    """Ask the system manager to drop its owner now (CONTROL_STATUS with no owner)."""

    reason: str


@dataclass(frozen=True)
class EmergencyEnded:
    """on_emergency left: `owner` took control back (the refuge flight goes on), or 0: landed."""

    owner: int
    at: float
    how: str


# --- triggers ------------------------------------------------------------------------------------
def commander_lost(lost: OwnerLost, policy: TriggerPolicy) -> Trigger | None:
    """The COMMANDER_LOST trigger for the manager's owner loss (None if it is not yet due,
    which `check_loss_timeout` rules out)."""
    fired = due_triggers(lost.at, commander_last_heard=lost.last_heard, outside_since=None, policy=policy)
    return next((t for t in fired if t.kind is TriggerKind.COMMANDER_LOST), None)


class OutsideWatch:
    """Since when the vehicle has been outside every coverage, sample by sample (`check_geofence`)."""

    def __init__(self) -> None:
        self.since: float | None = None

    def observe(self, coverages: Iterable[Any], point: GeoPoint, at: float) -> None:
        if any(c.contains(point) for c in coverages):
            self.since = None
        elif self.since is None:
            self.since = at

    def due(self, now: float, policy: TriggerPolicy) -> Trigger | None:
        if self.since is None:
            return None
        fired = due_triggers(now, commander_last_heard=None, outside_since=self.since, policy=policy)
        return fired[0] if fired else None


# --- the decision and its announcement -----------------------------------------------------------
def refuge_for(position: GeoPoint, home: GeoPoint, rally: tuple[GeoPoint, ...],
               battery: BatteryReading | None) -> Refuge:
    """`choose_refuge` with the battery left; without a battery model, the nearest refuge."""
    state, model = battery if battery is not None else _UNLIMITED
    refuge = choose_refuge(position, home, rally, state, model)
    if battery is None:
        where = "home" if refuge.kind is RefugeKind.HOME else f"rally point {refuge.rally_index}"
        refuge = Refuge(refuge.kind, refuge.point, refuge.distance_m, math.inf, refuge.rally_index,
                        f"{where}: the nearest refuge, {refuge.distance_m:.0f} m away (no battery model: range "
                        f"not limited)")
    return refuge


def _km(metres: float) -> str:
    return f"{metres:.0f} m" if metres < 1000 else f"{metres / 1000:.2f} km"


def announcement(trigger: Trigger, refuge: Refuge, commander: int) -> Send:
    """STATUSTEXT naming the trigger and the refuge (50 characters at most): CRITICAL with a
    refuge in range, EMERGENCY when the vehicle can only land where it is."""
    why = f"GCS {commander} lost" if trigger.kind is TriggerKind.COMMANDER_LOST else "outside coverage"
    where = {RefugeKind.HOME: f"RTL {_km(refuge.distance_m)}",
             RefugeKind.RALLY: f"rally {refuge.rally_index} {_km(refuge.distance_m)}",
             RefugeKind.LAND_HERE: "landing here"}[refuge.kind]
    severity = _d.MAV_SEVERITY_CRITICAL if refuge.reachable else _d.MAV_SEVERITY_EMERGENCY
    return Send(cm.statustext(severity, f"Emergency: {why}; {where}"))


def ended_text(ended: EmergencyEnded) -> Send:
    text = f"Emergency over: GCS {ended.owner} in control" if ended.owner else "Emergency: landed at the refuge"
    return Send(cm.statustext(_d.MAV_SEVERITY_NOTICE, text))


# --- who may command during the emergency --------------------------------------------------------
def screen(frame: Frame, system: int, component: int, entitled: Callable[[int], bool]) -> Refusal | None:
    """The refusal for `frame` while on_emergency, or None to let it through (to the manager).

    The vehicle's own components pass (a companion computer, as the manager lets them);
    telemetry requests, downloads and releases pass (they move nothing). A request for control
    passes only from a GCS `entitled` to take it back; every other state-changing message is
    refused as the manager refuses a GCS not in control, with TEMPORARILY_REJECTED for commands
    (the vehicle may take them once the emergency is over)."""
    src, msg = frame.source, frame.msg
    if src[0] == system or not cm.addressed_to(msg, system, component):
        return None
    name = msg._type
    who = f"GCS {src[0]}: emergency, no GCS in control"
    if name in ("COMMAND_LONG", "COMMAND_INT") and cm.is_request_control(msg) \
            and msg.param1 == cm.ACTION_REQUEST and not entitled(src[0]):
        ack = cm.command_ack(msg.command, _d.MAV_RESULT_TEMPORARILY_REJECTED, src)
        return Refusal(f"{name} {msg.command}: {who}", (Send(ack, src),))
    return refuse_state_change(msg, src, who, _d.MAV_RESULT_TEMPORARILY_REJECTED, "emergency")


def revoke_owner(manager: ControlManager, reason: str, now: float) -> list[Any]:
    """Drop the manager's owner for the emergency: CONTROL_STATUS with no owner now, and a
    `ControlChanged` for the vehicle to pass on. The manager has no public revocation; its
    table's OWNER_LOST move (every owned state -> unowned) is the one that fits: the owner can
    no longer command (its `stats.owners_lost` is left alone: nobody fell silent)."""
    if not manager.owner:
        return []
    return manager._change(lambda: manager._drop_owner(ControlEvent.OWNER_LOST), reason, now)
