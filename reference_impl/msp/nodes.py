"""MSP on a link: the flight controller's side and the client's, as datagram nodes.

The drivers move datagrams (reference_impl/net): SimNetwork in virtual time, the UDP driver
over UDP, TCP, serial lines and pseudo-terminals. MSP has no datagrams, only a byte stream,
so each node frames what it is given itself with `MspParser` (one per peer: a stream read
may hold half a frame, or garbage), and a stream link hands it the bytes as they came
(`stream_framer.PassThrough`). The same nodes then serve `builtin:msp` in virtual time, over
real TCP loopback, and on a pseudo-terminal.
"""

from __future__ import annotations

from typing import Callable

from ..net.node import Address
from .flight_controller import MspFlightController
from .frame import ERROR, FROM_FC, TO_FC, MspFrame, encode
from .parser import MspParser

MAX_PEERS = 64   # parsers kept for distinct UDP sources; a stream link has one peer


class _MspNode:
    """What both ends share: no timers, and an outbox the driver empties."""

    _out: list[tuple[bytes, Address]]

    def poll(self, now: float) -> None:
        pass

    def next_deadline(self) -> float | None:
        return None

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out, self._out = self._out, []
        return out


class MspServerNode(_MspNode):
    """An MSP flight controller on a link: requests in, its replies out to the sender."""

    def __init__(self, controller: MspFlightController | None = None, *,
                 parser: Callable[[], MspParser] = lambda: MspParser(accept=TO_FC)) -> None:
        self.controller = controller if controller is not None else MspFlightController()
        self._new_parser = parser
        self._parsers: dict[Address, MspParser] = {}
        self._out: list[tuple[bytes, Address]] = []

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        parser = self._parsers.get(source)
        if parser is None:
            if len(self._parsers) >= MAX_PEERS:
                self._parsers.pop(next(iter(self._parsers)))
            parser = self._parsers[source] = self._new_parser()
        for frame in parser.feed(data):
            for reply in self.controller.handle(frame):
                self._out.append((encode(reply), source))


class MspClientNode(_MspNode):
    """Our end of an MSP link: frames out to one peer, replies (`>` and `!`) in, timed."""

    def __init__(self, peer: Address | None = None) -> None:
        self.peer = peer                  # a udpin: target's address is learnt from what it sends
        self.parser = MspParser(accept=FROM_FC + ERROR)
        self.inbox: list[tuple[float, MspFrame]] = []
        self.sent_bytes = 0
        self.last_heard: float | None = None
        self._out: list[tuple[bytes, Address]] = []

    def send(self, frame: MspFrame) -> bytes:
        return self.send_raw(encode(frame))

    def send_raw(self, data: bytes) -> bytes:
        """Queue bytes as they are (a malformed frame, garbage); dropped if no peer is known."""
        if self.peer is not None:
            self._out.append((data, self.peer))
            self.sent_bytes += len(data)
        return data

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        if self.peer is None:
            self.peer = source
        self.last_heard = now
        for frame in self.parser.feed(data):
            self.took(frame, now)

    def took(self, frame: MspFrame, now: float) -> None:
        """A whole frame from the peer: kept in `inbox` (a subclass may act on it instead)."""
        self.inbox.append((now, frame))
