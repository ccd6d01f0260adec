"""Profiles, clauses and expectations cannot drift apart: a run of every clause against every
builtin PX4, ArduPilot and INAV profile, one per vehicle type (virtual time), fails exactly the
clauses its autopilot's bundled expectations file lists for that vehicle type, errs on none,
and every listed variant is one the profile covers."""

from __future__ import annotations

import re

import pytest

from mavconform.conformance import expectations
from mavconform.conformance.catalogue import CLAUSES
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile

AUTOPILOTS = ("px4", "ardupilot")
# Rows of VARIANTS.md each profile must account for (by a knob or a documented reason).
ROWS = {
    "px4": {f"P{i}" for i in range(1, 15)} | {"P1'", "P2'"},
    "ardupilot": {f"A{i}" for i in range(1, 20)},
}
VARIANT_ID = re.compile(r"^(HB|[APLI]\d+'?)$")   # L: the real SITL link rows; I: INAV


# every builtin profile but the spec's, and the expectations file of its autopilot (inav: its
# vehicle answers only the float forms, which the tester falls back to, harness/float_forms.py)
TYPED = {name: name.split("-")[0] for name in BUILTIN_PROFILES if name != "spec"}


def _run(name: str) -> tuple[dict, expectations.Expectations]:
    expected = expectations.load(TYPED[name])
    with Session(parse_target(f"builtin:{name}"), virtual=True) as session:
        results = {r.clause_id: r for r in run_clauses(session, CLAUSES).results}
        expected.identify(session.identity)
    return results, expected


@pytest.fixture(scope="module", params=sorted(TYPED))
def profile_run(request):
    return (request.param, *_run(request.param))


def test_the_profile_fails_exactly_the_clauses_its_expectations_list(profile_run) -> None:
    name, results, expected = profile_run
    failed = {k for k, r in results.items() if r.outcome is Outcome.FAIL}
    listed = set(expected)
    wrong = {k: results[k].detail for k in failed & listed if not expected[k].excuses(results[k].detail)}
    assert not wrong, f"{name}: failing otherwise than its expectation says: {wrong}"
    detail = {k: results[k].detail for k in failed ^ listed}
    assert failed == listed, (f"{name}: failing but not listed: {sorted(failed - listed)}; listed but "
                              f"passing: {sorted(listed - failed)}; {detail}")


def test_the_profile_leaves_no_clause_undecided(profile_run) -> None:
    name, results, _ = profile_run
    errors = {k: r.detail for k, r in results.items() if r.outcome is Outcome.ERROR}
    assert not errors, errors


def test_every_listed_variant_is_one_the_profile_reproduces(profile_run) -> None:
    name, _, expected = profile_run
    covered = load_profile(name).variants()
    for clause, dev in expected.items():
        assert dev.variant in covered, f"{name}: {clause} cites {dev.variant!r}, not a row of the {name} profile"


@pytest.mark.parametrize("name", AUTOPILOTS)
def test_the_profile_accounts_for_every_row_of_its_autopilot(name: str) -> None:
    profile = load_profile(name)
    assert ROWS[name] <= profile.variants(), sorted(ROWS[name] - profile.variants())
    for s in profile.settings:
        assert VARIANT_ID.match(s.variant) and s.source and s.why, s
    for d in profile.documented:
        assert VARIANT_ID.match(d.variant) and d.why, d


def test_spec_profile_is_the_default_vehicle() -> None:
    from mavconform.reference_impl.mission.behaviour import ServerBehaviour
    from mavconform.reference_impl.vehicle import VehicleConfig
    spec = load_profile("spec")
    assert spec.behaviour == ServerBehaviour() and spec.config == VehicleConfig() and not spec.settings
    # the other builtin profiles are vehicle types of these autopilots (px4-fixedwing, ...): the
    # same mission protocol, judged by the same expectations files
    assert {"spec", *AUTOPILOTS} <= set(BUILTIN_PROFILES)
    assert all(name.split("-")[0] in ("spec", *AUTOPILOTS, "inav") for name in BUILTIN_PROFILES)


def test_the_builtin_vehicle_says_who_it_is() -> None:
    for name, autopilot in (("spec", 7), ("px4", 12), ("ardupilot", 3)):
        with Session(parse_target(f"builtin:{name}"), virtual=True) as session:
            assert session.discover()["autopilot"] == autopilot
