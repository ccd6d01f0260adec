"""The chaos proxy: a bad radio link to put between a real GCS and a real vehicle.

A GCS sends to the proxy's listen port; the proxy passes each datagram through the uplink
`FaultModel` and sends what survives to the vehicle from a *leg*: a port of its own, one per
GCS, so the vehicle sees each GCS at a distinct address and its replies, arriving on that
leg, go back (through the downlink `FaultModel`) to the GCS that owns it, from the listen
port the GCS sent to. The leg table is bounded (`max_legs`): when it is full, a new GCS
takes over the leg of the GCS that has been quiet longest.

`ChaosProxy` is sans-IO, like the engines: datagrams and the time in, datagrams per port
out, `next_deadline()` for the faults' delays. Its fault decisions come from its own RNGs,
seeded from `seed` and the direction, so a run under `SimNetwork` repeats exactly. It keeps
per-direction `LinkStats` (`sent` = datagrams into the proxy, `delivered` = out of it) and
reports every datagram to capture hooks as the link it stands for: `tx` when the sender's
datagram reaches the proxy, `drop` when a fault (or a full delay queue) eats it, `rx` when
a copy, possibly corrupted, leaves for its destination; source and destination are the GCS
and the vehicle, so an `McapCapture` gets one channel per direction and GCS (a frame's `rx`
copy is kept only when it differs from its `tx`: a duplicate or a corrupted one).

Two adapters move its datagrams:
- `UdpProxy`: on a `UdpDriver`, the listen socket plus one socket per leg, opened when a
  GCS first speaks (the driver may host the GCS and the vehicle too). Either side may be a
  stream link instead (TCP, a serial line: `mavconform proxy --listen tcpin:5760 --forward
  serial:/dev/ttyACM0`): a stream has one peer, so a stream listen serves one GCS, and a
  stream forward is one connection, one leg (`max_legs` 1).
- `ProxyNode`: one `DatagramNode` at one address, for `SimNetwork` (whose loop steps one
  node at a time, so a datagram must leave the node that received it): one leg, and the
  vehicle's replies go to the GCS that spoke last.
"""

from __future__ import annotations

import random
from collections import OrderedDict, deque
from heapq import heappop, heappush
from itertools import count
from typing import Any

from mavconform.reference_impl.net.capture import address_label
from mavconform.reference_impl.net.faults import FaultModel, LinkStats
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.net.sim import CaptureHook, CaptureRecord, stable_seed
from mavconform.reference_impl.net.links import attach, open_stream
from mavconform.reference_impl.net.uri import LinkUri, UdpUri, local_bind_for

UP, DOWN = "up", "down"          # gcs -> vehicle, vehicle -> gcs
FRONT = -1                       # the listen port; legs are numbered 0..max_legs-1
MAX_LEGS = 16
MAX_PENDING = 4096               # delayed datagrams held at once; more are dropped (counted)
MAX_EVENTS = 100                 # UdpProxy.events kept unread


class ChaosProxy:
    """Relays datagrams between GCSs and one vehicle at `forward`, with faults each way."""

    def __init__(self, forward: Address, *, up: FaultModel | None = None,
                 down: FaultModel | None = None, seed: int = 0, max_legs: int = MAX_LEGS,
                 max_pending: int = MAX_PENDING) -> None:
        if max_legs < 1:
            raise ValueError(f"ChaosProxy needs max_legs >= 1, got {max_legs}")
        if max_pending < 0:
            raise ValueError(f"ChaosProxy needs max_pending >= 0, got {max_pending}")
        if up is not None and down is up:
            down = up.copy()   # rule counters belong to one direction
        self.forward = forward
        self.faults = {UP: up, DOWN: down}
        self.max_legs, self.max_pending = max_legs, max_pending
        self.stats = {UP: LinkStats(), DOWN: LinkStats()}
        self.stray = 0           # ignored: at a leg from anyone but the vehicle, or the
                                 # vehicle's own at the listen port (relaying it would loop)
        self.overflowed = 0      # copies dropped because MAX_PENDING were already delayed
        self.reassigned = 0      # legs handed to a new GCS because the table was full
        self._rng = {d: random.Random(stable_seed(seed, "chaos-proxy", d)) for d in (UP, DOWN)}
        self._legs: OrderedDict[Address, int] = OrderedDict()   # gcs -> leg, quietest first
        self._leg_gcs: list[Address] = []                       # leg -> gcs
        self._queues: dict[int, list[tuple[bytes, Address]]] = {FRONT: []}
        self._timers: list[tuple[float, int, str, int, Address, Address, bytes]] = []
        self._tiebreak = count()
        self._hooks: list[CaptureHook] = []

    # -- wiring -------------------------------------------------------------------------

    def add_capture(self, hook: CaptureHook) -> None:
        """Call `hook(CaptureRecord)` for every datagram in either direction (see module doc)."""
        self._hooks.append(hook)

    @property
    def legs_in_use(self) -> int:
        """Legs handed out so far (each needs a port); never more than `max_legs`."""
        return len(self._leg_gcs)

    def gcs_of(self, leg: int) -> Address:
        return self._leg_gcs[leg]

    def leg_of(self, gcs: Address) -> int | None:
        return self._legs.get(gcs)

    def pending(self) -> int:
        """Delayed copies not yet released."""
        return len(self._timers)

    # -- datagrams in -------------------------------------------------------------------

    def from_gcs(self, data: bytes, gcs: Address, now: float) -> int | None:
        """A datagram reached the listen port from `gcs`; returns the leg that carries it
        (None: it came from the vehicle itself, which would loop, so it is ignored)."""
        if gcs == self.forward:
            self.stray += 1
            return None
        leg = self._legs.get(gcs)
        if leg is None:
            if len(self._leg_gcs) < self.max_legs:
                leg = len(self._leg_gcs)
                self._leg_gcs.append(gcs)
                self._queues[leg] = []
            else:
                _, leg = self._legs.popitem(last=False)
                self._leg_gcs[leg] = gcs
                self.reassigned += 1
            self._legs[gcs] = leg
        else:
            self._legs.move_to_end(gcs)
        self._pass(UP, data, gcs, self.forward, leg, now)
        return leg

    def from_vehicle(self, data: bytes, leg: int, source: Address, now: float) -> None:
        """A datagram reached leg `leg` from `source`; only the vehicle's are relayed."""
        if source != self.forward or not 0 <= leg < len(self._leg_gcs):
            self.stray += 1
            return
        self._pass(DOWN, data, source, self._leg_gcs[leg], FRONT, now)

    # -- time and datagrams out ---------------------------------------------------------

    def next_deadline(self) -> float | None:
        return self._timers[0][0] if self._timers else None

    def poll(self, now: float) -> None:
        """Release the delayed copies that are due, in due order (ties: arrival order)."""
        timers = self._timers
        while timers and timers[0][0] <= now:
            _, _, direction, port, src, dst, data = heappop(timers)
            self._release(direction, port, src, dst, data, now)

    def take_outgoing(self, port: int) -> list[tuple[bytes, Address]]:
        """What port `port` (FRONT or a leg) must send, with destinations; clears it."""
        queue = self._queues.get(port)
        if not queue:
            return []
        self._queues[port] = []
        return queue

    # -- internals ----------------------------------------------------------------------

    def _pass(self, direction: str, data: bytes, src: Address, dst: Address, port: int,
              now: float) -> None:
        stats = self.stats[direction]
        stats.sent += 1
        if self._hooks:
            self._emit(now, src, dst, data, "tx")
        fault = self.faults[direction]
        if fault is None or fault.is_clean:
            self._release(direction, port, src, dst, data, now)
            return
        copies = fault.schedule(data, now, self._rng[direction], stats)
        if not copies and self._hooks:
            self._emit(now, src, dst, data, "drop")
        for delay, payload in copies:
            if delay <= 0.0:
                self._release(direction, port, src, dst, payload, now)
            elif len(self._timers) >= self.max_pending:
                self.overflowed += 1
                stats.dropped += 1
                if self._hooks:
                    self._emit(now, src, dst, payload, "drop")
            else:
                heappush(self._timers, (now + delay, next(self._tiebreak), direction, port,
                                        src, dst, payload))

    def _release(self, direction: str, port: int, src: Address, dst: Address, data: bytes,
                 now: float) -> None:
        self.stats[direction].delivered += 1
        if self._hooks:
            self._emit(now, src, dst, data, "rx")
        self._queues[port].append((data, dst))

    def _emit(self, now: float, src: Address, dst: Address, data: bytes, kind: str) -> None:
        rec = CaptureRecord(now, src, dst, data, kind)
        for hook in self._hooks:
            hook(rec)


class _Port:
    """One socket of the proxy as a `DatagramNode` on a `UdpDriver`."""

    __slots__ = ("owner", "port")

    def __init__(self, owner: "UdpProxy", port: int) -> None:
        self.owner, self.port = owner, port

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        owner = self.owner
        if self.port == FRONT:
            owner.proxy.from_gcs(data, source, now)
            owner.open_legs()
        else:
            owner.proxy.from_vehicle(data, self.port, source, now)

    def poll(self, now: float) -> None:
        self.owner.proxy.poll(now)

    def next_deadline(self) -> float | None:
        # The listen port speaks for the proxy's timers: one poll releases every port's copies.
        return self.owner.proxy.next_deadline() if self.port == FRONT else None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.owner.proxy.take_outgoing(self.port)


class UdpProxy:
    """A `ChaosProxy` on a `UdpDriver`: binds the listen socket now, a leg socket (port 0,
    on the interface that reaches the vehicle) whenever a new GCS needs one."""

    def __init__(self, driver: Any, proxy: ChaosProxy, *,
                 listen: tuple[str, int] | LinkUri = ("127.0.0.1", 0),
                 forward_link: LinkUri | None = None) -> None:
        """`listen`: an address to bind, or any link address (a stream serves one GCS);
        `forward_link`: a tcp: or serial: vehicle, reached over a stream (one leg)."""
        self.driver, self.proxy = driver, proxy
        forward = proxy.forward
        self.leg_host = local_bind_for(forward[0]) if isinstance(forward, tuple) else "127.0.0.1"
        self.forward_link = None if isinstance(forward_link, UdpUri) else forward_link
        if self.forward_link is not None and proxy.max_legs != 1:
            raise ValueError("a stream forward is one connection: its ChaosProxy needs max_legs=1")
        self.leg_addresses: list[Any] = []
        self.events: deque[str] = deque(maxlen=MAX_EVENTS)   # for the CLI to print
        self._reassigned_seen = 0
        self.front = _Port(self, FRONT)
        if isinstance(listen, tuple):
            self.address: Any = driver.add_node(self.front, bind=listen)
        else:
            _, self.address = attach(driver, self.front, listen, listen=True)

    def open_legs(self) -> None:
        """Bind a socket for every leg the proxy handed out that has none yet."""
        proxy = self.proxy
        seen = proxy.reassigned
        while len(self.leg_addresses) < proxy.legs_in_use:
            leg = len(self.leg_addresses)
            if self.forward_link is not None:
                link = open_stream(self.forward_link, self.driver.clock.now())
                self.driver.add_stream(_Port(self, leg), link)
                address = link.local
            else:
                address = self.driver.add_node(_Port(self, leg), bind=(self.leg_host, 0))
            self.leg_addresses.append(address)
            self.events.append(f"GCS {address_label(proxy.gcs_of(leg))} speaks to the vehicle "
                               f"from {address_label(address)}")
        if seen != self._reassigned_seen:
            self._reassigned_seen = seen
            self.events.append(f"leg table full ({proxy.max_legs}): the quietest GCS's leg "
                               f"now carries a new GCS")


class ProxyNode:
    """A `ChaosProxy` as one `DatagramNode` (for `SimNetwork`): datagrams from the vehicle's
    address go down, everything else goes up. One leg: replies go to the last GCS."""

    def __init__(self, proxy: ChaosProxy) -> None:
        if proxy.max_legs != 1:
            raise ValueError("ProxyNode has one address, so its ChaosProxy needs max_legs=1")
        self.proxy = proxy

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        if source == self.proxy.forward:
            self.proxy.from_vehicle(data, 0, source, now)
        else:
            self.proxy.from_gcs(data, source, now)

    def poll(self, now: float) -> None:
        self.proxy.poll(now)

    def next_deadline(self) -> float | None:
        return self.proxy.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.proxy.take_outgoing(FRONT) + self.proxy.take_outgoing(0)


