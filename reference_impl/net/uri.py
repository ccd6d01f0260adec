"""Endpoint URIs for the CLI: `udp:HOST:PORT` and `udpin:HOST:PORT`.

- `udp:HOST:PORT`   the peer listens at HOST:PORT and we send to it first;
- `udpin:HOST:PORT` we listen at HOST:PORT and the peer sends to us (as SITL does).
A bad URI is the user's mistake, so it raises `UsageError` with one line that quotes the
text and says what is wrong; nothing here touches the network.
"""

from __future__ import annotations

import ipaddress
import re
import socket
from dataclasses import dataclass

from ..errors import UsageError

SCHEMES = ("udp", "udpin")
_HOSTNAME = re.compile(r"(?=.{1,253}\Z)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
                       r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?")
_FORMS = "expected udp:HOST:PORT or udpin:HOST:PORT"


@dataclass(frozen=True)
class UdpUri:
    mode: str   # "udp" (we send to a listening peer) or "udpin" (we listen)
    host: str
    port: int

    @property
    def address(self) -> tuple[str, int]:
        return (self.host, self.port)

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.mode}:{host}:{self.port}"


def parse_udp_uri(text: str, *, listen: bool = False) -> UdpUri:
    """Parse an endpoint. With `listen=True` the URI names where *we* bind (either scheme),
    so port 0 (any free port) is allowed."""
    def bad(what: str) -> UsageError:
        return UsageError(f"bad endpoint {text!r}: {what} ({_FORMS})")

    scheme, sep, rest = text.strip().partition(":")
    if not sep:
        raise bad("missing scheme")
    if scheme.lower() not in SCHEMES:
        raise bad(f"unknown scheme {scheme!r}")
    mode = scheme.lower()
    host, sep, port_text = rest.rpartition(":")
    if not sep:
        raise bad("missing port")
    if not port_text:
        raise bad("missing port")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
        if not _is_ip(host, version=6):
            raise bad(f"bad host {host!r}: not an IPv6 address")
    elif not host:
        raise bad("missing host")
    elif ":" in host:
        raise bad(f"bad host {host!r}: write an IPv6 address in brackets, e.g. [::1]")
    elif re.fullmatch(r"[0-9.]+", host):
        if not _is_ip(host, version=4):
            raise bad(f"bad host {host!r}: not an IPv4 address")
    elif not _HOSTNAME.fullmatch(host):
        raise bad(f"bad host {host!r}")
    elif not _resolves(host):   # said now, not later as "no HEARTBEAT from the target"
        raise UsageError(f"bad endpoint {text!r}: cannot resolve host {host!r}")
    if not port_text.isdigit() or not port_text.isascii():
        raise bad(f"bad port {port_text!r}: not a number")
    port = int(port_text)
    if port > 65535:
        raise bad(f"bad port {port}: must be 0..65535")
    if port == 0 and mode == "udp" and not listen:
        raise bad("port 0 is only allowed for udpin (we cannot send to port 0)")
    return UdpUri(mode, host, port)


def _resolves(host: str) -> bool:
    try:
        socket.getaddrinfo(host, None, type=socket.SOCK_DGRAM)
    except (socket.gaierror, UnicodeError):
        return False
    return True


def _is_ip(text: str, *, version: int) -> bool:
    try:
        return ipaddress.ip_address(text).version == version
    except ValueError:
        return False


def local_bind_for(host: str) -> str:
    """Where to bind to reach `host`: loopback for a loopback target, any interface otherwise."""
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return "127.0.0.1" if host == "localhost" else "0.0.0.0"
    if ip.is_loopback:
        return str(ip)
    return "::" if ip.version == 6 else "0.0.0.0"
