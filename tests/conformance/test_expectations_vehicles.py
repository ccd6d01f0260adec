"""Expectation entries for some vehicle types only: one autopilot stores and flies differently
per vehicle type, so `--expect ardupilot` holds a clause's entry once per class, and which
one applies is known from the target's HEARTBEAT."""

from __future__ import annotations

import pytest

from mavconform.conformance import expectations
from mavconform.conformance.gating import apply_expectations
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.reference_impl.errors import UsageError

FILE = '''
[[deviation]]
clause = "MIS.PRG.01"
reason = "every vehicle loses a report"

[[deviation]]
clause = "MIS.DN.02"
reason = "copter and rover keep param1"
vehicles = ["multicopter", "ground"]
observed = "copter *"

[[deviation]]
clause = "MIS.DN.02"
reason = "a plane keeps param2 and param3"
vehicles = ["fixed-wing", "vtol"]
observed = "plane *"
'''


@pytest.fixture
def scoped(tmp_path):
    path = tmp_path / "scoped.toml"
    path.write_text(FILE)
    return expectations.load(str(path))


def test_before_the_heartbeat_only_the_entries_for_every_vehicle_apply(scoped):
    assert set(scoped) == {"MIS.PRG.01"} and len(scoped.entries) == 3


@pytest.mark.parametrize("mav_type, reason", [(2, "copter and rover keep param1"), (10, "copter and rover keep param1"),
                                              (1, "a plane keeps param2 and param3"),
                                              (22, "a plane keeps param2 and param3")])
def test_the_heartbeats_type_picks_the_entry(scoped, mav_type, reason):
    scoped.identify({"type": mav_type})
    assert set(scoped) == {"MIS.PRG.01", "MIS.DN.02"} and scoped["MIS.DN.02"].reason == reason


def test_a_failure_is_excused_only_by_its_own_vehicles_entry(scoped):
    scoped.identify({"type": 1})   # MAV_TYPE_FIXED_WING
    plane, copter = ClauseResult("MIS.DN.02", Outcome.FAIL, "plane kept p2"), \
        ClauseResult("MIS.DN.02", Outcome.FAIL, "copter kept p1")
    apply_expectations([plane, copter], scoped)
    assert plane.outcome is Outcome.KNOWN_DEVIATION
    assert copter.outcome is Outcome.FAIL and copter.detail.startswith("fails otherwise than the known deviation")


def test_a_vehicle_type_outside_every_scope_gets_the_common_entries_only(scoped):
    scoped.identify({"type": 12})   # MAV_TYPE_SUBMARINE
    assert set(scoped) == {"MIS.PRG.01"}


@pytest.mark.parametrize("text, said", [
    ('vehicles = ["boat"]', "'vehicles' must be a list of vehicle classes from multicopter, fixed-wing, vtol, ground"),
    ('vehicles = "ground"', "'vehicles' must be a list"),
])
def test_a_bad_vehicles_key_is_one_line_naming_the_entry(tmp_path, text, said):
    path = tmp_path / "bad.toml"
    path.write_text(f'[[deviation]]\nclause = "MIS.UP.04"\nreason = "r"\n{text}\n')
    with pytest.raises(UsageError, match=r"bad.toml: deviation\[0\]: " + said):
        expectations.load(str(path))


@pytest.mark.parametrize("first, second, said", [
    ("", "", "listed twice for every vehicle"),
    ('vehicles = ["ground"]', "", "listed twice for every vehicle"),
    ('vehicles = ["ground", "vtol"]', 'vehicles = ["vtol"]', "listed twice for vtol"),
])
def test_one_clause_twice_for_one_vehicle_is_refused(tmp_path, first, second, said):
    path = tmp_path / "twice.toml"
    path.write_text(f'[[deviation]]\nclause = "MIS.UP.04"\nreason = "r"\n{first}\n'
                    f'[[deviation]]\nclause = "MIS.UP.04"\nreason = "s"\n{second}\n')
    with pytest.raises(UsageError, match=r"deviation\[1\]: MIS.UP.04 is " + said):
        expectations.load(str(path))
