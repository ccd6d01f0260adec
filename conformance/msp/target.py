"""MSP targets: which flight controller the MSP clauses talk to, and the link to it.

- `builtin:msp`          our MSP flight controller (reference_impl/msp/flight_controller.py,
                         INAV 9.1's waypoint store as its SITL answered), in this process,
                         over real TCP loopback (virtual time in the tool's own tests);
- `msp-mutant:NAME`      the same with one behaviour broken (mutants.py), the negative controls;
- `msp:tcp:HOST:PORT`    a flight controller serving MSP on TCP (INAV's SITL: 5760 and 5761);
- `msp:tcpin:[HOST:]PORT` we listen and the flight controller connects;
- `msp:udp:HOST:PORT`    MSP in UDP datagrams (a bridge or a simulator that speaks it so);
- `msp:serial:DEVICE[:BAUD]` a flight controller on a serial port (115200 baud unless given:
                         INAV's MSP default, unlike MAVLink's 57600).
A mistake is one `UsageError` line quoting the text.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.msp.links import parse_msp_link
from mavconform.reference_impl.net.uri import LinkUri, SerialUri

BUILTIN = "builtin:msp"
MUTANT_PREFIX = "msp-mutant:"
LINK_PREFIX = "msp:"
FORMS = (f"{BUILTIN}, {MUTANT_PREFIX}NAME, msp:tcp:HOST:PORT, msp:tcpin:[HOST:]PORT, msp:udp:HOST:PORT "
         "or msp:serial:DEVICE[:BAUD]")


@dataclass(frozen=True)
class MspTarget:
    kind: str                    # builtin | mutant | link
    name: str = ""               # the mutant's name
    link: LinkUri | None = None

    @property
    def in_process(self) -> bool:
        return self.kind in ("builtin", "mutant")

    def __str__(self) -> str:
        if self.kind == "builtin":
            return BUILTIN
        if self.kind == "mutant":
            return f"{MUTANT_PREFIX}{self.name}"
        return f"{LINK_PREFIX}{self.link}"


def is_msp_target(text: str | None) -> bool:
    """Whether `--target` names an MSP flight controller (the MSP clauses, not MAVLink's)."""
    if text is None:
        return False
    raw = text.strip().lower()
    return raw == BUILTIN or raw.startswith(MUTANT_PREFIX) or raw.startswith(LINK_PREFIX)


def parse_msp_target(text: str) -> MspTarget:
    raw = text.strip()
    lowered = raw.lower()
    if lowered == BUILTIN:
        return MspTarget("builtin")
    if lowered.startswith(MUTANT_PREFIX):
        from .mutants import MSP_MUTANTS
        name = raw[len(MUTANT_PREFIX):]
        if name not in MSP_MUTANTS:
            raise UsageError(f"bad target {text!r}: unknown MSP mutant {name!r} "
                             "(list them with `mavconform clauses --role msp --mutants`)")
        return MspTarget("mutant", name)
    if not lowered.startswith(LINK_PREFIX):
        raise UsageError(f"bad target {text!r}: not an MSP target (expected {FORMS})")
    rest = raw[len(LINK_PREFIX):]
    if rest.lower().startswith("pty"):
        raise UsageError(f"bad target {text!r}: pty is where we serve; a flight controller on a "
                         "pseudo-terminal is msp:serial:/dev/pts/N")
    link = parse_msp_link(rest, option="--target")
    if isinstance(link, SerialUri):
        if not os.path.exists(link.device):
            raise UsageError(f"cannot open serial port {link.device}: No such file or directory")
    elif link.mode == "udpin":
        raise UsageError(f"bad target {text!r}: MSP is asked, never sent first: give msp:udp:HOST:PORT")
    return MspTarget("link", link=link)
