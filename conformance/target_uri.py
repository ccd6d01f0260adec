"""Target URIs: which vehicle the suite talks to.

- `builtin:spec`       our reference vehicle, in this process, over real UDP loopback;
  `builtin:px4`, `builtin:ardupilot`: the same with a PX4-like or ArduPilot-like profile
                       (reference_impl/profiles, VARIANTS.md);
- `mutant:NAME`        a reference vehicle with one behaviour broken (the negative controls;
                       `mavconform clauses --mutants` lists them), also over loopback;
- `udp:HOST:PORT`      a target listening at HOST:PORT; we send first (our HEARTBEAT);
- `udpin:[HOST:]PORT`  we listen at HOST:PORT (default host 127.0.0.1) and the target sends
                       to us first, as SITL does.
The UDP forms are parsed by reference_impl.net.uri, the one parser every command's and
plugin's addresses go through, so `run`, `fuzz`, `gcs`, `vehicle` and `proxy` agree.
A bad URI is the user's mistake: one `UsageError` line quoting it.

Operator control (the HO.* clauses). Under the suite, `builtin:spec` is its own system
manager (`SUITE_CONTROL`: development.xml's MAV_CMD_REQUEST_OPERATOR_CONTROL, CONTROL_STATUS
at 1 Hz), so the HO clauses pass on the reference vehicle. It runs open while no GCS is in
control (`open_when_unowned`, a choice the XML leaves to the vehicle), so the mission
clauses, which never ask for control, see the same vehicle as before: same answers, and a
CONTROL_STATUS stream that the exchanges do not record (harness/exchange.py keeps only
mission traffic), so reports stay as stable as they were. `builtin:px4` and
`builtin:ardupilot` keep their profiles' vehicles, which have no system manager: there the
HO clauses are not-applicable, as on any target that sends no CONTROL_STATUS or answers
32100 with MAV_RESULT_UNSUPPORTED. Mutants keep the vehicle they declare: the HO mutants
(mutants/operator_control.py) turn the same `SUITE_CONTROL` on, the others leave it off.
The fuzzers build their vehicles without these overrides (`session.build_vehicle`).
`mavconform vehicle --operator-control --open-when-unowned` serves what `builtin:spec` runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.net.uri import (FORMS as UDP_FORMS, SCHEMES as UDP_SCHEMES, UdpUri,
                                                parse_udp_uri)
from mavconform.reference_impl.profiles import BUILTIN_PROFILES

FORMS = f"builtin:spec|px4|ardupilot, mutant:NAME, {UDP_FORMS}"

# The system manager `builtin:spec` (and every HO mutant) runs under the suite: the reference
# manager's defaults (1 Hz CONTROL_STATUS, 5 s owner loss, a 10 s takeover window), open to
# every GCS while none is in control.
SUITE_CONTROL = ManagerConfig(open_when_unowned=True)


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

    def suite_overrides(self) -> dict[str, Any]:
        """`VehicleConfig` fields the conformance suite sets on the in-process vehicle this
        URI names: operator control on `builtin:spec` (see the module docstring), nothing
        elsewhere. The fuzzers do not apply them: their vehicle stays the profile's."""
        if self.kind == "builtin" and self.name == "spec":
            return {"control": SUITE_CONTROL}
        return {}


def parse_target(text: str) -> TargetUri:
    """builtin: and mutant: here; udp: and udpin: by the one UDP address parser."""
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
    if scheme in UDP_SCHEMES:
        udp = parse_udp_uri(raw)
        return TargetUri(udp.mode, udp=udp)
    raise UsageError(f"bad target {text!r}: unknown scheme {scheme!r} (expected {FORMS})")
