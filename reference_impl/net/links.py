"""Put a node on the link an address names: a UDP socket, a TCP connection, a serial line.

Every command and plugin that takes an address goes through `attach`, so a `tcp:` target
is reached the same way by `run`, `fuzz`, `gcs`, the vectors and the pytest plugins, and
`vehicle`/`proxy --listen` serve on any of them. The UDP driver runs both kinds: sockets
that carry datagrams, and stream links (stream_link.py) whose bytes it cuts into frames.
"""

from __future__ import annotations

from typing import Any

from .node import Address, DatagramNode
from .serial_link import PtyLink, SerialLink
from .stream_link import StreamLink
from .tcp_link import TcpClientLink, TcpServerLink
from .uri import LinkUri, SerialUri, TcpUri, UdpUri, local_bind_for


def open_stream(uri: TcpUri | SerialUri, now: float) -> StreamLink:
    """The stream link `uri` names, connecting (tcp:), listening (tcpin:) or opened
    (serial:, pty). A port in use or a device that cannot be opened: `UsageError`."""
    if isinstance(uri, TcpUri):
        if uri.mode == "tcp":
            return TcpClientLink(uri.host, uri.port, now)
        return TcpServerLink(uri.host, uri.port, now)
    if uri.device == "pty":
        return PtyLink(uri.baud, now)
    return SerialLink(uri.device, uri.baud, now)


def stream_peer(uri: TcpUri | SerialUri) -> str:
    """The address frames from the far end of a tcp: or serial: link carry (its `peer`),
    known before the link is opened (the proxy recognises its vehicle by it)."""
    return str(uri) if isinstance(uri, TcpUri) else f"serial:{uri.device}"


def attach(driver: Any, node: DatagramNode, uri: LinkUri, *, listen: bool = False,
           outgoing: Any = None, incoming: Any = None, framer: Any = None) -> tuple[Address | None, Address]:
    """Put `node` on `uri`'s link; (the peer's address if known now, our own address).

    `listen`: the address is where we listen even if it is udp: (vehicle/proxy --listen).
    For udp: the peer is the address given; for udpin: it is learnt from what arrives
    (None here); a stream link has one peer, known from the start. `framer`: how a stream
    is cut into datagrams (UdpDriver.add_stream; default MAVLink frames)."""
    if isinstance(uri, UdpUri):
        if uri.mode == "udpin" or listen:
            own = driver.add_node(node, bind=uri.address, outgoing=outgoing, incoming=incoming)
            return None, own
        own = driver.add_node(node, bind=(local_bind_for(uri.host), 0), outgoing=outgoing, incoming=incoming)
        return uri.address, own
    link = open_stream(uri, driver.clock.now())
    driver.add_stream(node, link, outgoing=outgoing, incoming=incoming, framer=framer)
    return link.peer, link.local


def stream_of(driver: Any, node: DatagramNode) -> StreamLink | None:
    """The stream link `node` is on, or None (a UDP socket, or virtual time)."""
    find = getattr(driver, "stream_of", None)
    return find(node) if find is not None else None
