"""Target URIs: which vehicle the suite talks to.

- `builtin:spec`       our reference vehicle, in this process, over real UDP loopback;
  `builtin:px4`, `builtin:ardupilot`: the same with a PX4-like or ArduPilot-like profile
                       (reference_impl/profiles, VARIANTS.md), and their other vehicle
                       types: `builtin:px4-fixedwing`, `builtin:px4-vtol`,
                       `builtin:ardupilot-plane`, `builtin:ardupilot-rover`;
- `mutant:NAME`        a reference vehicle with one behaviour broken (the negative controls;
                       `mavconform clauses --mutants` lists them), also over loopback;
- `udp:HOST:PORT`      a target listening at HOST:PORT; we send first (our HEARTBEAT);
- `udpin:[HOST:]PORT`  we listen at HOST:PORT (default host 127.0.0.1) and the target sends
                       to us first, as SITL does;
- `tcp:HOST:PORT`      a target serving TCP there (ArduPilot SITL's 5760, INAV's 5760+n-1);
- `tcpin:[HOST:]PORT`  we listen for the target's TCP connection;
- `serial:DEVICE[:BAUD]` a flight controller on a serial port (57600 baud by default).
The link forms are parsed by reference_impl.net.uri, the one parser every command's and
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
`mavconform vehicle --operator-control --open-when-unowned` serves the system manager
`builtin:spec` runs (the HO.CTL behaviour); `builtin:spec` also runs the mission computer
loaded from the conformance scenario, which `vehicle --handover conformance` serves with
that scenario's own owner-loss time and its emergency procedure on.

The handover sequence (the HO.SEQ clauses: the thesis's procedure, seed 003 ch. 4, over
operator control; docs/handover.md). The tester must know what the target's mission
computer was loaded with: which GCS is the parent, every GCS's system id and coverage, the
dwell and the bound. A handover scenario file says it (`--handover-scenario FILE`, read by
`reference_impl/handover/scenario.py`; the URI carries it as `scenario`); without one it is
the shipped `scenarios/conformance.json` (`conformance_scenario()`): the suite's two GCSs,
245 and 246, with 150 m discs, A's around the reference home and B's 250 m east, so the
handover region is the lens 100-150 m east of home. Under the suite `builtin:spec` also runs
the thesis's mission computer loaded from that same scenario (`handover_config`, as
`mavconform vehicle --handover` loads it), so the HO.SEQ clauses pass on it; the mission
clauses never ask for control, and a mission computer hands over only from a commander, so
their flights (25-75 m north of home, in A's disc only) never start one. The profiles and
every mutant but the HO.SEQ ones (mutants/handover_sequence.py) have none: there the HO.SEQ
clauses are not-applicable. The HO.SEQ mutants always run the conformance scenario's mission
computer, whatever `--handover-scenario` says. The suite's GCSs do not sign: against a vehicle
loaded with a scenario that has GCS keys, let it accept unsigned frames
(`mavconform vehicle --handover FILE --accept-unsigned`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.mission_computer import MissionComputerConfig
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, Scenario, load_scenario, scenario_path
from mavconform.reference_impl.handover.scenario_fleet import mission_computer_config
from mavconform.reference_impl.net.uri import FORMS as LINK_FORMS
from mavconform.reference_impl.net.uri import LinkUri, UdpUri, parse_link_uri
from mavconform.reference_impl.profiles import BUILTIN_PROFILES

FORMS = f"builtin:{'|'.join(BUILTIN_PROFILES)}, mutant:NAME, {LINK_FORMS}"
LINK_KINDS = ("udp", "udpin", "tcp", "tcpin", "serial")

# The system manager `builtin:spec` (and every HO mutant) runs under the suite: the reference
# manager's defaults (1 Hz CONTROL_STATUS, 5 s owner loss, a 10 s takeover window), open to
# every GCS while none is in control.
SUITE_CONTROL = ManagerConfig(open_when_unowned=True)

# The handover scenario the HO.SEQ clauses assume when none is given (see the docstring).
CONFORMANCE_SCENARIO = SCENARIOS_DIR / "conformance.json"


@lru_cache(maxsize=None)
def conformance_scenario() -> Scenario:
    return load_scenario(CONFORMANCE_SCENARIO)


def handover_config(scenario: Scenario) -> MissionComputerConfig:
    """The mission computer's load from a scenario (scenario_fleet's), with the emergency
    procedure off: nothing here judges it, and it would take over a clause's flight."""
    return replace(mission_computer_config(scenario), emergency=None)


@lru_cache(maxsize=None)
def suite_handover() -> MissionComputerConfig:
    """The mission computer `builtin:spec` (and every HO.SEQ mutant) runs under the suite by
    default: loaded from the conformance scenario."""
    return handover_config(conformance_scenario())


def load_handover_scenario(text: str, option: str = "--handover-scenario") -> Scenario:
    """`--handover-scenario FILE`: a scenario file, or the name of a shipped one (`conformance`,
    `delivery-flight`, ...). A mistake is one `UsageError` line naming the option and the file
    (and the field)."""
    try:
        scenario = load_scenario(scenario_path(text))
    except UsageError as exc:
        raise UsageError(f"{option}: {exc}") from None
    from .checks.handover_route import route_of   # the clauses say what they can fly
    route_of(scenario, option=f"{option} {text}")
    return scenario


@dataclass(frozen=True)
class TargetUri:
    kind: str                 # builtin | mutant | udp | udpin | tcp | tcpin | serial
    name: str = ""            # profile or mutant name
    link: LinkUri | None = None
    # what the target's mission computer was loaded with (--handover-scenario); None: the
    # conformance scenario (`handover_scenario`)
    scenario: Scenario | None = None
    # what an external target is, when its HEARTBEAT cannot say (--profile: INAV reports a
    # generic autopilot): the builtin profile or profile file whose stored form it keeps
    profile: str | None = None

    @property
    def in_process(self) -> bool:
        return self.kind in ("builtin", "mutant")

    def __str__(self) -> str:
        return f"{self.kind}:{self.name}" if self.in_process else str(self.link)

    @property
    def udp(self) -> UdpUri | None:
        """The UDP address, for a udp: or udpin: target."""
        return self.link if isinstance(self.link, UdpUri) else None

    @property
    def handover_scenario(self) -> Scenario:
        """The handover scenario the HO.SEQ clauses assume of this target."""
        return self.scenario if self.scenario is not None else conformance_scenario()

    def with_scenario(self, scenario: Scenario | None) -> "TargetUri":
        return replace(self, scenario=scenario)

    def with_profile(self, profile: str | None, option: str = "--profile") -> "TargetUri":
        """This external target, said to be what `profile` models (checked now: a bad name
        or file is one line naming the option)."""
        if profile is None:
            return self
        if self.in_process:
            raise UsageError(f"{option} is for an external target; {self} names its vehicle already")
        from mavconform.reference_impl.profiles import load_profile
        try:
            load_profile(profile)
        except UsageError as exc:
            raise UsageError(f"{option}: {exc}") from None
        return replace(self, profile=profile)

    def suite_overrides(self) -> dict[str, Any]:
        """`VehicleConfig` fields the conformance suite sets on the in-process vehicle this
        URI names: operator control and the mission computer (loaded from the handover
        scenario) on `builtin:spec` (see the module docstring), nothing elsewhere. The
        fuzzers do not apply them: their vehicle stays the profile's."""
        if self.kind == "builtin" and self.name == "spec":
            handover = suite_handover() if self.scenario is None else handover_config(self.scenario)
            return {"control": SUITE_CONTROL, "handover": handover}
        return {}


def parse_target(text: str) -> TargetUri:
    """builtin: and mutant: here; the links (udp:, tcp:, serial:, ...) by the one link parser."""
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
    if scheme in LINK_KINDS:
        link = parse_link_uri(raw)
        if scheme == "serial" and not os.path.exists(link.device):   # before any report folder
            raise UsageError(f"cannot open serial port {link.device}: No such file or directory")
        return TargetUri(link.mode, link=link)
    raise UsageError(f"bad target {text!r}: unknown scheme {scheme!r} (expected {FORMS})")
