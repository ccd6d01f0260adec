"""Client and server over SimNetwork with scripted drops: each recovers, or fails honestly."""

from __future__ import annotations

from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.results import Outcome
from mavconform.reference_impl.net import DropMessage, FaultModel

from ..rigs import vehicle_and_gcs
from .conftest import plan


def rig(up=(), down=()):
    r = vehicle_and_gcs(seed=5, up=FaultModel(rules=tuple(up)), down=FaultModel(rules=tuple(down)))
    return r.net, r.vehicle, r.session


def test_dropped_second_request_is_retried_after_the_item_timeout():
    net, vehicle, s = rig(down=[DropMessage("MISSION_REQUEST_INT", nth=2)])
    r = s.upload(MissionType.MISSION, plan(4))
    assert r.ok and vehicle.server.stats.retries == 1
    assert r.finished - r.started < 0.5


def test_dropped_first_count_is_resent_by_the_gcs():
    net, vehicle, s = rig(up=[DropMessage("MISSION_COUNT", nth=1)])
    r = s.upload(MissionType.MISSION, plan(2))
    assert r.ok and r.retries == 1 and 1.5 <= r.finished - r.started < 2.0


def test_lost_final_ack_is_recovered_by_resending_the_last_item():
    net, vehicle, s = rig(down=[DropMessage("MISSION_ACK", nth=1)])
    r = s.upload(MissionType.FENCE, plan(3, MissionType.FENCE))
    assert r.ok and r.retries == 1 and r.opaque_id == vehicle.store.opaque_id(MissionType.FENCE)


def test_every_ack_lost_is_an_unknown_outcome_and_the_plan_is_whole():
    net, vehicle, s = rig(down=[DropMessage("MISSION_ACK")])
    items = plan(3)
    r = s.upload(MissionType.MISSION, items)
    assert r.outcome is Outcome.TIMEOUT and r.outcome_unknown and r.retries == 5
    assert list(vehicle.store.items(MissionType.MISSION)) == items


def test_all_items_lost_fails_cleanly_with_old_plan():
    net, vehicle, s = rig(up=[DropMessage("MISSION_ITEM_INT", nth=2, onwards=True)])
    old = vehicle.store.items(MissionType.MISSION)
    r = s.upload(MissionType.MISSION, plan(3))
    assert not r.ok and not r.outcome_unknown
    assert vehicle.store.items(MissionType.MISSION) == old
    assert vehicle.server.stats.max_consecutive_retries == 5


def test_download_survives_dropped_items_and_count():
    net, vehicle, s = rig(down=[DropMessage("MISSION_COUNT", nth=1), DropMessage("MISSION_ITEM_INT", nth=2),
                                DropMessage("MISSION_ITEM_INT", nth=3)])
    items = plan(4)
    vehicle.store.commit(MissionType.MISSION, items)
    r = s.download(MissionType.MISSION)
    assert r.ok and r.items == tuple(items) and r.retries == 3
