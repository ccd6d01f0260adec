"""An open connection to a target: the driver, the testers, and what we learned about it.

In-process targets (`builtin:`, `mutant:`) put our vehicle node on the same driver as the
tester, so one single-threaded loop serves both ends: over real UDP loopback sockets by
default, or over `SimNetwork` in virtual time (`virtual=True`, used by the suite's own
negative-control tests, where thousands of protocol seconds cost milliseconds).

The testers' sockets are ours: what their kernel receive queues drop never reached us, so a
gap it leaves in the target's packet sequence is not the target's (each tester knows its
socket's `receive_queue`; the run's `receive_facts` are for the reports).
"""

from __future__ import annotations

import dataclasses
import time

from typing import Any, Callable

from mavconform.reference_impl.mission.messages import is_vehicle_heartbeat
from mavconform.reference_impl.net.clock import MonotonicClock, ScaledClock
from mavconform.reference_impl.net.guard import GuardedNode
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.net.receive_queue import total_drops
from mavconform.reference_impl.net.shared_link import SharedLink
from mavconform.reference_impl.net.sim import CaptureHook, SimNetwork
from mavconform.reference_impl.net.udp import UdpDriver
from mavconform.reference_impl.net.uri import local_bind_for
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

from .harness.link_timing import link_facts, stream_events
from .harness.tester import Tester, record_traffic
from .harness.stored_form import modelling_profile, stored_form_of
from .harness.tester_node import TesterNode
from .outcome import TargetUnresponsive
from .target_uri import TargetUri

TESTER_SYSTEM, TESTER2_SYSTEM, TESTER_COMPONENT = 245, 246, 190   # 190: MAV_COMP_ID_MISSIONPLANNER
DISCOVERY_TIMEOUT = 5.0   # s for the first HEARTBEAT (heartbeats are 1 Hz), scaled
# A builtin vehicle in a real-time run flies this many times faster than real (legs, climbs and
# descents; holds and protocol timers keep their length), as one runs SITL with --speedup: its
# flights are protocol exchanges spread over minutes of waiting, not what a clause judges
BUILTIN_FLIGHT_SPEEDUP = 4.0
# An in-process target and its testers share one clock, by default this many times real time
# (reference_impl/net/clock.ScaledClock): every timer, stream, timeout and bound runs in that
# clock's seconds, so the run judges what a real-time one does in a quarter of the wall time.
# An external target lives in real time (1).
BUILTIN_CLOCK_SPEED = 4.0


def build_vehicle(uri: TargetUri, *, wall_clock: Callable[[], float] = time.time,
                  base: VehicleConfig | None = None, **config: Any) -> VehicleNode:
    """The in-process vehicle a `builtin:` or `mutant:` target names, with `VehicleConfig`
    fields overridden by `config` (the fuzzers run signing vehicles). `wall_clock` feeds
    the signing timestamps of builtin vehicles; mutants are built as they declare. `base`:
    a builtin vehicle from this config instead of its profile's (the knob matrix builds
    vehicles knob by knob, conformance/knob_judges.py)."""
    if uri.kind == "mutant":
        from .mutants import MUTANTS
        return MUTANTS[uri.name].build(dataclasses.replace(VehicleConfig(), **config))
    if base is None:
        base = VehicleConfig()
        if uri.name != "spec":
            from mavconform.reference_impl.profiles import load_profile
            base = load_profile(uri.name).config
    return VehicleNode(dataclasses.replace(base, **config), wall_clock=wall_clock)


class Session:
    """What a check receives. `t` is the scripted GCS; `second()` a second GCS.

    `shared_link`: the second GCS speaks from the first one's socket (another system id on
    the same link, routed by target_system), as a target whose GCS link is bound to one
    peer needs (VARIANTS.md L1, L2). Default: shared for every external target and for an
    in-process vehicle whose profile models such a link; a socket of its own otherwise.

    `config`: a `builtin:` target's vehicle built from this `VehicleConfig` instead of its
    profile's (the suite's own overrides still apply), so a test can run the clauses against
    a vehicle with any set of knobs (conformance/knob_judges.py).

    `clock_speed`: for an in-process target over real sockets, how many clock seconds the
    vehicle and the testers live in each real one (None: BUILTIN_CLOCK_SPEED; an external
    target: 1, the only speed it can have)."""

    def __init__(self, uri: TargetUri, *, scale: float = 1.0, virtual: bool = False,
                 seed: int = 0, allow_flight: bool | None = None,
                 capture: CaptureHook | None = None, shared_link: bool | None = None,
                 config: VehicleConfig | None = None, clock_speed: float | None = None) -> None:
        if config is not None and uri.kind != "builtin":
            raise ValueError("a vehicle config replaces a builtin target's profile only")
        if clock_speed is None:
            clock_speed = BUILTIN_CLOCK_SPEED if uri.in_process and not virtual else 1.0
        elif clock_speed != 1.0 and not (uri.in_process and not virtual):
            raise ValueError("only an in-process target over real sockets runs on a faster clock")
        self.clock_speed = clock_speed
        self.uri = uri
        self.scale = scale
        self.virtual = virtual
        self.allow_flight = uri.in_process if allow_flight is None else allow_flight
        self.cache: dict[str, Any] = {}        # observations several clauses share
        self._observed_lag: dict[str, float] = {}   # shared(): the driver's lag while each was made
        self.current_clause = ""
        # how every flight ended (harness.landing): the clause that flew, the style, the plan,
        # disarmed or not; the run report shows them, and one left armed fails the run
        self.flights: list[dict[str, Any]] = []
        # told the target's identity once its HEARTBEAT came (the expectations for its vehicle type)
        self.on_identity: Callable[[dict[str, Any]], None] | None = None
        self.identity: dict[str, Any] | None = None
        self.vehicle: VehicleNode | None = None
        self.guard: GuardedNode | None = None   # an in-process vehicle that raises stops here
        self.target_address: Any = None
        self._second: Tester | None = None
        self._more: dict[int, Tester] = {}      # GCSs with other system ids (`gcs`)
        node = TesterNode("tester", TESTER_SYSTEM, TESTER_COMPONENT)
        self.link = SharedLink(node)
        self._sockets: list[Any] = [self.link]   # the testers' own: the link, GCSs apart
        if virtual:
            if not uri.in_process:
                raise ValueError("virtual time needs an in-process target")
            self.driver: Any = SimNetwork(seed)
            self.vehicle = build_vehicle(uri, base=config, **uri.suite_overrides())
            self.guard = GuardedNode(self.vehicle)
            self.driver.add_node("vehicle", self.guard)
            self.driver.add_node("tester", self.link)
            self.driver.connect("tester", "vehicle")
            self.target_address = "vehicle"
            self.vehicle.endpoint.add_address("tester")
            node.endpoint.add_address("vehicle")
        else:
            clock = ScaledClock(clock_speed) if clock_speed != 1.0 else MonotonicClock()
            self.driver = UdpDriver(clock, seed=seed)
            try:
                if uri.in_process:
                    self.vehicle = build_vehicle(uri, base=config, **uri.suite_overrides(),
                                                 wall_clock=clock.wall, flight_speedup=BUILTIN_FLIGHT_SPEEDUP)
                    self.guard = GuardedNode(self.vehicle)
                    self.target_address = self.driver.add_node(self.guard)
                    tester_address = self.driver.add_node(self.link)
                    node.endpoint.add_address(self.target_address)
                    # in-process, the vehicle may know us from the start: no 1 s wait for
                    # its first HEARTBEAT to find a listener
                    self.vehicle.endpoint.add_address(tester_address)
                else:   # udpin: the target finds us (its address is learnt on discovery)
                    self.target_address, _ = attach(self.driver, self.link, uri.link)
                    if self.target_address is not None:
                        node.endpoint.add_address(self.target_address)
            except BaseException:
                self.driver.close()
                raise
        if shared_link is None:
            shared_link = self.vehicle.config.single_peer_link if self.vehicle is not None else True
        self.shared_link = shared_link
        node.receive_queue = self.driver.receive_queue(self.link)
        self.capture = capture   # its `mark`, if it has one, labels where each clause starts
        if capture is not None:
            self.driver.add_capture(capture)
        self.stream = None if virtual else self.driver.stream_of(self.link)   # tcp:, serial: ...
        self.link_facts = link_facts("in-process" if uri.in_process else uri.kind, self.stream)
        if clock_speed != 1.0:
            self.link_facts["clock_speed"] = clock_speed
        self.t = Tester(node, self.driver, scale=scale)
        self.t.link_allowance = self.link_facts["reply_allowance_s"]
        self.t.int_forms = not self._profile_ignores_int()   # the forms probe may still find out
        record_traffic(self.t)

    # --- lifecycle ------------------------------------------------------------------------
    def discover(self, timeout: float = DISCOVERY_TIMEOUT) -> dict[str, Any]:
        """Wait for the target's HEARTBEAT; its ids become the testers' target."""
        node = self.t.node
        found: list[Any] = []

        def heartbeat() -> bool:
            for _, frame in node.inbox:
                msg = frame.msg
                if is_vehicle_heartbeat(msg):
                    found.append(frame)
                    return True
            return False

        wait = timeout * self.scale
        if not self.driver.run_until(heartbeat, timeout=wait):
            where = self.uri
            raise TargetUnresponsive(f"no HEARTBEAT from {where} within {wait:g} s "
                                     "(is it running, and is the address right?)")
        frame = found[0]
        node.target = (frame.src_system, frame.src_component)
        node.inbox = [(t, f) for t, f in node.inbox if (f.src_system, f.src_component) == node.target]
        node.last_heard = self.t.now()
        if self.target_address is None:
            self.target_address = node.endpoint.peers.get(node.target)
        self.t.target = node.target
        msg = frame.msg
        self.t.form = stored_form_of(modelling_profile(
            str(self.uri), vehicle_config=self.vehicle.config if self.vehicle is not None else None,
            mutant=self.uri.kind == "mutant", chosen=self.uri.profile, autopilot=msg.autopilot, mav_type=msg.type))
        self.identity = {
            "system": frame.src_system, "component": frame.src_component, "type": msg.type,
            "autopilot": msg.autopilot, "mavlink_version": frame.version,
            "address": _label(self.target_address), "stored_form": self.t.form.describe()}
        if self.on_identity is not None:
            self.on_identity(self.identity)
        return self.identity

    def _profile_ignores_int(self) -> bool:
        """Does the target's profile (its builtin vehicle's, or --profile's) say it ignores
        the _INT mission messages (INAV 9.1)?"""
        if self.vehicle is not None:
            return self.vehicle.config.int_forms_ignored
        if self.uri.profile is None:
            return False
        from mavconform.reference_impl.profiles import load_profile
        return load_profile(self.uri.profile).int_messages_ignored

    def record_flight(self, style: str, plan: str, ending: Any) -> None:
        """Keep how a flight ended (a `landing.Ending`) for the run report."""
        self.flights.append({"clause": self.current_clause, "style": style, "plan": plan, **ending.as_dict()})

    def second(self) -> Tester:
        """A second GCS (another system id; on the first one's link or a socket of its own,
        as `shared_link` says), created on first use."""
        if self._second is None:
            self._second = self._new_gcs("tester2", TESTER2_SYSTEM)
        return self._second

    def gcs(self, system: int) -> Tester:
        """The GCS with system id `system`: the first or the second GCS when it is theirs,
        else one more made as the second is, on first use (the handover clauses play the
        GCSs a handover scenario names). It shares the first GCS's exchange for the clause
        that makes it; a check that uses it in a later clause gives it that clause's."""
        if system == self.t.node.endpoint.system:
            return self.t
        if system == TESTER2_SYSTEM:
            return self.second()
        if system not in self._more:
            self._more[system] = self._new_gcs(f"gcs{system}", system)
        return self._more[system]

    def _new_gcs(self, name: str, system: int) -> Tester:
        """A GCS with system id `system`, on the first one's link or a socket of its own."""
        node = TesterNode(name, system, TESTER_COMPONENT)
        node.target = self.t.node.target
        if self.shared_link:
            self.link.join(node)
            node.receive_queue = self.t.node.receive_queue
        elif self.virtual:
            self.driver.add_node(name, node)
            self.driver.connect(name, "vehicle")
            self._sockets.append(node)
        else:
            host = self.target_address[0] if isinstance(self.target_address, tuple) else "127.0.0.1"
            self.driver.add_node(node, bind=(local_bind_for(host), 0))
            self._sockets.append(node)
        if not self.shared_link:
            node.receive_queue = self.driver.receive_queue(node)
        node.endpoint.add_address(self.target_address)
        tester = Tester(node, self.driver, scale=self.scale)
        tester.link_allowance = self.t.link_allowance
        tester.int_forms, tester.translate = self.t.int_forms, self.t.translate
        tester.form = self.t.form
        tester.plan_ids = self.t.plan_ids   # one record of accepted plans for all GCSs
        tester.replaced_ids = self.t.replaced_ids
        tester.exchange = self.t.exchange
        record_traffic(tester)
        # announce it (a HEARTBEAT), so the target learns where it lives
        node.poll(self.t.now())
        self.driver.run_until(_always, timeout=0.0)
        return tester

    def shared(self, key: str, observe: Callable[[], Any]) -> Any:
        """An observation several clauses decide from (e.g. one silent upload serves the
        retry count, the retry interval and the give-up clauses): made once per run, and
        its exchange copied into every clause that uses it, so each keeps its evidence.
        The driver's lag while it was made goes with it: a clause that decides from it was
        judged under that lag (conformance/host_lag.py)."""
        exchange = self.t.exchange
        driver = self.driver
        if key in self.cache:
            value, events, owner, decided = self.cache[key]
            if exchange is not None:
                exchange.note(self.t.now(), "tester", f"the exchange below was recorded for {owner} "
                              "and is shared with this clause (times are from that clause)")
                exchange.events.extend(events)
                if decided is not None:   # what the observation judged, until the clause says otherwise
                    exchange.decide(decided)
            driver.lag = max(driver.lag, self._observed_lag.get(key, 0.0))
            return value
        first = len(exchange.events) if exchange is not None else 0
        outer, driver.lag = driver.lag, 0.0
        try:
            value = observe()
        finally:
            lag = driver.lag
            driver.lag = max(outer, lag)
        events = list(exchange.events[first:]) if exchange is not None else []
        index = exchange.decided_by if exchange is not None else None
        decided = exchange.events[index] if index is not None and index >= first else None
        self.cache[key] = (value, events, self.current_clause, decided)
        self._observed_lag[key] = lag
        return value

    def take_lag(self) -> float:
        """The most the driver ran behind its clock since the last call (host_lag.py)."""
        return self.driver.take_lag()

    def forget_lagged(self, tolerance: float) -> None:
        """Drop the shared observations made while the driver ran more than `tolerance`
        behind its clock, so a clause run again observes afresh."""
        for key in [k for k, lag in self._observed_lag.items() if lag > tolerance]:
            del self.cache[key], self._observed_lag[key]

    def receive_facts(self) -> dict[str, int | None]:
        """For the run's report: the datagrams all the testers' sockets dropped (None:
        unknown) and the smallest receive buffer the kernel granted them (None: unknown, or
        no socket, as in virtual time)."""
        queues = [self.driver.receive_queue(node) for node in self._sockets]
        granted = [q.granted for q in queues if q.granted is not None]
        return {"dropped": total_drops(queues), "buffer_bytes": min(granted) if granted else None}

    def link_events(self) -> dict[str, Any] | None:
        """For the run's report (volatile): what happened to a stream link (connections,
        losses, bytes, frames dropped while it was down); None on UDP."""
        return stream_events(self.stream, self.t.now())

    def testers(self) -> list[Tester]:
        return [self.t] + ([self._second] if self._second is not None else []) + list(self._more.values())

    def run_for(self, seconds: float) -> None:
        self.driver.run_until(_never, timeout=seconds * self.scale)

    def close(self) -> None:
        if not self.virtual:
            self.driver.close()

    def __enter__(self) -> "Session":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _never() -> bool:
    return False


def _always() -> bool:
    return True


def _label(address: Any) -> str | None:
    if address is None:
        return None
    if isinstance(address, tuple):
        return f"{address[0]}:{address[1]}"
    return str(address)


SessionFactory = Callable[[], Session]
