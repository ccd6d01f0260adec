"""The vehicles that stay armed (conformance/mutants/arming.py), for a clause on the suite's
own flight: one refuses MISSION_START once armed, one ignores disarming (virtual time)."""

from __future__ import annotations

from mavconform.conformance.mutants import MUTANTS
from mavconform.conformance.mutants.arming import IgnoresDisarm, RefusesMissionStartArmed, arming_mutant
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.vehicle import VehicleConfig

from .pilot import TAKEOFF_WP_LAND, Pilot

GUIDED = 4


def build(cls, **kw):
    make = arming_mutant(cls, **kw)
    return lambda wall_clock: make(VehicleConfig())


def test_a_vehicle_that_refuses_mission_start_once_armed_stays_armed_until_disarmed():
    p = Pilot(build(RefusesMissionStartArmed))
    p.upload(TAKEOFF_WP_LAND)
    assert p.set_mode(GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.FAILED and p.mode() == GUIDED
    p.run(60.0)                                   # no idle disarm: it waits for the GCS
    assert p.armed() and p.beat().base_mode & 128 and p.reached() == []
    assert p.disarm() == R.ACCEPTED and not p.armed()


def test_a_vehicle_that_ignores_disarm_stays_armed_after_its_landing():
    p = Pilot(build(IgnoresDisarm))
    p.upload(TAKEOFF_WP_LAND)
    assert p.set_mode(GUIDED) == R.ACCEPTED and p.arm() == R.ACCEPTED
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED
    assert p.run_until(lambda: 4 in p.reached(), timeout=120)
    p.run(30.0)
    assert p.altitude() == 0.0 and p.armed()      # landed, and no disarm by itself
    assert p.disarm() == R.ACCEPTED and p.armed()
    assert p.disarm(force=True) == R.ACCEPTED and p.armed() and p.beat().base_mode & 128


def test_they_can_be_built_on_another_profile_and_are_not_registered():
    p = Pilot(build(IgnoresDisarm, profile="px4"))
    p.upload(TAKEOFF_WP_LAND)
    assert p.command(Cmd.MISSION_START, 0, 0) == R.ACCEPTED and p.run_until(lambda: 3 in p.reached(), timeout=120)
    p.run(10.0)
    assert p.armed() and p.beat().autopilot == 12
    assert not {"refuses-mission-start-armed", "ignores-disarm"} & set(MUTANTS)
