"""UdpDriver: the same `DatagramNode`s over real UDP sockets (and byte-stream links: TCP,
serial), one thread, `selectors`.

The only real wait in the project lives here: `selector.select(timeout)`, always bounded by
the run's end and the earliest node deadline or fault timer, so a silent peer costs exactly
the timeout and never a hang. Fault models apply per node: `outgoing` to what the node
sends, `incoming` to what it receives; delays go on the driver's own timer heap (no sleep).
Socket errors (ICMP port unreachable surfacing as ConnectionRefusedError, a full buffer)
are what a bad peer or link does, so they are counted, never raised. A bind failure is the
user's mistake (bad address, port in use): a one-line `UsageError`.

What the kernel drops before we read it is ours, not the peer's: each socket gets a large
receive buffer and, where the platform can count them, its drops (receive_queue.py);
`receive_queue(node)` says both. Every wake-up reads what is waiting on each ready socket
(bounded), so a busy peer is read as it sends.

A stream link (`add_stream`: stream_link.py, tcp_link.py, serial_link.py) carries the same
nodes: its bytes are cut into frames (stream_framer.py) and each frame goes to the node as
a datagram from the link's one peer; what the node sends goes down the stream, through the
same fault models, frame by frame. Nothing is lost on a TCP link, so its receive queue's
drop count is a known 0; a serial line's is unknown.

Fault RNGs are seeded from (seed, node index, direction), not the OS-chosen port, so the
fault *decisions* repeat for a given seed even though real timing does not.
"""

from __future__ import annotations

import ipaddress
import random
import selectors
import socket
from heapq import heappop, heappush
from itertools import count
from typing import Any, Callable

from ..errors import UsageError
from .clock import Clock, MonotonicClock
from .faults import FaultModel, LinkStats
from .node import Address, DatagramNode
from .receive_queue import ANCILLARY_SPACE, ReceiveQueue, open_queue, resize
from .sim import CaptureHook, CaptureRecord, stable_seed
from .stream_framer import StreamFramer
from .stream_link import StreamLink

MAX_DATAGRAM = 65535
MAX_DRAIN = 256  # datagrams read from one socket per wake-up, so one flood can't starve the rest
_SEND, _RECV = 0, 1


class _Endpoint:
    __slots__ = ("node", "sock", "address", "outgoing", "incoming", "rng_out", "rng_in", "queue")

    def __init__(self, node: DatagramNode, sock: socket.socket, address: tuple[str, int],
                 outgoing: FaultModel | None, incoming: FaultModel | None,
                 rng_out: random.Random, rng_in: random.Random, queue: ReceiveQueue) -> None:
        self.node, self.sock, self.address = node, sock, address
        self.outgoing, self.incoming = outgoing, incoming
        self.rng_out, self.rng_in = rng_out, rng_in
        self.queue = queue


class _StreamEndpoint:
    """A node on a stream link: the link, its framer, and the same fault plumbing."""

    __slots__ = ("node", "link", "address", "outgoing", "incoming", "rng_out", "rng_in", "queue",
                 "framer", "generation")

    def __init__(self, node: DatagramNode, link: StreamLink, outgoing: FaultModel | None,
                 incoming: FaultModel | None, rng_out: random.Random, rng_in: random.Random,
                 framer: Any) -> None:
        self.node, self.link, self.address = node, link, link.local
        self.outgoing, self.incoming = outgoing, incoming
        self.rng_out, self.rng_in = rng_out, rng_in
        self.queue = ReceiveQueue(None, counted=link.kind in ("tcp", "tcpin"))
        self.framer = framer
        self.generation = link.generation


class UdpDriver:
    """Runs nodes on UDP sockets in real time. Use as a context manager, or call close()."""

    def __init__(self, clock: Clock | None = None, seed: int = 0) -> None:
        self.clock: Clock = clock if clock is not None else MonotonicClock()
        self.seed = seed
        self.stats: dict[tuple[Address, Address], LinkStats] = {}
        self.recv_errors = 0
        self._selector = selectors.DefaultSelector()
        self._endpoints: list[_Endpoint] = []
        self._streams: list[_StreamEndpoint] = []
        self._nodes: list[_Endpoint | _StreamEndpoint] = []   # both kinds, in the order added
        self._registered: dict[int, tuple[_StreamEndpoint, object, int, int]] = {}
        self._timers: list[tuple[float, int, int, _Endpoint, bytes, Address]] = []
        self._tiebreak = count()
        self._hooks: list[CaptureHook] = []
        self._closed = False
        # the most this driver has run behind its own schedule since `take_lag()`, in clock
        # seconds: how late it served a node deadline or a fault timer that was still ahead
        # when it last looked, and how far it overslept the time it meant to wake. A host too
        # busy to keep the clock (a 4x one asks four times the punctuality) shows here, and a
        # timing verdict judged meanwhile is the host's.
        self.lag = 0.0
        self._looked = self.clock.now()   # when the driver last read what was due

    def take_lag(self) -> float:
        """`lag` since the last call, and start counting afresh."""
        lag, self.lag = self.lag, 0.0
        return lag

    # -- wiring -------------------------------------------------------------------------

    def add_node(self, node: DatagramNode, *, bind: tuple[str, int] = ("127.0.0.1", 0),
                 outgoing: FaultModel | None = None,
                 incoming: FaultModel | None = None) -> tuple[str, int]:
        """Bind a socket for `node` and return the bound (host, port)."""
        self._check_open()
        host, port = bind
        sock = socket.socket(_family(host), socket.SOCK_DGRAM)
        queue = open_queue(sock)
        try:
            sock.bind((host, port))
        except (OSError, OverflowError) as exc:
            sock.close()
            reason = getattr(exc, "strerror", None) or str(exc)
            raise UsageError(f"cannot bind UDP {host}:{port}: {reason}") from None
        sock.setblocking(False)
        address = tuple(sock.getsockname()[:2])
        if incoming is not None and incoming is outgoing:
            incoming = outgoing.copy()  # rule counters belong to one direction
        index = len(self._endpoints)
        ep = _Endpoint(node, sock, address, outgoing, incoming,
                       random.Random(stable_seed(self.seed, index, "out")),
                       random.Random(stable_seed(self.seed, index, "in")), queue)
        self._endpoints.append(ep)
        self._nodes.append(ep)
        self._selector.register(sock, selectors.EVENT_READ, ep)
        return address  # type: ignore[return-value]

    def add_stream(self, node: DatagramNode, link: StreamLink, *, outgoing: FaultModel | None = None,
                   incoming: FaultModel | None = None, framer: Any = None) -> None:
        """Run `node` on a stream link (which the driver then owns and closes). `framer` cuts
        what arrives into datagrams (default: MAVLink frames, stream_framer.py; an MSP node
        takes the bytes as they come, `PassThrough`, and frames them itself)."""
        self._check_open()
        if incoming is not None and incoming is outgoing:
            incoming = outgoing.copy()
        index = len(self._nodes)
        ep = _StreamEndpoint(node, link, outgoing, incoming,
                             random.Random(stable_seed(self.seed, index, "out")),
                             random.Random(stable_seed(self.seed, index, "in")),
                             framer if framer is not None else StreamFramer())
        self._streams.append(ep)
        self._nodes.append(ep)

    def stream_of(self, node: DatagramNode) -> StreamLink | None:
        """The stream link `node` runs on, or None if it is on a UDP socket."""
        ep = self._endpoint(node)
        return ep.link if isinstance(ep, _StreamEndpoint) else None

    def add_capture(self, hook: CaptureHook) -> None:
        self._hooks.append(hook)

    def receive_queue(self, node: DatagramNode) -> ReceiveQueue:
        """The receive queue of `node`'s socket: the buffer granted, the datagrams dropped."""
        return self._endpoint(node).queue

    def resize_receive_buffer(self, node: DatagramNode, wanted: int) -> int | None:
        """Ask for a `wanted`-byte receive buffer on `node`'s socket; the size granted
        (None on a stream link: there is no datagram queue to size)."""
        ep = self._endpoint(node)
        if isinstance(ep, _StreamEndpoint):
            return None
        return resize(ep.sock, ep.queue, wanted)

    # -- running ------------------------------------------------------------------------

    def run_for(self, seconds: float) -> None:
        self.run_until(lambda: False, timeout=seconds)

    def run_until(self, condition: Callable[[], bool], *, timeout: float,
                  max_steps: int = 10_000_000) -> bool:
        """Serve sockets and timers until `condition()` holds or `timeout` seconds of the
        driver's clock pass. Never blocks past the end or the earliest node deadline / fault timer."""
        self._check_open()
        if not timeout >= 0.0:
            raise ValueError(f"run_until timeout must be >= 0 seconds, got {timeout!r}")
        clock = self.clock
        speed = getattr(clock, "speed", 1.0)   # a ScaledClock's seconds pass faster than real ones
        now = clock.now()
        end = now + timeout
        self._flush(now)
        if condition():
            return True
        timers = self._timers
        nodes = self._nodes
        streams = self._streams
        for _ in range(max_steps):
            now = clock.now()
            busy = False
            looked, self._looked = self._looked, now
            while timers and timers[0][0] <= now:
                due, _, kind, ep, data, peer = heappop(timers)
                if due > looked and now - due > self.lag:
                    self.lag = now - due
                if kind == _SEND:
                    self._sendto(ep, data, peer)
                else:
                    self._deliver(ep, data, peer, now)
                busy = True
            for ep in nodes:
                d = ep.node.next_deadline()
                if d is not None and d <= now:
                    if d > looked and now - d > self.lag:
                        self.lag = now - d
                    ep.node.poll(now)
                    busy = True
            for sp in streams:
                d = sp.link.next_deadline()
                if d is not None and d <= now:
                    sp.link.poll(now)
            if busy:
                self._flush(now)
                if condition():
                    return True
            now = clock.now()
            wake = end
            if timers and timers[0][0] < wake:
                wake = timers[0][0]
            for ep in nodes:
                d = ep.node.next_deadline()
                if d is not None and d < wake:
                    wake = d
            for sp in streams:
                d = sp.link.next_deadline()
                if d is not None and d < wake:
                    wake = d
            if streams:
                self._sync_streams(now)
            events = self._selector.select(max(0.0, wake - now) / speed)
            overslept = clock.now() - wake
            if overslept > self.lag and wake > now:
                self.lag = overslept
            if events:
                now = clock.now()
                for key, mask in events:
                    if key.data.__class__ is _Endpoint:
                        self._drain(key.data, now)
                    else:
                        self._stream_ready(key.fd, mask, now)
                self._flush(now)
                if condition():
                    return True
            if clock.now() >= end:  # after one select, so timeout=0 still drains the sockets
                break
        return condition()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        for ep in self._endpoints:
            self._selector.unregister(ep.sock)
            ep.sock.close()
        for fd in list(self._registered):
            self._unregister(fd)
        for sp in self._streams:
            sp.link.close()
        self._selector.close()

    def __enter__(self) -> "UdpDriver":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- internals ----------------------------------------------------------------------

    def _check_open(self) -> None:
        if self._closed:
            raise ValueError("UdpDriver is closed")

    def _endpoint(self, node: DatagramNode) -> _Endpoint | _StreamEndpoint:
        for ep in self._nodes:
            if ep.node is node:
                return ep
        raise ValueError(f"UdpDriver has no socket for {node!r}")

    def _link(self, src: Address, dst: Address) -> LinkStats:
        stats = self.stats.get((src, dst))
        if stats is None:
            stats = self.stats[(src, dst)] = LinkStats()
        return stats

    def _emit(self, now: float, src: Address, dst: Address, data: bytes, kind: str) -> None:
        rec = CaptureRecord(now, src, dst, data, kind, self.clock.wall())
        for hook in self._hooks:
            hook(rec)

    def _flush(self, now: float) -> None:
        """Send what every node has queued, through its outgoing faults."""
        for ep in self._nodes:
            for data, dst in ep.node.take_outgoing():
                stats = self._link(ep.address, dst)
                stats.sent += 1
                if self._hooks:
                    self._emit(now, ep.address, dst, data, "tx")
                fault = ep.outgoing
                if fault is None or fault.is_clean:
                    self._sendto(ep, data, dst)
                    continue
                copies = fault.schedule(data, now, ep.rng_out, stats)
                if not copies and self._hooks:
                    self._emit(now, ep.address, dst, data, "drop")
                for delay, payload in copies:
                    if delay <= 0.0:
                        self._sendto(ep, payload, dst)
                    else:
                        heappush(self._timers,
                                 (now + delay, next(self._tiebreak), _SEND, ep, payload, dst))
        for sp in self._streams:
            sp.link.flush(now)

    def _sendto(self, ep: _Endpoint | _StreamEndpoint, data: bytes, dst: Address) -> None:
        if ep.__class__ is _StreamEndpoint:
            if not ep.link.send(data, self.clock.now()):
                self._link(ep.address, dst).errors += 1
            return
        try:
            ep.sock.sendto(data, dst)  # type: ignore[arg-type]
        except OSError:
            self._link(ep.address, dst).errors += 1

    def _drain(self, ep: _Endpoint, now: float) -> None:
        """Read what is waiting on one socket (bounded) and pass it through incoming faults.
        Where the kernel counts the socket's drops, each read takes its count along."""
        sock, queue = ep.sock, ep.queue
        counted = queue.drops is not None
        for _ in range(MAX_DRAIN):
            try:
                if counted:
                    data, ancillary, _, addr = sock.recvmsg(MAX_DATAGRAM, ANCILLARY_SPACE)
                    if ancillary:
                        queue.note(ancillary)
                else:
                    data, addr = sock.recvfrom(MAX_DATAGRAM)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:  # e.g. a queued ICMP error from an earlier send
                self.recv_errors += 1
                continue
            src = (addr[0], addr[1])
            fault = ep.incoming
            if fault is None or fault.is_clean:
                self._deliver(ep, data, src, now)
                continue
            copies = fault.schedule(data, now, ep.rng_in, self._link(src, ep.address))
            if not copies and self._hooks:
                self._emit(now, src, ep.address, data, "drop")
            for delay, payload in copies:
                if delay <= 0.0:
                    self._deliver(ep, payload, src, now)
                else:
                    heappush(self._timers,
                             (now + delay, next(self._tiebreak), _RECV, ep, payload, src))

    # -- stream links -------------------------------------------------------------------

    def _sync_streams(self, now: float) -> None:
        """Wait on what each stream link wants now (it changes as links connect and drop)."""
        wanted: dict[int, tuple[_StreamEndpoint, object, int, int]] = {}
        for sp in self._streams:
            for fileobj, read, write in sp.link.wanted(now):
                fd = fileobj if isinstance(fileobj, int) else fileobj.fileno()
                mask = (selectors.EVENT_READ if read else 0) | (selectors.EVENT_WRITE if write else 0)
                if mask:
                    wanted[fd] = (sp, fileobj, mask, sp.link.generation)
        registered = self._registered
        for fd, entry in list(registered.items()):
            if wanted.get(fd) != entry:
                self._unregister(fd)
        for fd, entry in wanted.items():
            if fd not in registered:
                self._selector.register(fd, entry[2], entry)
                registered[fd] = entry

    def _unregister(self, fd: int) -> None:
        self._registered.pop(fd, None)
        try:
            self._selector.unregister(fd)
        except (KeyError, ValueError, OSError):
            pass

    def _stream_ready(self, fd: int, mask: int, now: float) -> None:
        entry = self._registered.get(fd)
        if entry is None:
            return
        sp, fileobj = entry[0], entry[1]
        data = sp.link.ready(fileobj, bool(mask & selectors.EVENT_READ), bool(mask & selectors.EVENT_WRITE), now)
        if sp.link.generation != sp.generation:   # a new connection: nothing carries over
            sp.generation = sp.link.generation
            sp.framer.reset()
        if not data:
            return
        peer = sp.link.peer
        fault = sp.incoming
        for frame in sp.framer.feed(data):
            if fault is None or fault.is_clean:
                self._deliver(sp, frame, peer, now)
                continue
            copies = fault.schedule(frame, now, sp.rng_in, self._link(peer, sp.address))
            if not copies and self._hooks:
                self._emit(now, peer, sp.address, frame, "drop")
            for delay, payload in copies:
                if delay <= 0.0:
                    self._deliver(sp, payload, peer, now)
                else:
                    heappush(self._timers, (now + delay, next(self._tiebreak), _RECV, sp, payload, peer))

    def _deliver(self, ep: _Endpoint | _StreamEndpoint, data: bytes, src: Address, now: float) -> None:
        self._link(src, ep.address).delivered += 1
        if self._hooks:
            self._emit(now, src, ep.address, data, "rx")
        ep.node.datagram_received(data, src, now)


def _family(host: str) -> socket.AddressFamily:
    try:
        return socket.AF_INET6 if ipaddress.ip_address(host).version == 6 else socket.AF_INET
    except ValueError:
        return socket.AF_INET  # a host name: resolved by bind, IPv4
