"""SimNetwork: datagram nodes on an in-memory network, in virtual time.

Theory of operation: one heap of pending deliveries `(time, tiebreak, link, bytes)`. Each
step moves the `SimClock` to the earlier of the next delivery and the earliest node
deadline, then either delivers that one datagram or polls the due nodes, then collects
every node's `take_outgoing()` and passes each datagram through its link's `FaultModel`.
Nothing here reads the real clock or a global RNG: each link direction has its own
`random.Random` seeded from (seed, src, dst) by a stable hash, so the same seed and the
same nodes give the same run, byte for byte and tick for tick.

This loop is a hot path (fuzz campaigns run thousands of lossy transfers through it), so
it works on local variables, skips the fault model on clean links and builds capture
records only when someone listens.
"""

from __future__ import annotations

import hashlib
import math
import random
from dataclasses import dataclass
from heapq import heappop, heappush
from itertools import count
from typing import Callable

from .clock import SimClock
from .faults import FaultModel, LinkStats
from .node import Address, DatagramNode
from .receive_queue import ReceiveQueue

_INF = math.inf


@dataclass(frozen=True, slots=True)
class CaptureRecord:
    """One datagram event on a link. kind: 'tx' (a node sent it), 'rx' (delivered to the
    destination), 'drop' (the fault model dropped it, or there was no route). `wall`: the
    driver clock's `wall()` then (Unix seconds; under SimClock a fixed epoch plus virtual
    time, so it repeats), for captures' timestamps; None from a producer without one."""

    time: float
    src: Address
    dst: Address
    data: bytes
    kind: str
    wall: float | None = None


CaptureHook = Callable[[CaptureRecord], None]


def stable_seed(*parts: object) -> int:
    """A 64-bit seed from reprs; unlike hash(), the same in every process."""
    digest = hashlib.blake2b(repr(parts).encode(), digest_size=8).digest()
    return int.from_bytes(digest, "big")


class _Link:
    """One direction of a connection: faults, its RNG, counters, and where it delivers."""

    __slots__ = ("src", "dst", "node", "fault", "rng", "stats")

    def __init__(self, src: Address, dst: Address, node: DatagramNode,
                 fault: FaultModel | None, rng: random.Random, stats: LinkStats) -> None:
        self.src, self.dst, self.node = src, dst, node
        self.fault, self.rng, self.stats = fault, rng, stats


class SimNetwork:
    """An in-memory network of `DatagramNode`s in virtual time, deterministic from `seed`."""

    def __init__(self, seed: int = 0, clock: SimClock | None = None) -> None:
        self.seed = seed
        self.clock = clock if clock is not None else SimClock()
        self.stats: dict[tuple[Address, Address], LinkStats] = {}
        self.steps = 0  # total steps taken, across runs
        self._nodes: dict[Address, DatagramNode] = {}
        self._node_list: list[tuple[Address, DatagramNode]] = []
        self._links: dict[tuple[Address, Address], _Link] = {}
        self._heap: list[tuple[float, int, _Link, bytes]] = []
        self._tiebreak = count()
        self._hooks: list[CaptureHook] = []

    # -- wiring -------------------------------------------------------------------------

    def add_node(self, address: Address, node: DatagramNode) -> None:
        if address in self._nodes:
            raise ValueError(f"SimNetwork already has a node at {address!r}")
        self._nodes[address] = node
        self._node_list.append((address, node))

    def connect(self, a: Address, b: Address, *, a_to_b: FaultModel | None = None,
                b_to_a: FaultModel | None = None) -> None:
        """Link a and b both ways; None means a clean direction. Connecting again replaces
        the fault models (counters in `stats` carry on)."""
        for addr in (a, b):
            if addr not in self._nodes:
                raise ValueError(f"SimNetwork.connect: no node at {addr!r}")
        if a == b:
            raise ValueError(f"SimNetwork.connect: cannot link {a!r} to itself")
        if b_to_a is not None and b_to_a is a_to_b:
            b_to_a = a_to_b.copy()  # rule counters belong to one direction
        for src, dst, fault in ((a, b, a_to_b), (b, a, b_to_a)):
            stats = self.stats.setdefault((src, dst), LinkStats())
            rng = random.Random(stable_seed(self.seed, src, dst))
            self._links[(src, dst)] = _Link(src, dst, self._nodes[dst], fault, rng, stats)

    def add_capture(self, hook: CaptureHook) -> None:
        """Call `hook(CaptureRecord)` for every tx, rx and drop from now on."""
        self._hooks.append(hook)

    def receive_queue(self, node: DatagramNode) -> ReceiveQueue:
        """As `UdpDriver.receive_queue`. A datagram is handed to its node when it is due, so
        none waits in a queue and none is dropped there (a fault model's drops are the link's)."""
        return ReceiveQueue(None, counted=True)

    # -- running ------------------------------------------------------------------------

    lag = 0.0   # as UdpDriver.lag: virtual time never falls behind its own schedule

    def take_lag(self) -> float:
        return 0.0

    def in_flight(self) -> int:
        """Datagrams scheduled for delivery and not yet delivered."""
        return len(self._heap)

    def run_for(self, seconds: float) -> None:
        self.run_until(_never, timeout=seconds)

    def run_until_quiet(self, *, timeout: float) -> bool:
        """Run until no datagram is in flight; False if that did not happen in time."""
        heap = self._heap
        return self.run_until(lambda: not heap, timeout=timeout)

    def run_until(self, condition: Callable[[], bool], *, timeout: float,
                  max_steps: int = 10_000_000) -> bool:
        """Step until `condition()` holds (checked before the first step and after every
        step), `timeout` virtual seconds pass (the clock then stands at the end), or
        `max_steps` steps are taken (the clock stays where it got to). Returns condition."""
        if not timeout >= 0.0:
            raise ValueError(f"run_until timeout must be >= 0 seconds, got {timeout!r}")
        clock = self.clock
        now = clock.now()
        end = now + timeout
        self._collect(now)
        if condition():
            return True
        heap = self._heap
        nodes = self._node_list
        hooks = self._hooks
        collect_from = self._collect_from
        # A node's deadline changes only when it is stepped (given a datagram or polled), or
        # from outside this loop (an operation started between calls): so it is read once
        # here and re-read only for the node that was stepped.
        deadlines = [node.next_deadline() for _, node in nodes]
        index = {id(node): i for i, (_, node) in enumerate(nodes)}
        # nodes that share state (a bridge's two sides, msp/bridge.py: `coupled`): stepping one
        # may give the other something to send or a new deadline
        partners = [[index[id(p)] for p in getattr(node, "coupled", ()) if id(p) in index] for _, node in nodes]
        steps = 0
        while steps < max_steps:
            t_dead = _INF
            for d in deadlines:
                if d is not None and d < t_dead:
                    t_dead = d
            t_deliv = heap[0][0] if heap else _INF
            t = t_deliv if t_deliv <= t_dead else t_dead
            if t > end:
                break
            if t > now:
                clock.advance_to(t)
                now = t
            steps += 1
            if t_deliv <= t_dead:
                _, _, link, data = heappop(heap)
                link.stats.delivered += 1
                if hooks:
                    rec = CaptureRecord(now, link.src, link.dst, data, "rx", clock.wall())
                    for hook in hooks:
                        hook(rec)
                node = link.node
                node.datagram_received(data, link.src, now)
                i = index[id(node)]
                deadlines[i] = node.next_deadline()
                collect_from(i, now)
                for j in partners[i]:
                    deadlines[j] = nodes[j][1].next_deadline()
                    collect_from(j, now)
            else:
                for i, d in enumerate(deadlines):
                    if d is not None and d <= now:
                        node = nodes[i][1]
                        node.poll(now)
                        deadlines[i] = node.next_deadline()
                        collect_from(i, now)
                        for j in partners[i]:
                            deadlines[j] = nodes[j][1].next_deadline()
                            collect_from(j, now)
            if condition():
                self.steps += steps
                return True
        else:
            self.steps += steps
            return condition()
        self.steps += steps
        if end > now:
            clock.advance_to(end)
        return condition()

    def _collect(self, now: float) -> None:
        """Take every node's queued datagrams and schedule them through their links."""
        for i in range(len(self._node_list)):
            self._collect_from(i, now)

    def _collect_from(self, i: int, now: float) -> None:
        """Schedule node i's queued datagrams through their links."""
        src, node = self._node_list[i]
        out = node.take_outgoing()
        if not out:
            return
        links = self._links
        heap = self._heap
        tiebreak = self._tiebreak
        hooks = self._hooks
        for data, dst in out:
            link = links.get((src, dst))
            if hooks:
                self._emit(now, src, dst, data, "tx")
            if link is None:
                stats = self.stats.setdefault((src, dst), LinkStats())
                stats.sent += 1
                stats.dropped += 1
                if hooks:
                    self._emit(now, src, dst, data, "drop")
                continue
            link.stats.sent += 1
            fault = link.fault
            if fault is None or fault.is_clean:
                heappush(heap, (now, next(tiebreak), link, data))
                continue
            copies = fault.schedule(data, now, link.rng, link.stats)
            if not copies:
                if hooks:
                    self._emit(now, src, dst, data, "drop")
                continue
            for delay, payload in copies:
                heappush(heap, (now + delay, next(tiebreak), link, payload))

    def _emit(self, now: float, src: Address, dst: Address, data: bytes, kind: str) -> None:
        rec = CaptureRecord(now, src, dst, data, kind, self.clock.wall())
        for hook in self._hooks:
            hook(rec)


def _never() -> bool:
    return False
