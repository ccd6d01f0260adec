"""MISSION_ITEM_REACHED with one pending slot (item_reached_one_slot): a waypoint followed by a
DO command, which is done at once, is never reported on its own; only the DO's seq is. The spec
vehicle reports every item. Virtual time, the vehicle on a SimNetwork with a GCS."""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.progress import REACHED_SLOT_DELAY
from mavconform.reference_impl.vehicle import VehicleConfig

from ..rigs import vehicle_and_gcs

HOME = (47.397742, 8.545594)


def wp(seq: int, north_m: float, alt: float = 20.0) -> MissionItem:
    lat = HOME[0] + north_m / 111_195.0
    return MissionItem(seq, 3, int(Cmd.NAV_WAYPOINT), x=round(lat * 1e7), y=round(HOME[1] * 1e7), z=alt)


# waypoint, DO_CHANGE_SPEED, waypoint, DO_CHANGE_SPEED, DO_CHANGE_SPEED, waypoint
PLAN = [wp(0, 0), wp(1, 100), MissionItem(2, 2, int(Cmd.DO_CHANGE_SPEED), param2=5.0), wp(3, 200),
        MissionItem(4, 2, int(Cmd.DO_CHANGE_SPEED), param2=8.0),
        MissionItem(5, 2, int(Cmd.DO_CHANGE_SPEED), param2=6.0), wp(6, 300)]


def fly(config: VehicleConfig) -> tuple[list[tuple[float, int]], float]:
    """Every MISSION_ITEM_REACHED (arrival time, seq) of a flight of PLAN, and when it ended."""
    rig = vehicle_and_gcs(dataclasses.replace(config, autostart=True), seed=3)
    assert rig.session.upload(MissionType.MISSION, PLAN).ok
    got: list[tuple[float, int]] = []
    seen = 0

    def collect() -> bool:
        nonlocal seen
        for msg in rig.gcs.received[seen:]:
            if msg.get_type() == "MISSION_ITEM_REACHED":
                got.append((rig.net.clock.now(), msg.seq))
        seen = len(rig.gcs.received)
        return any(seq == 6 for _, seq in got)

    assert rig.net.run_until(collect, timeout=120)
    end = rig.net.clock.now()
    rig.net.run_for(15.0)
    collect()
    return got, end


def test_the_spec_vehicle_reports_every_item_at_once():
    got, _ = fly(VehicleConfig())
    assert [seq for _, seq in got] == [0, 1, 2, 3, 4, 5, 6]


def test_one_slot_reports_only_the_later_of_two_items_done_close_together():
    config = VehicleConfig(behaviour=dataclasses.replace(VehicleConfig().behaviour, item_reached_one_slot=True))
    got, _ = fly(config)
    # waypoint 1 is replaced by DO 2 (0.1 s later); waypoint 3 by DO 4 and then DO 5
    assert [seq for _, seq in got] == [0, 2, 5, 6]


def test_the_slot_is_sent_at_the_next_send_opportunity_and_px4s_repeats_follow_it():
    spec = VehicleConfig().behaviour
    slotted = dataclasses.replace(spec, item_reached_one_slot=True)
    plain, _ = fly(VehicleConfig())
    repeated, _ = fly(VehicleConfig(behaviour=dataclasses.replace(slotted, item_reached_repeats=3)))
    when = dict((seq, t) for t, seq in reversed(plain))          # first report of each seq
    first = {}
    for t, seq in repeated:
        first.setdefault(seq, t)
    # the waypoint reached at t is reported with the DO's seq at t + REACHED_SLOT_DELAY
    assert first[2] == pytest.approx(when[1] + REACHED_SLOT_DELAY, abs=0.02)
    assert first[6] == pytest.approx(when[6] + REACHED_SLOT_DELAY, abs=0.02)
    # each report is repeated twice more, 1 s apart (P13's repeats, of the later seq only)
    assert [seq for _, seq in repeated].count(6) == 3 and 1 not in {seq for _, seq in repeated}
