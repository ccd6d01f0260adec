"""UDP addresses: the one grammar, and its one parser, for every command and plugin option.

    udp:HOST:PORT      a peer listens at HOST:PORT; we send to it first
    udpin:HOST:PORT    we listen at HOST:PORT; the peer sends to us first (as SITL does)
    udpin:PORT         the same on 127.0.0.1
HOST is an IPv4 address, a host name, or an IPv6 address in brackets ([::1]). What an
option does with the address (its `role`) decides which of these make sense for it, so
`--forward udpin:...` is refused by saying what --forward needs, not as a syntax error.
A bad address is the user's mistake: `UsageError`, one line quoting the text and saying
what is wrong, including a host name that does not resolve (now, not later as "no
HEARTBEAT from the target"). Resolving a name is the only network access here.
"""

from __future__ import annotations

import ipaddress
import re
import socket
from dataclasses import dataclass
from typing import Callable, Literal

from ..errors import UsageError

SCHEMES = ("udp", "udpin")
FORMS = "udp:HOST:PORT or udpin:[HOST:]PORT"
LISTEN_HOST = "127.0.0.1"   # udpin:PORT: loopback, so nothing is exposed unless a host is named
_HOSTNAME = re.compile(r"(?=.{1,253}\Z)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
                       r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?")

# What an option does with an address:
#   target  the scheme says who listens: udp: the peer, udpin: we (run, fuzz, gcs --target);
#   listen  we listen there whatever the scheme; port 0 is any free port (vehicle/proxy --listen);
#   peer    a peer listens there and we send first, so udp: only (vehicle --connect, proxy --forward).
Role = Literal["target", "listen", "peer"]


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


def parse_udp_uri(text: str, *, role: Role = "target", option: str | None = None) -> UdpUri:
    """Parse a UDP address for an option of the given `role`; `option` (e.g. "--listen")
    starts the error message, so the user learns which of several addresses is wrong."""
    where = f"{option}: " if option else ""

    def bad(what: str, hint: str = f" (expected {FORMS})") -> UsageError:
        return UsageError(f"{where}bad endpoint {text!r}: {what}{hint}")

    scheme, sep, rest = text.strip().partition(":")
    if not sep:
        raise bad("missing scheme")
    if scheme.lower() not in SCHEMES:
        raise bad(f"unknown scheme {scheme!r}")
    mode = scheme.lower()
    host, port_text = _split(rest, mode, bad)
    _check_host(host, bad)
    if not port_text.isdigit() or not port_text.isascii():
        raise bad(f"bad port {port_text!r}: not a number")
    port = int(port_text)
    if port > 65535:
        raise bad(f"bad port {port}: must be 0..65535")
    if role == "peer" and mode == "udpin":
        raise bad("here a peer listens and we send first: give udp:HOST:PORT "
                  "(udpin: is for an address we listen at)", "")
    if port == 0 and mode == "udp" and role != "listen":
        raise bad("port 0 is only allowed where we listen (we cannot send to port 0)")
    return UdpUri(mode, host, port)


def _split(rest: str, mode: str, bad: Callable[..., UsageError]) -> tuple[str, str]:
    """HOST:PORT (or, for udpin, PORT alone) -> (host, port text); brackets removed."""
    if rest.startswith("["):
        host, close, after = rest[1:].partition("]")
        if not close:
            raise bad("'[' without ']'")
        if not _is_ip(host, version=6):
            raise bad(f"bad host {host!r}: not an IPv6 address")
        if not after.startswith(":") or not after[1:]:
            raise bad("missing port")
        return host, after[1:]
    host, sep, port_text = rest.rpartition(":")
    if not sep:
        if mode == "udpin" and rest:
            return LISTEN_HOST, rest
        if rest.isdigit():
            raise bad("missing host", f" (expected {FORMS}; only udpin: may leave it out)")
        raise bad("missing port")
    if not port_text:
        raise bad("missing port")
    if not host:
        raise bad("missing host")
    if ":" in host:
        raise bad(f"bad host {host!r}: write an IPv6 address in brackets, e.g. [::1]")
    return host, port_text


def _check_host(host: str, bad: Callable[..., UsageError]) -> None:
    if ":" in host:   # an IPv6 address, checked by _split
        return
    if re.fullmatch(r"[0-9.]+", host):
        if not _is_ip(host, version=4):
            raise bad(f"bad host {host!r}: not an IPv4 address")
    elif not _HOSTNAME.fullmatch(host):
        raise bad(f"bad host {host!r}")
    elif not _resolves(host):
        raise bad(f"cannot resolve host {host!r}", "")


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
