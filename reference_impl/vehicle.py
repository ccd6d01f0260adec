"""The reference vehicle: heartbeat, mission server, simulated flight, one node.

A `DatagramNode`, so the same object runs under `SimNetwork` (virtual time) or the UDP
driver (real time). Any number of GCSs may talk to it; each is learned from its traffic.

Operator control (MAV_CMD_REQUEST_OPERATOR_CONTROL, development.xml) is off unless
`VehicleConfig.control` is set, so every mission verdict stays what it was. When on, the
`ControlManager` sees every frame first: its own messages (the request, the owner's ACK of
a forwarded request) stop there, and its `screen` answers a GCS not in control
(COMMAND_ACK NOT_IN_CONTROL, MISSION_ACK DENIED, ...) before the mission server or the
command handler can act on what it sent.
"""

from __future__ import annotations

import time
from collections import deque
from dataclasses import dataclass
from typing import Any, Callable

from . import vehicle_info
from .autopilot import Autopilot
from .endpoint import MavlinkEndpoint
from .flight import FlightBattery, FlightSim, Position
from .flight_rules import FlightRules
from .handover import control_messages as cm
from .handover.authenticity import Roster, UnknownGcsGate
from .handover.control_manager import ControlManager, ManagerConfig
from .handover.control_results import ControlChanged, OwnerLost
from .handover.emergency_procedure import (EmergencyEnded, EmergencyStarted, RevokeControl, check_loss_timeout,
                                           revoke_owner)
from .handover.geo import GeoPoint
from .handover.mission_computer import (HandoverFinished, HandoverStarted, MissionComputer, MissionComputerConfig,
                                        WithdrawTakeover, mission_waypoints)
from .handover.mission_computer_transitions import McState
from .mission import messages as m
from .mission.actions import Send
from .mission.behaviour import ServerBehaviour
from .mission.constants import Cmd, CommandResult
from .mission.constants import Cmd as _Cmd
from .mission.items import MISSION_PLAN, PLAN_TYPES, MissionItem, MissionType
from .mission.server import MissionServer
from .net.node import Address
from .vehicle_class import VehicleClass, vehicle_class
from .vehicle_info import Param
from .wire.dialect import mavlink as _d
from .wire.signing import SigningKey

HEARTBEAT_PERIOD = 1.0
POSITION_PERIOD = 1.0
MAX_CONTROL_EVENTS = 1000   # kept for whoever reads them (the mission computer, later)


@dataclass(frozen=True)
class VehicleConfig:
    system: int = 1
    component: int = 1
    behaviour: ServerBehaviour = ServerBehaviour()
    home: Position = Position(47.397742, 8.545594, 0.0)
    speed: float = 10.0              # m/s ground speed of the simulated flight
    # the simulated flight runs this many times faster (legs, climbs, descents; never a hold
    # nor a protocol timer), as SITL's --speedup: a builtin vehicle's flights in a real-time run
    flight_speedup: float = 1.0
    autostart: bool = False          # start flying as soon as a mission is accepted
    mavlink_version: int = 2
    signing: SigningKey | None = None
    require_signature: bool = False
    # HEARTBEAT.autopilot (MAV_AUTOPILOT): GCSs adapt to it (generic 7, ArduPilot 3, PX4 12)
    autopilot: int = _d.MAV_AUTOPILOT_GENERIC_MISSION_FULL
    # HEARTBEAT.type (MAV_TYPE): what flies; vehicle_class.py says how (a ground vehicle never climbs)
    vehicle_type: int = _d.MAV_TYPE_QUADROTOR
    # HEARTBEAT.custom_mode on the ground / while flying the mission, in the autopilot's own
    # numbering (GCSs show it as the flight mode), for a vehicle without a mode table
    # (flight_rules.modes); 0 for the generic autopilot, which has none
    custom_mode_idle: int = 0
    custom_mode_mission: int = 0
    # How the autopilot lets itself be flown: modes, arming, starting, take-off, landing,
    # return (flight_rules.py; the default: the spec vehicle, no modes and no arming)
    flight_rules: FlightRules = FlightRules()
    # The parameters PARAM_REQUEST_READ is answered for (PARAM_VALUE); others get no answer
    params: tuple[Param, ...] = ()
    # the GCS link is bound to one peer address (real SITL links: VARIANTS.md L1, L2)
    single_peer_link: bool = False
    # Messages (by name) the autopilot has no handler for: dropped unread, never answered
    # (INAV 9.1 ignores MISSION_ITEM_INT, MISSION_REQUEST_INT, MISSION_ACK, COMMAND_LONG, ...)
    ignored_messages: frozenset[str] = frozenset()
    # Operator control. None (the default): no system manager, 32100 is UNSUPPORTED and any
    # GCS may change state, as before. Set: the vehicle is its own system manager. Unowned,
    # the filter stays closed unless `control.open_when_unowned`: a GCS asks for control
    # first (the request, mission downloads and telemetry requests are always let through),
    # so no GCS can change the plan of a vehicle it never took.
    control: ManagerConfig | None = None
    # Known GCSs, each with its own signing key (handover/authenticity.py). None: `signing`
    # alone, as before. Set: a frame is checked against the key of the system it claims and
    # frames to a GCS are signed with its key; with `control`, a system not in the roster
    # never reaches the manager (never gains control), even if unsigned frames are accepted.
    roster: Roster | None = None
    # The thesis's mission computer (handover/mission_computer.py). None (the default): no
    # handover, as before. Set (needs `control`): it is told the flight's position, starts
    # the handover sequence in a handover region and withdraws what an aborted one left open.
    handover: MissionComputerConfig | None = None
    # The flight's battery (flight.FlightBattery: the scenario's energy model and charge),
    # drained by distance flown; the emergency procedure plans its refuge with it. None: none.
    battery: FlightBattery | None = None

    def __post_init__(self) -> None:
        if self.flight_rules.modes and (self.custom_mode_idle or self.custom_mode_mission):
            raise ValueError("custom_mode_idle / custom_mode_mission are for a vehicle without a mode table; "
                             "with flight modes the HEARTBEAT carries the current mode's number (boot_mode)")
        if len({p.name for p in self.params}) != len(self.params):
            raise ValueError("params: a parameter is listed twice")

    @property
    def int_forms_ignored(self) -> bool:
        """MISSION_ITEM_INT / MISSION_REQUEST_INT are dropped unread (INAV 9.1): a GCS must use
        MISSION_ITEM / MISSION_REQUEST."""
        return bool({"MISSION_ITEM_INT", "MISSION_REQUEST_INT"} & self.ignored_messages)

    @property
    def abandoned_upload_ends(self) -> bool:
        """An upload a GCS abandons is ended, by the vehicle's timer or by the GCS's cancel.
        INAV 9.1 has neither (no upload timers, MISSION_ACK unread): it stays open."""
        return self.behaviour.upload_timers and "MISSION_ACK" not in self.ignored_messages


class VehicleNode:
    """Reference vehicle as a sans-IO datagram node."""

    def __init__(self, config: VehicleConfig | None = None, *,
                 wall_clock: Callable[[], float] = time.time,
                 server_class: type[MissionServer] = MissionServer,
                 manager_class: type[ControlManager] = ControlManager,
                 mission_computer_class: type[MissionComputer] = MissionComputer,
                 autopilot_class: type[Autopilot] = Autopilot) -> None:
        self.config = cfg = config or VehicleConfig()
        keyring = cfg.roster.keyring(cfg.system, cfg.signing) if cfg.roster is not None else None
        self.endpoint = MavlinkEndpoint(cfg.system, cfg.component, version=cfg.mavlink_version,
                                        signing=cfg.signing, require_signature=cfg.require_signature,
                                        wall_clock=wall_clock, single_peer=cfg.single_peer_link, keyring=keyring)
        self.gate = UnknownGcsGate(cfg.roster, cfg.system, cfg.component) if cfg.roster is not None else None
        self.server = server_class(cfg.system, cfg.component, cfg.behaviour)
        self.server.home = home_item(cfg.home)
        self.flight = FlightSim(self.server.store, self.server.progress, home=cfg.home, speed=cfg.speed,
                                battery=cfg.battery, ground=vehicle_class(cfg.vehicle_type) is VehicleClass.GROUND,
                                speedup=cfg.flight_speedup)
        self.frames_received = 0
        self.events: list[str] = []   # human-readable log of plan changes, for the CLI
        # autopilot_class: a test plugs in an autopilot that misbehaves (autopilot_faults.py)
        self.autopilot = autopilot_class(cfg.flight_rules, self.flight, events=self.events,
                                         legacy_modes=(cfg.custom_mode_idle, cfg.custom_mode_mission))
        self._seen = self._plan_state()
        self._seen_quick = (self.server.store.version, 0, 0)
        self._next_heartbeat: float | None = 0.0
        self._next_position: float | None = 0.0
        # manager_class: the conformance mutants plug a broken system manager in here
        self.control = manager_class(cfg.system, cfg.component, cfg.control) if cfg.control is not None else None
        self.control_events: deque[ControlChanged | OwnerLost] = deque(maxlen=MAX_CONTROL_EVENTS)
        self.refused = 0              # frames the control filter stopped
        if cfg.handover is not None and self.control is None:
            raise ValueError("VehicleConfig.handover needs VehicleConfig.control: the mission computer "
                             "hands control over through the system manager")
        if cfg.handover is not None and cfg.handover.emergency is not None:
            check_loss_timeout(cfg.handover.emergency, cfg.control)
        # mission_computer_class: the conformance mutants plug a broken mission computer in here
        self.mission_computer = (mission_computer_class(cfg.system, cfg.component, cfg.handover)
                                 if cfg.handover is not None else None)
        self.handover_events: deque[Any] = deque(maxlen=MAX_CONTROL_EVENTS)

    @property
    def store(self):
        return self.server.store

    @property
    def owner(self) -> int:
        """The GCS in control (`gcs_main`), 0 for none or without operator control."""
        return self.control.owner if self.control is not None else 0

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for frame in self.endpoint.receive(data, source):
            self.frames_received += 1
            if frame.msg._type in self.config.ignored_messages:
                continue
            if self.control is not None and not self._passes_control(frame, now):
                continue
            msg = frame.msg
            name = msg._type
            server = self.server
            if server.handles(name):
                # the stored mission is a tuple replaced on commit: identity tells a change
                seq_before, mission_before = server.progress.seq, server.store.items(MISSION_PLAN)
                self._send(server.handle(frame, now))
                if server.store.items(MISSION_PLAN) is not mission_before:
                    self._plan_changed(now)
                elif server.progress.seq != seq_before:
                    self.flight.retarget(now)
            elif name in ("COMMAND_LONG", "COMMAND_INT"):
                self._on_command(msg, frame.source, now)
            elif name == "PARAM_REQUEST_READ" and self._for_me(msg):
                value = vehicle_info.param_value_message(self.config.params, msg)
                if value is not None:
                    self.endpoint.send(value, frame.source)
        self._note_changes()
        if self.mission_computer is not None:
            self._sync_mission_computer(now)

    def poll(self, now: float) -> None:
        if self.control is not None:
            self._on_control(self.control.poll(now), now)
        self._send(self.server.poll(now))
        self._note_changes()
        self._send(self.flight.poll(now))
        self._send(self.autopilot.poll(now))
        if self.mission_computer is not None:
            self._sync_mission_computer(now)
            self._on_handover(self.mission_computer.poll(now), now)
        if self._next_heartbeat is not None and now >= self._next_heartbeat:
            self._next_heartbeat = now + HEARTBEAT_PERIOD
            self.endpoint.send(self._heartbeat())
        if self._next_position is not None and now >= self._next_position:
            self._next_position = now + POSITION_PERIOD
            self.endpoint.send(self._position(now))

    def next_deadline(self) -> float | None:
        best = self._next_heartbeat
        for t in (self._next_position, self.server.next_deadline(), self.flight.next_deadline(),
                  self.autopilot.next_deadline()):
            if t is not None and (best is None or t < best):
                best = t
        for engine in (self.control, self.mission_computer):   # None unless configured
            t = engine.next_deadline() if engine is not None else None
            if t is not None and (best is None or t < best):
                best = t
        return best

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.endpoint.take_outgoing()

    # --- operator control -----------------------------------------------------------------
    def _passes_control(self, frame: Any, now: float) -> bool:
        """Whether `frame` goes on to the mission server and command handling. The manager
        hears every frame (the owner's HEARTBEATs keep it in control), keeps its own, and
        answers a GCS not in control in their place."""
        control = self.control
        refusal = self.gate.screen(frame) if self.gate is not None else None   # unknown GCSs: before the manager
        if refusal is None and self.mission_computer is not None:
            refusal = self.mission_computer.screen(frame)   # the emergency: nobody commands the refuge flight
        if refusal is None:
            self._on_control(control.handle(frame, now), now)
            if self.mission_computer is not None:
                self._on_handover(self.mission_computer.handle(frame, now), now)
            if control.consumes(frame.msg):
                return False
            refusal = control.screen(frame)
        if refusal is None:
            return True
        self.refused += 1
        if refusal.actions:   # answered refusals only: a stream (MANUAL_CONTROL) is dropped unlogged
            self.events.append(f"control: refused {refusal.reason}")
        self._send(list(refusal.actions))
        return False

    def _on_control(self, actions: list[Any], now: float) -> None:
        """Send what the manager sends (CONTROL_STATUS, ACKs, forwarded requests); keep and
        log its events. Owner loss is also announced in a STATUSTEXT: the XML's "If all owning
        GCS are disconnected the vehicle should GCS loss failsafe, and broadcast a
        CONTROL_STATUS indicating that it has no owner(s)" says what to broadcast, not how an
        operator hears of it; the failsafe itself is for whoever reads `control_events`."""
        for action in self.endpoint.send_all(actions):
            self.control_events.append(action)
            if isinstance(action, OwnerLost):
                silent = action.at - action.last_heard
                self.events.append(f"control: GCS {action.sysid} lost ({silent:.1f} s without its HEARTBEAT)")
                self.endpoint.send(cm.statustext(_d.MAV_SEVERITY_CRITICAL,
                                                 f"GCS {action.sysid} lost: no GCS in control"))
                if self.mission_computer is not None:   # the emergency procedure's commander-lost trigger
                    self._sync_mission_computer(now)      # decided where the vehicle is now
                    self._on_handover(self.mission_computer.owner_lost(action, now), now)
            else:
                was = f" (was {action.previous})" if action.previous != action.owner else ""
                takeover = "allowed" if action.takeover_allowed else "disallowed"
                self.events.append(f"control: gcs_main {action.owner}{was}, takeover {takeover}: {action.reason}")
                if self.mission_computer is not None:
                    self._on_handover(self.mission_computer.control_changed(action, now), now)

    # --- mission computer (VehicleConfig.handover) -----------------------------------------
    def _sync_mission_computer(self, now: float) -> None:
        """Tell the mission computer where the vehicle is and whether it flies (it does not
        read the flight model itself)."""
        mc, flight = self.mission_computer, self.flight
        p = flight.where(now)
        battery = flight.battery_at(now)
        mc.observe(GeoPoint(p.lat, p.lon, p.alt), now, None if battery is None else (battery, flight.battery.model))
        if flight.flying and mc.state is McState.ON_LOAD:
            mc.start(now, mission_waypoints(self.server.store.items(MissionType.MISSION)))
        elif not flight.flying and mc.state is not McState.ON_LOAD:
            self._on_handover(mc.stop(now), now)

    def _on_handover(self, actions: list[Any], now: float) -> None:
        """Send the mission computer's messages (invitations, connect notices, STATUSTEXT),
        withdraw what an aborted handover left open in the manager, keep and log its events."""
        for action in self.endpoint.send_all(actions):
            if isinstance(action, WithdrawTakeover):
                self._on_control(self.control.withdraw(action.requester, now), now)
                continue
            if isinstance(action, RevokeControl):
                self._on_control(revoke_owner(self.control, action.reason, now), now)
                continue
            self.handover_events.append(action)
            if isinstance(action, HandoverStarted):
                self.events.append(f"handover: GCS {action.commander} -> GCS {action.partner} started "
                                   f"(region {action.region})")
            elif isinstance(action, HandoverFinished):
                r = action.result
                detail = f": {r.detail}" if r.detail else ""
                self.events.append(f"handover: GCS {r.commander} -> GCS {r.partner} {r.outcome.value} "
                                   f"after {r.duration:.2f} s, gcs_main {r.owner}{detail}")
            elif isinstance(action, EmergencyStarted):
                target = action.refuge.point
                self.flight.divert(Position(float(target.lat), float(target.lon), self.config.home.alt), now)
                self.events.append(f"emergency: {action.trigger.reason}; {action.refuge.reason}")
            elif isinstance(action, EmergencyEnded):
                self.events.append(f"emergency over: {action.how}")

    # --- internals ------------------------------------------------------------------------
    def _plan_state(self) -> tuple:
        store, stats = self.server.store, self.server.stats
        return (tuple((store.count(t), store.opaque_id(t)) for t in PLAN_TYPES),
                stats.uploads_failed, stats.denied)

    def _note_changes(self) -> None:
        stats = self.server.stats
        quick = (self.server.store.version, stats.uploads_failed, stats.denied)
        if quick == self._seen_quick:
            return
        self._seen_quick = quick
        state = self._plan_state()
        (plans, failed, denied), (old_plans, old_failed, old_denied) = state, self._seen
        for t, (n, oid), old in zip(PLAN_TYPES, plans, old_plans):
            if (n, oid) != old:
                self.events.append(f"{t.label}: {n} items stored (id 0x{oid:08x})" if n else f"{t.label}: cleared")
        if failed > old_failed:
            self.events.append(f"upload failed or cancelled; stored plans unchanged ({failed} so far)")
        if denied > old_denied:
            self.events.append(f"denied a second GCS during a transfer ({denied} so far)")
        self._seen = state

    def _send(self, actions: list[Send]) -> None:
        send = self.endpoint.send
        for msg, to in actions:
            send(msg, to)

    def _plan_changed(self, now: float) -> None:
        """A new flight plan was committed (or cleared)."""
        self._send(self.autopilot.plan_changed(now))
        if self.config.autostart and self.server.store.count(0):
            self._send(self.autopilot.start_now(now))
        else:
            self.flight.retarget(now)

    def _for_me(self, msg: Any) -> bool:
        return msg.target_system in (0, self.config.system) and msg.target_component in (0, self.config.component)

    def _on_command(self, msg: Any, source: tuple[int, int], now: float) -> None:
        if not self._for_me(msg):
            return
        if msg.command == Cmd.DO_SET_MISSION_CURRENT and self.server.behaviour.set_current_command:
            self._send(self.server.command_set_current(msg.param1, source, now))
            self.flight.retarget(now)
            return
        answer = self.autopilot.command(msg, source, now)   # modes, arming, start, take-off, RTL, land, home
        if answer is None:
            answer = [Send(m.command_ack_message(msg.command, CommandResult.UNSUPPORTED, source), source)]
        self._send(answer)

    def _heartbeat(self) -> Any:
        base_mode, custom_mode, status = self.autopilot.heartbeat_fields()
        return _d.MAVLink_heartbeat_message(self.config.vehicle_type, self.config.autopilot, base_mode, custom_mode,
                                            status, 3)

    def _position(self, now: float) -> Any:
        p = self.flight.where(now)
        return _d.MAVLink_global_position_int_message(
            int(now * 1000) & 0xFFFFFFFF, round(p.lat * 1e7), round(p.lon * 1e7),
            round(p.alt * 1000), round((p.alt - self.config.home.alt) * 1000), 0, 0, 0, 0xFFFF)


def home_item(home: Position) -> MissionItem:
    """The vehicle's home as the mission item a plan that holds it at seq 0 serves
    (MAV_FRAME_GLOBAL: absolute altitude)."""
    return MissionItem(0, 0, _Cmd.NAV_WAYPOINT, x=round(home.lat * 1e7), y=round(home.lon * 1e7),
                       z=float(home.alt))
