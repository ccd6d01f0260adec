"""Target URIs: which vehicle the suite talks to.

- `builtin:spec`       our reference vehicle, in this process, over real UDP loopback;
  `builtin:px4`, `builtin:ardupilot`: the same with a PX4-like or ArduPilot-like profile
                       (reference_impl/profiles, VARIANTS.md);
- `mutant:NAME`        a reference vehicle with one behaviour broken (the negative controls;
                       `mavconform clauses --mutants` lists them), also over loopback;
- `udp:HOST:PORT`      a target listening at HOST:PORT; we send first (our HEARTBEAT);
- `udpin:[HOST:]PORT`  we listen at HOST:PORT (default host 127.0.0.1) and the target sends
                       to us first, as SITL does.
A bad URI is the user's mistake: one `UsageError` line quoting it.
"""

from __future__ import annotations

from dataclasses import dataclass

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.uri import UdpUri, parse_udp_uri
from mavconform.reference_impl.profiles import BUILTIN_PROFILES

FORMS = "builtin:spec|px4|ardupilot, mutant:NAME, udp:HOST:PORT or udpin:[HOST:]PORT"


@dataclass(frozen=True)
class TargetUri:
    kind: str                 # builtin | mutant | udp | udpin
    name: str = ""            # profile or mutant name
    udp: UdpUri | None = None

    @property
    def in_process(self) -> bool:
        return self.kind in ("builtin", "mutant")

    def __str__(self) -> str:
        return f"{self.kind}:{self.name}" if self.in_process else str(self.udp)


def parse_target(text: str) -> TargetUri:
    raw = text.strip()
    scheme, sep, rest = raw.partition(":")
    scheme = scheme.lower()
    if not sep:
        raise UsageError(f"bad target {text!r}: missing scheme (expected {FORMS})")
    if scheme == "builtin":
        if rest not in BUILTIN_PROFILES:
            raise UsageError(f"bad target {text!r}: unknown builtin profile {rest!r} "
                             f"(known: {', '.join(BUILTIN_PROFILES)})")
        return TargetUri("builtin", rest)
    if scheme == "mutant":
        from .mutants import MUTANTS
        if rest not in MUTANTS:
            raise UsageError(f"bad target {text!r}: unknown mutant {rest!r} "
                             "(list them with `mavconform clauses --mutants`)")
        return TargetUri("mutant", rest)
    if scheme == "udp":
        return TargetUri("udp", udp=parse_udp_uri(raw))
    if scheme == "udpin":
        if rest.isdigit():
            raw = f"udpin:127.0.0.1:{rest}"
        return TargetUri("udpin", udp=parse_udp_uri(raw, listen=True))
    raise UsageError(f"bad target {text!r}: unknown scheme {scheme!r} (expected {FORMS})")
