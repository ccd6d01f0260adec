"""The reference GCS against a profiled vehicle in virtual time: wiring and checks shared by
the fault-tolerance table, the round-trip report and the interop tests.

The GCS is left to choose its adaptations from the vehicle's HEARTBEAT, as it does in the
field; nothing here tells it which profile it talks to. The checks read the vehicle's store
directly (never through the GCS under test), so a GCS bug cannot hide itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from ..gcs import GcsNode
from ..mission.items import MissionItem, MissionType, renumber
from ..mission.results import OperationResult
from ..net import FaultModel, SimNetwork
from ..profiles import Profile

RESULT_BOUND = 120.0   # virtual s: an operation with no result by then hangs
IDLE_BOUND = 30.0      # virtual s after a result for both ends to be idle again
VEHICLE_ADDRESS, GCS_ADDRESS = "vehicle", "gcs"


@dataclass
class Pair:
    """A GCS and a (possibly wrapped) profiled vehicle on one SimNetwork."""

    net: SimNetwork
    profile: Profile
    vehicle: Any          # the VehicleNode (the wrapper's inner node, if wrapped)
    gcs: GcsNode

    @property
    def now(self) -> float:
        return self.net.clock.now()

    def run(self, start: Callable[[float], None], *, bound: float = RESULT_BOUND) -> OperationResult | None:
        """Start an operation and run until its result; None if none came within `bound`."""
        done = len(self.gcs.results)
        start(self.now)
        if not self.net.run_until(lambda: len(self.gcs.results) > done, timeout=bound):
            return None
        return self.gcs.results[done]

    def upload(self, t: MissionType, items: list[MissionItem]) -> OperationResult | None:
        return self.run(lambda now: self.gcs.upload(t, items, now))

    def download(self, t: MissionType) -> OperationResult | None:
        return self.run(lambda now: self.gcs.download(t, now))

    def clear(self, t: MissionType) -> OperationResult | None:
        return self.run(lambda now: self.gcs.clear(t, now))

    def set_current(self, seq: int) -> OperationResult | None:
        return self.run(lambda now: self.gcs.set_current(seq, now))

    def idle(self) -> bool:
        return self.vehicle.server.is_idle() and not self.gcs.busy

    def settle(self, bound: float = IDLE_BOUND) -> float | None:
        """Run until both ends are idle and nothing is in flight (as a user's next click comes
        after the link went quiet: MISSION_ACK carries no id, so a late duplicate of one
        operation's ACK could otherwise pass for the next one's); the virtual seconds it
        took, or None past `bound`."""
        start = self.now
        if not self.net.run_until(lambda: self.idle() and self.net.in_flight() == 0, timeout=bound):
            return None
        return self.now - start

    def held(self, t: MissionType) -> tuple[MissionItem, ...]:
        """The plan the vehicle holds, as a download would return it (without its home)."""
        return held_plan(self.profile, self.vehicle, t)


def held_plan(profile: Profile, vehicle: Any, t: MissionType) -> tuple[MissionItem, ...]:
    items = vehicle.store.items(t)
    if t is MissionType.MISSION and profile.behaviour.home_at_seq0 and items:
        items = items[1:]    # the vehicle's seq 0 is its home (A1)
    return tuple(renumber(items))


def expected_plan(profile: Profile, items: list[MissionItem], t: MissionType) -> tuple[MissionItem, ...]:
    """What the profile documents a download returns after uploading `items`."""
    return tuple(renumber(profile.stored_items(renumber(items, t), t)))


def build_pair(profile: Profile, *, seed: int = 0, up: FaultModel | None = None,
               down: FaultModel | None = None, wrap: Callable[[Any], Any] | None = None,
               heartbeat_bound: float = 10.0) -> Pair:
    """Wire a fresh GCS to a fresh `profile` vehicle (wrapped by `wrap`, if given) and wait
    for the GCS to discover it."""
    net = SimNetwork(seed=seed)
    vehicle = profile.vehicle()
    gcs = GcsNode(remote=VEHICLE_ADDRESS, wall_clock=net.clock.wall)
    net.add_node(VEHICLE_ADDRESS, wrap(vehicle) if wrap is not None else vehicle)
    net.add_node(GCS_ADDRESS, gcs)
    net.connect(GCS_ADDRESS, VEHICLE_ADDRESS, a_to_b=up, b_to_a=down)
    if not net.run_until(lambda: gcs.connected, timeout=heartbeat_bound):
        raise RuntimeError(f"profile {profile.name}: the vehicle sent no HEARTBEAT within {heartbeat_bound:g} s")
    return Pair(net, profile, vehicle, gcs)


def sample_plan(n: int, t: MissionType = MissionType.MISSION, *, shift: int = 0) -> list[MissionItem]:
    """A small valid plan of `t` (global waypoints, fence circles or rally points)."""
    out = []
    for i in range(n):
        x, y = 473977420 + 1000 * (i + shift), 85455940 - 700 * (i + shift)
        if t is MissionType.FENCE:
            out.append(MissionItem(i, 0, 5003, param1=100.0 + i, x=x, y=y, mission_type=t))
        elif t is MissionType.RALLY:
            out.append(MissionItem(i, 3, 5100, x=x, y=y, z=30.0, mission_type=t))
        else:
            out.append(MissionItem(i, 3, 16, x=x, y=y, z=50.0 + i + shift, mission_type=t))
    return out
