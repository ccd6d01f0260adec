"""The world a protocol fuzz example runs in: the target vehicle and our three GCSs.

- GCS "a" runs the operations, over a link whose faults the fuzzer changes between steps;
- GCS "b" is a second GCS (another system id) that starts transfers of its own;
- "mute" sends stray messages and never answers (a GCS that crashed mid-transfer);
- "probe" asks MISSION_REQUEST_LIST over a clean link after every step: is the vehicle
  still answering?

In-process targets (`builtin:`, `mutant:`) put the vehicle on a `SimNetwork` in virtual
time (deterministic from the seed, and the vehicle's store and transfer state can be read
directly); each GCS has a link of its own, and the faults act on A's. `udp:`/`udpin:`
targets are reached over real sockets with bounded waits, and judged from the wire only.
There all four GCSs share the campaign's one socket (`TargetConnection`: `SharedLink`,
routed by system id): a real vehicle's GCS link is bound to one peer (VARIANTS.md L1, L2)
and would never hear a GCS on a socket of its own. The faults then act on that one link, as
on a real radio link, and are lifted while the probe asks (`faults_lifted`), so the probe
still has a clean link. Every node sits in a `GuardedNode`, so a node that raises falls
silent and the exception is kept: the vehicle's is a finding (`target-crash`), one of our
GCSs' is a tool error, and neither is a traceback here.

The oracles' rules (`Profile`) are the target's: its own profile in-process, the spec for a
mutant, and for a UDP target `--profile` or the builtin profile of the autopilot family its
HEARTBEAT names.

With `handover` (`--operator-control`) the in-process vehicle is its own operator-control system
manager (`control.HANDOVER_CONTROL`; an HO mutant brings its own, broken, copy of it) and sits
inside a `ControlWatch`, the judge of the control invariants; GCSs A and B run a control
client and send HEARTBEAT (the owner-loss rule counts them). A UDP target must already be a
system manager: it must send CONTROL_STATUS (`require_control_status`).
"""

from __future__ import annotations

import copy
import dataclasses
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from mavconform.conformance.harness.stored_form import SPEC_FORM, StoredForm, form_of_behaviour, modelling_profile
from mavconform.conformance.session import build_vehicle
from mavconform.conformance.target_uri import TargetUri, parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net import FaultModel, SimNetwork
from mavconform.reference_impl.net.guard import GuardedNode
from mavconform.reference_impl.net.sim import CaptureHook
from mavconform.reference_impl.vehicle import VehicleNode

from .connection import TargetConnection
from .control import HANDOVER_CONTROL, ControlRules, ControlWatch
from .wire_control import WireControl
from .faults import install
from .gcs import FuzzGcs
from .scope import Scope

SYSTEM_A, SYSTEM_B, SYSTEM_PROBE, SYSTEM_MUTE, COMPONENT = 245, 246, 247, 248, 190
NAMES = {SYSTEM_A: "GCS A", SYSTEM_B: "GCS B", SYSTEM_PROBE: "the probe GCS", SYSTEM_MUTE: "the mute GCS"}
OUR_NODES = ("a", "b", "probe", "mute")   # an exception in one of these is our bug
# Over real sockets every dropped message costs our GCS a real timeout: a fuzz GCS need not
# wait the spec's 1.5 s for a reply that comes within milliseconds on loopback, and a quick
# resend (a duplicate the vehicle must take in its stride) is fuzzing in itself.
UDP_GCS_TIMINGS = Timings(default_timeout=0.5)


@dataclass(frozen=True)
class Profile:
    """What the oracles hold the target to, and where that came from."""

    atomic: bool = True               # an upload replaces the plan whole or not at all
    timings: Timings = Timings()      # the retry limit the vehicle must keep
    retry_cap: bool = True            # False: retries end on a protocol timeout (PX4, P3)
    form: StoredForm = SPEC_FORM      # how it stores plans (home in slot 0, compact items)
    basis: str = "the spec"
    scope: Scope = Scope()            # the part of the protocol it has (fuzz.protocol.scope)


def rules_of(config: Any, basis: str) -> Profile:
    """The oracle rules a vehicle's profile (its VehicleConfig: knobs and unread messages) implies."""
    behaviour = config.behaviour
    return Profile(atomic=behaviour.atomic_upload, timings=behaviour.timings,
                   retry_cap=behaviour.retry_cap, form=form_of_behaviour(behaviour, basis), basis=basis,
                   scope=Scope.of(config, basis))


def profile_from(name_or_file: str, basis: str) -> Profile:
    """The oracle rules of a vehicle profile (builtin name or TOML file)."""
    from mavconform.reference_impl.profiles import load_profile
    return rules_of(load_profile(name_or_file).config, basis)


def profile_for(uri: TargetUri, vehicle: VehicleNode | None, *, chosen: str | None = None,
                autopilot: int | None = None, mav_type: int | None = None) -> Profile:
    """The oracle rules of the profile the target is held to (stored_form.modelling_profile,
    the one choice every consumer makes): a mutant's are the spec's (it claims to be the spec
    vehicle), an in-process vehicle's its own, a UDP target's those of --profile, else of the
    builtin profile its HEARTBEAT names, else the spec's."""
    model = modelling_profile(str(uri), vehicle_config=vehicle.config if vehicle is not None else None,
                              mutant=uri.kind == "mutant", chosen=chosen, autopilot=autopilot, mav_type=mav_type)
    return Profile() if model is None else rules_of(*model)


class World:
    def __init__(self, target: str, seed: int, *, capture: CaptureHook | None = None,
                 atomic: bool | None = None, connection: TargetConnection | None = None,
                 profile: str | None = None, latency: float = 0.0, handover: bool = False) -> None:
        self.uri = parse_target(target)
        self.seed = seed
        self.handover = handover
        self.watch: ControlWatch | None = None       # in-process, with handover
        self.wire: WireControl | None = None         # over UDP, with handover
        self.rules = ControlRules.of(HANDOVER_CONTROL)
        self.latency = latency                 # one-way, every simulated link (in-process only)
        self.virtual = self.uri.in_process
        self.vehicle: VehicleNode | None = None
        self.guards: dict[str, GuardedNode] = {}
        self.shared = False                    # all GCSs on one socket (UDP targets)
        self.connection: TargetConnection | None = None
        self._owns_connection = False
        if self.virtual:
            self._up, self._down = self._latent(FaultModel()), self._latent(FaultModel())  # A's link; changed in place
            self._open_sim(capture)
        else:
            self._open_udp(capture, connection, seed)
        autopilot = self.connection.autopilot if self.connection is not None else None
        mav_type = self.connection.mav_type if self.connection is not None else None
        base = profile_for(self.uri, self.vehicle, chosen=profile, autopilot=autopilot, mav_type=mav_type)
        self.profile = base if atomic is None else dataclasses.replace(base, atomic=atomic)
        for gcs in (self.a, self.b, self.probe, self.mute):
            gcs.float_only = self.profile.scope.float_only

    # --- time and running -----------------------------------------------------------------
    def now(self) -> float:
        return self.driver.clock.now()

    def run_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        return self.driver.run_until(condition, timeout=max(0.0, timeout))

    def run_for(self, seconds: float) -> None:
        self.driver.run_until(_never, timeout=max(0.0, seconds))

    def set_faults(self, up: FaultModel, down: FaultModel) -> None:
        """Faults on GCS A's link from now on: `up` is what A sends, `down` what it gets (on
        top of the simulated links' own latency)."""
        install(self._up, self._latent(up))
        install(self._down, self._latent(down))

    def _latent(self, model: FaultModel) -> FaultModel:
        if not self.virtual or not self.latency:
            return model
        return dataclasses.replace(model, delay=model.delay + self.latency)

    def link_clean(self) -> bool:
        """The shared link of a UDP target has no faults now (judged over UDP only: in-process
        every link carries the simulated latency)."""
        return self._up.is_clean and self._down.is_clean

    @contextmanager
    def faults_lifted(self) -> Iterator[None]:
        """A clean link while the body runs, where the probe shares A's (UDP targets); the
        faults as they were (rule counters included) afterwards."""
        if not self.shared:
            yield
            return
        saved = copy.copy(self._up), copy.copy(self._down)
        self.set_faults(FaultModel(), FaultModel())
        try:
            yield
        finally:
            self.set_faults(*saved)

    # --- what can be seen of the vehicle (in-process only) ----------------------------------
    def stored(self, t: MissionType) -> tuple | None:
        return None if self.vehicle is None else self.vehicle.store.items(t)

    def vehicle_idle(self) -> bool:
        """In-process only; a vehicle whose profile has no way back to idle (no upload timers,
        a GCS's cancel unread: INAV) is not held to it."""
        return self.vehicle is None or not self.profile.scope.returns_to_idle or self.vehicle.server.is_idle()

    def quiet(self) -> bool:
        """Nothing in flight (virtual time; over UDP in-flight datagrams cannot be seen)."""
        return not self.virtual or self.driver.in_flight() == 0

    def control_error(self) -> BaseException | None:
        """An exception in our control judge (inside the vehicle's calls): a bug of ours."""
        return self.watch.error if self.watch is not None else None

    def crashes(self) -> list[str]:
        """Exceptions the target raised (an in-process vehicle): a finding."""
        return [f"{name}: {g.crash}" for name, g in self.guards.items()
                if g.crash is not None and name not in OUR_NODES]

    def tool_crash(self) -> BaseException | None:
        """An exception one of our own GCS nodes raised: a bug of ours, not the target's."""
        for name in OUR_NODES:
            g = self.guards.get(name)
            if g is not None and g.crash is not None:
                return g.exception or RuntimeError(f"GCS {name}: {g.crash}")
        return None

    def heartbeat_age(self) -> float | None:
        """Seconds since the target's last HEARTBEAT (UDP targets; None in-process)."""
        return None if self.connection is None else self.connection.heartbeat_age()

    def close(self) -> None:
        if self.connection is not None and self._owns_connection:
            self.connection.close()

    # --- wiring ---------------------------------------------------------------------------
    def _gcs(self, system: int, target: Any, *, heartbeat: bool, mute: bool = False,
             control: bool = False) -> FuzzGcs:
        return FuzzGcs(system, COMPONENT, target, heartbeat=heartbeat, mute=mute,
                       timings=None if self.virtual else UDP_GCS_TIMINGS,
                       wall_clock=self.driver.clock.wall, control=control)

    @property
    def gcss(self) -> dict[str, FuzzGcs]:
        return {"a": self.a, "b": self.b, "mute": self.mute}

    def _open_sim(self, capture: CaptureHook | None) -> None:
        net = self.driver = SimNetwork(self.seed)
        # Each fuzz GCS (a, b, the mute one, the probe) has an address of its own here, so the
        # vehicle must read them all: a profile's single-peer link (VARIANTS.md L1/L2) would
        # hear only the first. Several identities on one link is the UDP fuzzer's to learn.
        extra = {"control": HANDOVER_CONTROL} if self.handover else {}
        self.vehicle = build_vehicle(self.uri, single_peer_link=False, **extra)
        cfg = self.vehicle.config
        target = (cfg.system, cfg.component)
        ho = self.handover
        self.a = self._gcs(SYSTEM_A, target, heartbeat=ho, control=ho)
        self.b = self._gcs(SYSTEM_B, target, heartbeat=ho, control=ho)
        self.probe = self._gcs(SYSTEM_PROBE, target, heartbeat=False)
        self.mute = self._gcs(SYSTEM_MUTE, target, heartbeat=False, mute=True)
        self.target = target
        node: Any = self.vehicle
        if ho:
            if self.vehicle.control is None:
                raise UsageError(f"--operator-control: {self.uri} was built without operator control")
            node = self.watch = ControlWatch(self.vehicle, self.rules, describe_system)
        self._guard(net.add_node, "vehicle", node)
        for name, gcs in (("a", self.a), ("b", self.b), ("probe", self.probe), ("mute", self.mute)):
            self._guard(net.add_node, name, gcs)
            gcs.endpoint.add_address("vehicle")
        net.connect("a", "vehicle", a_to_b=self._up, b_to_a=self._down)
        for name in ("b", "probe", "mute"):
            net.connect(name, "vehicle", a_to_b=self._latent(FaultModel()), b_to_a=self._latent(FaultModel()))
        if capture is not None:
            net.add_capture(capture)

    def _open_udp(self, capture: CaptureHook | None, connection: TargetConnection | None,
                  seed: int) -> None:
        """GCS nodes on the campaign's connection (or on one of our own, for a replay)."""
        if connection is None:   # TargetUnresponsive if it never says HEARTBEAT
            connection = TargetConnection(self.uri, seed=seed, capture=capture)
            self._owns_connection = True
        self.connection = connection
        self.driver = connection.driver
        self._up, self._down = connection.up, connection.down
        self.shared = True
        self.target = connection.target
        ho = self.handover
        self.a = self._gcs(SYSTEM_A, self.target, heartbeat=True, control=ho)
        self.b = self._gcs(SYSTEM_B, self.target, heartbeat=ho, control=ho)
        if ho:
            self.wire = WireControl(describe_system)
        self.probe = self._gcs(SYSTEM_PROBE, self.target, heartbeat=False)
        self.mute = self._gcs(SYSTEM_MUTE, self.target, heartbeat=False, mute=True)
        for gcs in (self.a, self.b, self.probe, self.mute):
            gcs.endpoint.add_address(connection.address)
        connection.attach([self._guarded(name, gcs) for name, gcs in
                           (("a", self.a), ("b", self.b), ("probe", self.probe), ("mute", self.mute))])

    def _guard(self, add: Callable[..., Any], name: str, node: Any) -> None:
        guard = self.guards[name] = GuardedNode(node)
        add(name, guard)

    def _guarded(self, name: str, node: Any) -> GuardedNode:
        guard = self.guards[name] = GuardedNode(node)
        return guard


def describe_system(sysid: int) -> str:
    """A GCS by the name the findings use (A, B, the probe, the mute one), else by its id."""
    return NAMES.get(sysid, f"GCS {sysid}")


def _never() -> bool:
    return False
