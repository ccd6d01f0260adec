"""The same nodes over real UDP on 127.0.0.1 with OS-chosen ports (real time, bounded)."""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.reference_impl.files import SAMPLES_DIR, load_plan
from mavconform.reference_impl.gcs import GcsNode
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType, renumber
from mavconform.reference_impl.net import FaultModel, MonotonicClock, UdpDriver
from mavconform.reference_impl.session import GcsSession, TargetUnresponsive
from mavconform.reference_impl.vehicle import VehicleNode

pytestmark = pytest.mark.udp


def test_plan_round_trip_over_lossy_udp_loopback():
    plan = load_plan(SAMPLES_DIR / "demo.plan")
    clock = MonotonicClock()
    faults = FaultModel(loss=0.1, duplicate=0.05, reorder=0.05, reorder_delay=0.02)
    vehicle = VehicleNode(wall_clock=clock.wall)
    with UdpDriver(clock=clock, seed=4) as driver:
        at = driver.add_node(vehicle, outgoing=faults, incoming=faults.copy())
        gcs = GcsNode(remote=at, wall_clock=clock.wall)
        driver.add_node(gcs)
        session = GcsSession(driver, gcs)
        assert session.wait_for_target(5.0) == (1, 1)
        for t in PLAN_TYPES:
            assert session.upload(t, plan.items(t)).ok
        for t in PLAN_TYPES:
            r = session.download(t)
            assert r.ok and r.items == tuple(renumber(plan.items(t), t))
        assert session.clear(MissionType.ALL).ok
        assert all(vehicle.store.count(t) == 0 for t in PLAN_TYPES)
        assert sum(s.dropped for s in driver.stats.values()) > 0   # the faults were really on


def test_gcs_listening_for_a_vehicle_that_talks_first():
    """udpin: the GCS binds and waits; the vehicle knows its address and sends first (like SITL)."""
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as driver:
        gcs = GcsNode(wall_clock=clock.wall)               # no remote: it learns the vehicle's address
        gcs_at = driver.add_node(gcs)
        vehicle = VehicleNode(wall_clock=clock.wall)
        driver.add_node(vehicle)
        vehicle.endpoint.add_address(gcs_at)
        session = GcsSession(driver, gcs)
        session.wait_for_target(5.0)
        items = load_plan(SAMPLES_DIR / "demo.waypoints").mission
        assert session.upload(MissionType.MISSION, items).ok
        plan = tuple(dataclasses.replace(it, current=0) for it in renumber(items, MissionType.MISSION))
        assert session.download(MissionType.MISSION).items == plan   # `current` is vehicle state


def test_silent_target_is_reported_within_the_bound():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as driver:
        silent = driver.add_node(GcsNode(wall_clock=clock.wall))   # a GCS never claims to be a vehicle
        gcs = GcsNode(remote=silent, wall_clock=clock.wall)
        driver.add_node(gcs)
        start = clock.now()
        with pytest.raises(TargetUnresponsive):
            GcsSession(driver, gcs).wait_for_target(0.3)
        assert clock.now() - start < 2.0
