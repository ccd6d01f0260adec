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
There all four GCSs share one socket (`SharedLink`, routed by system id): a real vehicle's
GCS link is bound to one peer (VARIANTS.md L1, L2) and would never hear a GCS on a socket
of its own. The faults then act on that one link, as on a real radio link, and are lifted
while the probe asks (`faults_lifted`), so the probe still has a clean link. Every node sits in a `GuardedNode`, so a node that raises falls
silent and the exception is kept: a crash is a finding, never a traceback here.
"""

from __future__ import annotations

import copy
import dataclasses
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, Callable, Iterator

from conformance.session import build_vehicle
from conformance.target_uri import TargetUri, parse_target
from reference_impl.mission.items import MissionType
from reference_impl.mission.timing import Timings
from reference_impl.net import FaultModel, SimNetwork, UdpDriver
from reference_impl.net.guard import GuardedNode
from reference_impl.net.shared_link import SharedLink
from reference_impl.net.sim import CaptureHook
from reference_impl.net.uri import local_bind_for
from reference_impl.vehicle import VehicleNode

from .faults import install
from .gcs import FuzzGcs

SYSTEM_A, SYSTEM_B, SYSTEM_PROBE, SYSTEM_MUTE, COMPONENT = 245, 246, 247, 248, 190
DISCOVERY_TIMEOUT = 5.0   # s for the target's first HEARTBEAT (real time, UDP targets)
NON_ATOMIC_PROFILES = frozenset({"ardupilot"})   # VARIANTS A2: items written as they arrive


@dataclass(frozen=True)
class Profile:
    """What the oracles hold the target to."""

    atomic: bool = True               # an upload replaces the plan whole or not at all
    timings: Timings = Timings()      # the retry limit the vehicle must keep
    retry_cap: bool = True            # False: retries end on a protocol timeout (PX4, P3)


def profile_for(uri: TargetUri, vehicle: VehicleNode | None) -> Profile:
    """Builtin profiles are held to their own documented timings and atomicity; mutants
    and remote targets to the spec's (a mutant claims to be the spec vehicle)."""
    if uri.kind == "builtin" and vehicle is not None:
        behaviour = vehicle.server.behaviour
        return Profile(atomic=uri.name not in NON_ATOMIC_PROFILES, timings=behaviour.timings,
                       retry_cap=behaviour.retry_cap)
    return Profile()


class World:
    def __init__(self, target: str, seed: int, *, capture: CaptureHook | None = None,
                 atomic: bool | None = None) -> None:
        self.uri = parse_target(target)
        self.seed = seed
        self.virtual = self.uri.in_process
        self.vehicle: VehicleNode | None = None
        self.guards: dict[str, GuardedNode] = {}
        self.unresponsive: str | None = None   # set when a remote target never said HEARTBEAT
        self.shared = False                    # all GCSs on one socket (UDP targets)
        self._up, self._down = FaultModel(), FaultModel()   # A's link; changed in place
        if self.virtual:
            self._open_sim(capture)
        else:
            self._open_udp(capture)
        profile = profile_for(self.uri, self.vehicle)
        self.profile = profile if atomic is None else dataclasses.replace(profile, atomic=atomic)

    # --- time and running -----------------------------------------------------------------
    def now(self) -> float:
        return self.driver.clock.now()

    def run_until(self, condition: Callable[[], bool], timeout: float) -> bool:
        return self.driver.run_until(condition, timeout=max(0.0, timeout))

    def run_for(self, seconds: float) -> None:
        self.driver.run_until(_never, timeout=max(0.0, seconds))

    def set_faults(self, up: FaultModel, down: FaultModel) -> None:
        """Faults on GCS A's link from now on: `up` is what A sends, `down` what it gets."""
        install(self._up, up)
        install(self._down, down)

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
        return self.vehicle is None or self.vehicle.server.is_idle()

    def quiet(self) -> bool:
        """Nothing in flight (virtual time; over UDP in-flight datagrams cannot be seen)."""
        return not self.virtual or self.driver.in_flight() == 0

    def crashes(self) -> list[str]:
        return [f"{name}: {g.crash}" for name, g in self.guards.items() if g.crash is not None]

    def close(self) -> None:
        if not self.virtual:
            self.driver.close()

    # --- wiring ---------------------------------------------------------------------------
    def _gcs(self, system: int, target: Any, *, heartbeat: bool, mute: bool = False) -> FuzzGcs:
        return FuzzGcs(system, COMPONENT, target, heartbeat=heartbeat, mute=mute,
                       wall_clock=self.driver.clock.wall)

    @property
    def gcss(self) -> dict[str, FuzzGcs]:
        return {"a": self.a, "b": self.b, "mute": self.mute}

    def _open_sim(self, capture: CaptureHook | None) -> None:
        net = self.driver = SimNetwork(self.seed)
        # Each fuzz GCS (a, b, the mute one, the probe) has an address of its own here, so the
        # vehicle must read them all: a profile's single-peer link (VARIANTS.md L1/L2) would
        # hear only the first. Several identities on one link is the UDP fuzzer's to learn.
        self.vehicle = build_vehicle(self.uri, single_peer_link=False)
        cfg = self.vehicle.config
        target = (cfg.system, cfg.component)
        self.a = self._gcs(SYSTEM_A, target, heartbeat=False)
        self.b = self._gcs(SYSTEM_B, target, heartbeat=False)
        self.probe = self._gcs(SYSTEM_PROBE, target, heartbeat=False)
        self.mute = self._gcs(SYSTEM_MUTE, target, heartbeat=False, mute=True)
        self.target = target
        self._guard(net.add_node, "vehicle", self.vehicle)
        for name, gcs in (("a", self.a), ("b", self.b), ("probe", self.probe), ("mute", self.mute)):
            self._guard(net.add_node, name, gcs)
            gcs.endpoint.add_address("vehicle")
        net.connect("a", "vehicle", a_to_b=self._up, b_to_a=self._down)
        for name in ("b", "probe", "mute"):
            net.connect(name, "vehicle")
        if capture is not None:
            net.add_capture(capture)

    def _open_udp(self, capture: CaptureHook | None) -> None:
        driver = self.driver = UdpDriver(seed=self.seed)
        try:
            udp = self.uri.udp
            bind_host = local_bind_for(udp.host)
            self.a = self._gcs(SYSTEM_A, None, heartbeat=True)
            self.b = self._gcs(SYSTEM_B, None, heartbeat=True)
            self.probe = self._gcs(SYSTEM_PROBE, None, heartbeat=True)
            self.mute = self._gcs(SYSTEM_MUTE, None, heartbeat=True, mute=True)
            if capture is not None:
                driver.add_capture(capture)
            link = SharedLink(self._guarded("a", self.a))
            self.shared = True
            bind = (bind_host, 0) if self.uri.kind == "udp" else udp.address   # udpin: it sends first
            driver.add_node(link, bind=bind, outgoing=self._up, incoming=self._down)
            if self.uri.kind == "udp":
                self.a.endpoint.add_address(udp.address)
            if not driver.run_until(lambda: self.a.target is not None, timeout=DISCOVERY_TIMEOUT):
                self.unresponsive = (f"no HEARTBEAT from {self.uri} within {DISCOVERY_TIMEOUT:g} s "
                                     "(is it running, and is the address right?)")
                self.target = None
                return
            self.target = self.a.target
            address = self.a.endpoint.peers.get(self.target, udp.address)
            for name, gcs in (("b", self.b), ("probe", self.probe), ("mute", self.mute)):
                gcs.set_target(self.target)
                link.join(self._guarded(name, gcs))
                gcs.endpoint.add_address(address)
        except BaseException:
            driver.close()
            raise

    def _guard(self, add: Callable[..., Any], name: str, node: Any) -> None:
        guard = self.guards[name] = GuardedNode(node)
        add(name, guard)

    def _guarded(self, name: str, node: Any) -> GuardedNode:
        guard = self.guards[name] = GuardedNode(node)
        return guard


def _never() -> bool:
    return False
