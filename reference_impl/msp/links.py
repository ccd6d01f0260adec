"""Put an MSP client node on the link to its flight controller, or serve one in-process.

One place for what the MSP clauses' session and the bridge both do: a flight controller of
our own (`builtin:msp`) is served over real TCP loopback (a listener on 127.0.0.1 at a port
the OS picks, our client connected to it, both run by the same UDP driver in one thread);
an external one is reached over the link its URI names. The bytes go to the nodes as they
were read (`PassThrough`): MSP nodes frame the stream themselves.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from ..net.links import attach, stream_of
from ..net.node import Address
from ..net.stream_framer import PassThrough
from ..net.tcp_link import TcpClientLink, TcpServerLink
from ..net.uri import LinkUri, Role, SerialUri, parse_link_uri
from .nodes import MspClientNode, MspServerNode

CONNECT_TIMEOUT = 3.0     # s for a TCP link to come up before the first request
LOOPBACK = "127.0.0.1"
MSP_BAUD = 115200         # INAV's serial ports speak MSP at 115200 by default (MAVLink's: 57600)


def parse_msp_link(text: str, *, role: Role = "target", option: str | None = None) -> LinkUri:
    """An address of an MSP flight controller: the one link parser's, except that a serial
    line given without a baud rate runs at MSP_BAUD."""
    uri = parse_link_uri(text, role=role, option=option)
    given = text.strip().partition(":")[2] != getattr(uri, "device", None)
    if isinstance(uri, SerialUri) and not given:
        uri = replace(uri, baud=MSP_BAUD)
    return uri


def connect(driver: Any, node: MspClientNode, uri: LinkUri | None, *,
            server: MspServerNode | None = None) -> Address | None:
    """`node` on the link to `uri`, or to `server` over TCP loopback; the peer's address. A
    stream link is given CONNECT_TIMEOUT to come up (a request sent while it is down is lost)."""
    now = driver.clock.now()
    if server is not None:
        listener = TcpServerLink(LOOPBACK, 0, now)
        driver.add_stream(server, listener, framer=PassThrough())
        client = TcpClientLink(LOOPBACK, listener.address[1], now)
        driver.add_stream(node, client, framer=PassThrough())
        node.peer = client.peer
    else:
        assert uri is not None
        node.peer, _ = attach(driver, node, uri, framer=PassThrough())
    link = stream_of(driver, node)
    if link is not None:
        driver.run_until(lambda: link.up, timeout=CONNECT_TIMEOUT)
        node.peer = link.peer
    return node.peer
