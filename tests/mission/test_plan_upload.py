"""A .plan upload is all-or-nothing by default: the first refused part stops the rest, and the
report says what went, what did not, and which earlier plans were replaced; `keep_going`
tries every part. The reference GCS against a reference vehicle, in virtual time."""

from __future__ import annotations

import argparse

import pytest

from mavconform import gcs_cmd
from mavconform.reference_impl.files import load_plan, plan_from_items, save_plan
from mavconform.reference_impl.mission.behaviour import ServerBehaviour
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType
from mavconform.reference_impl.mission.plan_upload import previous_plans, upload_plan
from mavconform.reference_impl.mission.results import Outcome
from mavconform.reference_impl.vehicle import VehicleConfig

from ..rigs import vehicle_and_gcs
from .conftest import plan

M, F, RA = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY
PARTS = [(M, plan(3)), (F, plan(2, F)), (RA, plan(1, RA))]
NO_MISSIONS = ServerBehaviour(supported_types=frozenset({F, RA}))   # mission uploads: UNSUPPORTED


def rig(behaviour: ServerBehaviour = ServerBehaviour()):
    r = vehicle_and_gcs(VehicleConfig(behaviour=behaviour), seed=5)
    return r.net, r.vehicle, r.session


def test_a_refused_mission_leaves_fence_and_rally_unsent() -> None:
    net, vehicle, session = rig(NO_MISSIONS)
    done = upload_plan(PARTS, session.upload)
    assert [(r.mission_type, r.outcome, r.nack) for r in done.results] == [(M, Outcome.NACK, R.UNSUPPORTED)]
    assert done.not_sent == (F, RA) and done.uploaded == () and not done.ok
    assert vehicle.store.count(F) == vehicle.store.count(RA) == 0
    assert done.report()[0] == ("plan upload stopped at the mission: uploaded nothing; not uploaded "
                                "mission (nack), fence (not sent), rally (not sent)")


def test_keep_going_still_uploads_fence_and_rally() -> None:
    net, vehicle, session = rig(NO_MISSIONS)
    done = upload_plan(PARTS, session.upload, keep_going=True)
    assert [(r.mission_type, r.ok) for r in done.results] == [(M, False), (F, True), (RA, True)]
    assert done.not_sent == () and done.uploaded == (F, RA) and not done.ok
    assert (vehicle.store.count(F), vehicle.store.count(RA)) == (2, 1)
    assert done.report()[0] == "plan upload incomplete: uploaded fence, rally; not uploaded mission (nack)"


def test_a_refused_fence_says_the_mission_already_replaced_the_old_one() -> None:
    net, vehicle, session = rig(ServerBehaviour(capacity={M: 100, F: 1, RA: 100}))
    assert session.upload(M, plan(5)).ok                # the vehicle's previous mission
    net.run_for(1.5)                                    # its MISSION_CURRENT reports it
    previous = previous_plans(session.gcs.received)
    assert previous == {M: True, F: False, RA: False}
    done = upload_plan(PARTS, session.upload, previous=previous)
    assert [(r.mission_type, r.nack) for r in done.results] == [(M, None), (F, R.NO_SPACE)]
    assert done.uploaded == (M,) and done.not_sent == (RA,)
    assert vehicle.store.count(M) == 3 and vehicle.store.count(RA) == 0
    assert "the mission replaced the vehicle's previous mission (not rolled back)" in done.report()


def test_without_a_mission_current_the_previous_plans_are_unknown() -> None:
    assert previous_plans([]) == {t: None for t in PLAN_TYPES}
    net, vehicle, session = rig()
    net.run_for(1.5)
    assert previous_plans(session.gcs.received) == {M: False, F: None, RA: None}   # no ids yet
    assert session.upload(F, plan(1, F)).ok             # now a plan id is reported: the fence's
    net.run_for(1.5)
    assert previous_plans(session.gcs.received) == {M: False, F: True, RA: False}


def test_a_refused_last_part_stops_the_upload_and_an_unknown_past_is_said_so() -> None:
    net, vehicle, session = rig(ServerBehaviour(capacity={M: 100, F: 0, RA: 100}))
    done = upload_plan([(M, plan(1)), (F, plan(1, F))], session.upload)     # no MISSION_CURRENT seen
    assert done.stopped and done.not_sent == () and not done.ok
    assert done.report() == [
        "plan upload stopped at the fence: uploaded mission; not uploaded fence (nack)",
        "the mission replaced whatever mission the vehicle held before (not rolled back)"]


def test_a_complete_upload_reports_nothing_extra() -> None:
    net, vehicle, session = rig()
    done = upload_plan(PARTS, session.upload)
    assert done.ok and done.uploaded == (M, F, RA) and done.report() == []


@pytest.mark.parametrize(("keep_going", "sent"), [(False, [M]), (True, [M, F, RA])])
def test_gcs_upload_command_stops_at_the_refused_mission_unless_told_to_keep_going(
        tmp_path, capsys, keep_going, sent) -> None:
    path = tmp_path / "all.plan"
    save_plan(plan_from_items(*(items for _, items in PARTS)), path)
    net, vehicle, session = rig(NO_MISSIONS)
    args = argparse.Namespace(operation="upload", file=str(path), keep_going=keep_going)
    results = gcs_cmd._operate(args, session, load_plan(path))
    assert [r.mission_type for r in results] == sent and not results[0].ok
    assert (vehicle.store.count(F), vehicle.store.count(RA)) == ((2, 1) if keep_going else (0, 0))
    out = capsys.readouterr().out
    assert ("not uploaded mission (nack), fence (not sent), rally (not sent)" in out) != keep_going
    assert ("--keep-going" in out) != keep_going


def test_the_gcs_upload_parser_has_keep_going() -> None:
    parser = argparse.ArgumentParser()
    gcs_cmd.add_parser(parser.add_subparsers())
    args = parser.parse_args(["gcs", "upload", "x.plan", "--target", "udp:127.0.0.1:14550"])
    assert args.keep_going is False
    args = parser.parse_args(["gcs", "upload", "x.plan", "--target", "udp:127.0.0.1:14550", "--keep-going"])
    assert args.keep_going is True
