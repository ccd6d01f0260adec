"""A MAVLink endpoint inside a node: codec, peer table, outbox.

Both reference nodes (vehicle and GCS) own one. It turns datagrams into frames, remembers
which address each (system, component) last spoke from (seed 001, routing: a system learns
the link of a peer from the messages it sees), and turns `Send` actions into datagrams for
the right addresses. Bad bytes are counted and kept for the report, never raised.

`single_peer=True` models a link bound to one peer, as real SITL GCS links are (VARIANTS.md
L1: ArduPilot's `udpclient` socket is connected to one address; L2: PX4 locks a link to its
first sender): the first configured or heard address is the only one read or sent to.
"""

from __future__ import annotations

import time
from collections import deque
from typing import Any, Callable, Iterable

from .mission.actions import Peer, Send
from .net.node import Address
from .wire.codec import FrameDecoder, FrameEncoder
from .wire.frame import DecodeError, Frame, SignatureVerdict
from .wire.signing import SigningKey

MAX_KEPT_ERRORS = 100
MAX_ADDRESSES = 64   # learned peers kept for broadcasts; the oldest learned one goes first


class MavlinkEndpoint:
    def __init__(self, system: int, component: int, *, dialect: Any = None, version: int = 2,
                 signing: SigningKey | None = None, require_signature: bool = False,
                 wall_clock: Callable[[], float] = time.time, single_peer: bool = False) -> None:
        self.encoder = FrameEncoder(system, component, dialect=dialect, version=version,
                                    signing=signing, wall_clock=wall_clock)
        self.decoder = FrameDecoder(dialect=dialect, signing=signing, wall_clock=wall_clock)
        self.require_signature = require_signature
        self.peers: dict[Peer, Address] = {}
        self.addresses: dict[Address, None] = {}   # insertion-ordered set: broadcast targets
        self._configured: set[Address] = set()     # given by add_address: never forgotten
        self.decode_errors: deque[tuple[Address, DecodeError]] = deque(maxlen=MAX_KEPT_ERRORS)
        self.rejected_signatures = 0
        self.single_peer = single_peer
        self.locked_to: Address | None = None      # with single_peer: the one peer address
        self.foreign_datagrams = 0                 # with single_peer: datagrams from elsewhere, unread
        self._outbox: list[tuple[bytes, Address]] = []

    @property
    def system(self) -> int:
        return self.encoder.system

    @property
    def component(self) -> int:
        return self.encoder.component

    def add_address(self, address: Address) -> None:
        """A place to send to before anyone has spoken (the target of `udp:HOST:PORT`)."""
        if self.single_peer:
            if self.locked_to is not None and address != self.locked_to:
                return
            self.locked_to = address
        self._configured.add(address)
        self.addresses.setdefault(address, None)

    def receive(self, data: bytes, source: Address) -> list[Frame]:
        """Frames in a datagram that passed the signature policy; errors are recorded."""
        if self.single_peer and self.locked_to is not None and source != self.locked_to:
            self.foreign_datagrams += 1
            return []
        frames: list[Frame] = []
        peers = self.peers
        for item in self.decoder.feed(data):
            if item.__class__ is DecodeError:
                self.decode_errors.append((source, item))
                continue
            if (item.signature is not SignatureVerdict.UNSIGNED or self.require_signature) \
                    and not self._signature_acceptable(item):
                self.rejected_signatures += 1
                continue
            peers[(item.src_system, item.src_component)] = source
            frames.append(item)
        if frames and source not in self.addresses:
            if self.single_peer:
                self.locked_to = source
            self._learn(source)   # only a source that sent a valid frame is a peer
        return frames

    def _learn(self, source: Address) -> None:
        addresses = self.addresses
        if len(addresses) >= MAX_ADDRESSES:
            oldest = next((a for a in addresses if a not in self._configured), None)
            if oldest is not None:
                del addresses[oldest]
        addresses[source] = None

    def _signature_acceptable(self, frame: Frame) -> bool:
        verdict = frame.signature
        if verdict is SignatureVerdict.INVALID:
            return False
        return not (self.require_signature and verdict is not SignatureVerdict.VALID)

    def send(self, msg: Any, to: Peer | None = None) -> None:
        """Queue `msg` for one peer (by its last address) or, with `to=None`, every address."""
        data = self.encoder.encode(msg)
        if to is not None:
            address = self.peers.get(to)
            if address is None and to[1] == 0:
                address = next((a for p, a in self.peers.items() if p[0] == to[0]), None)
            if address is not None:
                self._outbox.append((data, address))
                return
        for address in self.addresses:
            self._outbox.append((data, address))

    def send_raw(self, data: bytes, to: Peer | None = None) -> None:
        """Queue bytes as they are (a damaged frame, on purpose) for one peer's address, or
        every address if that peer's is not known."""
        address = self.peers.get(to) if to is not None else None
        for where in [address] if address is not None else list(self.addresses):
            self._outbox.append((data, where))

    def send_all(self, actions: Iterable[Any]) -> list[Any]:
        """Send every `Send` in `actions`; return the other actions (e.g. results)."""
        rest = []
        for action in actions:
            if isinstance(action, Send):
                self.send(action.msg, action.to)
            else:
                rest.append(action)
        return rest

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out, self._outbox = self._outbox, []
        return out
