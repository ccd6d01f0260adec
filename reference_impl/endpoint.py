"""A MAVLink endpoint inside a node: codec, peer table, outbox.

Both reference nodes (vehicle and GCS) own one. It turns datagrams into frames, remembers
which address each (system, component) last spoke from (seed 001, routing: a system learns
the link of a peer from the messages it sees), and turns `Send` actions into datagrams for
the right addresses. Bad bytes are counted and kept for the report, never raised.

`single_peer=True` models a link bound to one peer, as real SITL GCS links are (VARIANTS.md
L1: ArduPilot's `udpclient` socket is connected to one address; L2: PX4 locks a link to its
first sender): the first configured or heard address is the only one read or sent to.

Signatures. With one `SigningKey` every frame is signed with it and checked against it. With
a `Keyring` (a key per system id: the vehicle's GCS roster) each frame is checked against
the key of the system it claims, and frames to an address are signed with the key of the
known system last verified there (per link, as MAVLink keys are shared by the two ends of a
link), so no GCS holds a key that signs what another GCS receives; an address no known
system has spoken from gets the endpoint's own key, or unsigned frames. Every frame the
signature policy drops is counted by its `Frame.authenticity` label in `rejections` and the
last ones are kept in `rejected`, for logs and reports: a drop is never silent. Decode
errors likewise: the last ones kept in `decode_errors`, every one counted by source address
in `decode_error_counts` (a busy target sends more frames our dialect lacks than any kept
list holds, and each is a frame of its packet sequence that we did not read).
"""

from __future__ import annotations

import time
from collections import Counter, deque
from dataclasses import dataclass
from typing import Any, Callable, Iterable

from .mission.actions import Peer, Send
from .net.node import Address
from .wire.codec import FrameDecoder, FrameEncoder
from .wire.frame import DecodeError, Frame, SignatureVerdict
from .wire.signing import Keyring, SigningKey

MAX_KEPT_ERRORS = 100
MAX_KEPT_REJECTIONS = 100
MAX_ADDRESSES = 64   # learned peers kept for broadcasts; the oldest learned one goes first
# read for every frame received, bound once: on Python 3.11 `SignatureVerdict.UNSIGNED` off
# the class is a slow metaclass hook
_UNSIGNED, _VALID = SignatureVerdict.UNSIGNED, SignatureVerdict.VALID


@dataclass(frozen=True, slots=True)
class Rejection:
    """A decoded frame the signature policy dropped: who it claimed to be, what, and why."""

    source: Address
    system: int
    component: int
    message: str
    reason: str        # Frame.authenticity: "unsigned", "bad signature", "replayed", ...

    def __str__(self) -> str:
        return f"{self.message} claiming {self.system}/{self.component} from {self.source}: {self.reason}"


class MavlinkEndpoint:
    def __init__(self, system: int, component: int, *, dialect: Any = None, version: int = 2,
                 signing: SigningKey | None = None, require_signature: bool = False,
                 wall_clock: Callable[[], float] = time.time, single_peer: bool = False,
                 keyring: Keyring | None = None) -> None:
        """`signing`: our own key (outgoing frames to addresses without a known system; with
        no `keyring`, also the key every frame is checked against). `keyring`: a key per
        system id to check frames by and sign each link with. `require_signature`: drop
        unsigned frames too (frames that fail a check are always dropped)."""
        self._dialect, self._version, self._wall_clock = dialect, version, wall_clock
        self.encoder = FrameEncoder(system, component, dialect=dialect, version=version,
                                    signing=signing, wall_clock=wall_clock)
        self.decoder = FrameDecoder(dialect=dialect, signing=keyring if keyring is not None else signing,
                                    wall_clock=wall_clock)
        self.keyring = keyring
        self.require_signature = require_signature
        self.rejections: Counter[str] = Counter()       # dropped frames by Frame.authenticity
        self.rejected: deque[Rejection] = deque(maxlen=MAX_KEPT_REJECTIONS)
        self._link_keys: dict[Address, SigningKey] = {}         # with a keyring: key per address
        self._link_encoders: dict[SigningKey, FrameEncoder] = {}  # one sequence per link key
        self.peers: dict[Peer, Address] = {}
        self.addresses: dict[Address, None] = {}   # insertion-ordered set: broadcast targets
        self._configured: set[Address] = set()     # given by add_address: never forgotten
        self.decode_errors: deque[tuple[Address, DecodeError]] = deque(maxlen=MAX_KEPT_ERRORS)
        self.decode_error_counts: Counter[Address] = Counter()   # every one, by source
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
                self.decode_error_counts[source] += 1
                continue
            if (item.signature is not _UNSIGNED or self.require_signature) \
                    and not self._signature_acceptable(item):
                self._reject(item, source)
                continue
            peers[(item.src_system, item.src_component)] = source
            if self.keyring is not None and item.signature is _VALID:
                self._link_keys[source] = self.keyring.key_for(item.src_system)
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
                self._link_keys.pop(oldest, None)
        addresses[source] = None

    def _signature_acceptable(self, frame: Frame) -> bool:
        verdict = frame.signature
        if verdict is SignatureVerdict.INVALID:
            return False
        return not (self.require_signature and verdict is not SignatureVerdict.VALID)

    def _reject(self, frame: Frame, source: Address) -> None:
        reason = frame.authenticity
        self.rejected_signatures += 1
        self.rejections[reason] += 1
        self.rejected.append(Rejection(source, frame.src_system, frame.src_component, frame.name, reason))

    def link_key(self, address: Address) -> SigningKey | None:
        """The key frames to `address` are signed with (None: the endpoint's own, if any)."""
        return self._link_keys.get(address)

    def send(self, msg: Any, to: Peer | None = None) -> None:
        """Queue `msg` for one peer (by its last address) or, with `to=None`, every address."""
        if self._link_keys:
            self._send_per_link(msg, to)
            return
        data = self.encoder.encode(msg)
        if to is not None:
            address = self.peers.get(to)   # the usual case, without a call; else by system
            if address is None:
                address = self._address_of(to)
            if address is not None:
                self._outbox.append((data, address))
                return
        for address in self.addresses:
            self._outbox.append((data, address))

    def _send_per_link(self, msg: Any, to: Peer | None) -> None:
        """`send` with a keyring: each address gets the frame signed with its link's key,
        encoded once per key (each link key has its own sequence numbers, as a channel)."""
        address = self._address_of(to) if to is not None else None
        encoded: dict[SigningKey | None, bytes] = {}
        for where in [address] if address is not None else list(self.addresses):
            key = self._link_keys.get(where)
            data = encoded.get(key)
            if data is None:
                data = encoded[key] = self._encoder_for(key).encode(msg)
            self._outbox.append((data, where))

    def _address_of(self, to: Peer) -> Address | None:
        address = self.peers.get(to)
        if address is None and to[1] == 0:
            address = next((a for p, a in self.peers.items() if p[0] == to[0]), None)
        return address

    def _encoder_for(self, key: SigningKey | None) -> FrameEncoder:
        if key is None:
            return self.encoder
        encoder = self._link_encoders.get(key)
        if encoder is None:
            encoder = self._link_encoders[key] = FrameEncoder(
                self.encoder.system, self.encoder.component, dialect=self._dialect, version=self._version,
                signing=key, wall_clock=self._wall_clock)
        return encoder

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
