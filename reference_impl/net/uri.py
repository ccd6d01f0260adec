"""Link addresses: the one grammar, and its one parser, for every command and plugin option.

    udp:HOST:PORT         a peer listens at HOST:PORT; we send to it first
    udpin:[HOST:]PORT     we listen at HOST:PORT (127.0.0.1 if no host); the peer sends first (as SITL does)
    tcp:HOST:PORT         a peer listens at HOST:PORT; we connect (and reconnect)
    tcpin:[HOST:]PORT     we listen for one TCP peer at a time (127.0.0.1 if no host)
    serial:DEVICE[:BAUD]  a serial port (pyserial), 57600 baud unless BAUD is given
    pty[:BAUD]            (where we listen only) a new pseudo-terminal pair: we serve on it and
                          print the device (/dev/pts/N) the peer opens as serial:/dev/pts/N
HOST is an IPv4 address, a host name, or an IPv6 address in brackets ([::1]). A DEVICE may
itself hold colons (/dev/serial/by-path/...): a trailing `:digits` is the baud rate, and a
trailing `:word` is a bad baud rate when what precedes it is an existing file.
What an option does with the address (its `role`) decides which of these make sense for it,
so `--forward udpin:...` is refused by saying what --forward needs, not as a syntax error.
A bad address is the user's mistake: `UsageError`, one line quoting the text and saying
what is wrong, including a host name that does not resolve (now, not later as "no
HEARTBEAT from the target"). Resolving a name is the only network access here; a serial
device is opened (and a missing one said) when the link is made (links.py).
"""

from __future__ import annotations

import ipaddress
import os
import re
import socket
from dataclasses import dataclass
from typing import Callable, Literal

from ..errors import UsageError

UDP_SCHEMES = ("udp", "udpin")
SCHEMES = ("udp", "udpin", "tcp", "tcpin", "serial", "pty")
UDP_FORMS = "udp:HOST:PORT or udpin:[HOST:]PORT"
FORMS = "udp:HOST:PORT, udpin:[HOST:]PORT, tcp:HOST:PORT, tcpin:[HOST:]PORT or serial:DEVICE[:BAUD]"
LISTEN_FORMS = "udpin:[HOST:]PORT, tcpin:[HOST:]PORT, serial:DEVICE[:BAUD] or pty[:BAUD]"
PEER_FORMS = "udp:HOST:PORT, tcp:HOST:PORT or serial:DEVICE[:BAUD]"
DEFAULT_BAUD = 57600
BAUD_RANGE = (50, 20_000_000)
LISTEN_HOST = "127.0.0.1"   # udpin:PORT: loopback, so nothing is exposed unless a host is named
_HOSTNAME = re.compile(r"(?=.{1,253}\Z)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
                       r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?")

# What an option does with an address:
#   target  the scheme says who listens: udp:/tcp: the peer, udpin:/tcpin: we; serial: either
#           (run, fuzz, gcs --target);
#   listen  we listen there (udp: too, whatever the scheme); port 0 is any free port; pty: a
#           new pseudo-terminal (vehicle/proxy --listen);
#   peer    a peer listens there and we send first: udp:, tcp: or serial: (vehicle --connect,
#           proxy --forward).
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


@dataclass(frozen=True)
class TcpUri:
    mode: str   # "tcp" (we connect to a listening peer) or "tcpin" (we listen)
    host: str
    port: int

    @property
    def address(self) -> tuple[str, int]:
        return (self.host, self.port)

    def __str__(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{self.mode}:{host}:{self.port}"


@dataclass(frozen=True)
class SerialUri:
    device: str   # a path, or "pty": a new pseudo-terminal pair
    baud: int

    @property
    def mode(self) -> str:
        return "pty" if self.device == "pty" else "serial"

    def __str__(self) -> str:
        return f"pty:{self.baud}" if self.device == "pty" else f"serial:{self.device}:{self.baud}"


LinkUri = UdpUri | TcpUri | SerialUri


def parse_udp_uri(text: str, *, role: Role = "target", option: str | None = None) -> UdpUri:
    """A UDP address only, for what has no stream form (the UDP-only tools)."""
    uri = parse_link_uri(text, role=role, option=option, schemes=UDP_SCHEMES)
    assert isinstance(uri, UdpUri)
    return uri


def parse_link_uri(text: str, *, role: Role = "target", option: str | None = None,
                   schemes: tuple[str, ...] = SCHEMES) -> LinkUri:
    """Parse an address for an option of the given `role`; `option` (e.g. "--listen")
    starts the error message, so the user learns which of several addresses is wrong."""
    where = f"{option}: " if option else ""
    forms = UDP_FORMS if schemes == UDP_SCHEMES else \
        {"listen": LISTEN_FORMS, "peer": PEER_FORMS}.get(role, FORMS)

    def bad(what: str, hint: str = f" (expected {forms})") -> UsageError:
        return UsageError(f"{where}bad endpoint {text!r}: {what}{hint}")

    scheme, sep, rest = text.strip().partition(":")
    mode = scheme.lower()
    if mode == "pty" and "pty" in schemes:
        return _serial("pty", rest if sep else "", role, bad)
    if not sep:
        raise bad("missing scheme")
    if mode not in schemes:
        raise bad(f"unknown scheme {scheme!r}")
    if mode == "serial":
        return _serial("serial", rest, role, bad)
    host, port_text = _split(rest, mode, bad)
    _check_host(host, bad)
    if not port_text.isdigit() or not port_text.isascii():
        raise bad(f"bad port {port_text!r}: not a number")
    port = int(port_text)
    if port > 65535:
        raise bad(f"bad port {port}: must be 0..65535")
    if role == "peer" and mode in ("udpin", "tcpin"):
        raise bad(f"here a peer listens and we send first: give {mode[:3]}:HOST:PORT "
                  f"({mode}: is for an address we listen at)", "")
    if role == "listen" and mode == "tcp":
        raise bad("here we listen: give tcpin:[HOST:]PORT (tcp: is for a peer that listens)", "")
    if port == 0 and mode in ("udp", "tcp") and role != "listen":
        raise bad("port 0 is only allowed where we listen (we cannot send to port 0)")
    if mode in ("tcp", "tcpin"):
        return TcpUri(mode, host, port)
    return UdpUri(mode, host, port)


def _serial(mode: str, rest: str, role: Role, bad: Callable[..., UsageError]) -> SerialUri:
    """serial:DEVICE[:BAUD] or pty[:BAUD]."""
    if mode == "pty":
        if role != "listen":
            raise bad("pty: makes a pseudo-terminal to serve on, so it is for --listen; "
                      "give the device it printed as serial:/dev/pts/N[:BAUD]", "")
        return SerialUri("pty", _baud(rest, bad) if rest else DEFAULT_BAUD)
    device, sep, tail = rest.rpartition(":")
    if sep and tail.isdigit() and tail.isascii():
        baud = _baud(tail, bad)
    elif sep and device and os.path.exists(device) and not os.path.exists(rest):
        raise bad(f"bad baud rate {tail!r}: not a number", "")
    else:
        device, baud = rest, DEFAULT_BAUD
    if not device:
        raise bad("missing device", " (expected serial:DEVICE[:BAUD], e.g. serial:/dev/ttyACM0:115200)")
    return SerialUri(device, baud)


def _baud(text: str, bad: Callable[..., UsageError]) -> int:
    if not (text.isdigit() and text.isascii()):
        raise bad(f"bad baud rate {text!r}: not a number", "")
    baud = int(text)
    if not BAUD_RANGE[0] <= baud <= BAUD_RANGE[1]:
        raise bad(f"bad baud rate {baud}: must be {BAUD_RANGE[0]}..{BAUD_RANGE[1]}", "")
    return baud


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
        if mode in ("udpin", "tcpin") and rest:
            return LISTEN_HOST, rest
        if rest.isdigit():
            raise bad("missing host", f" ({mode}:HOST:PORT; only udpin: and tcpin: may leave it out)")
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
