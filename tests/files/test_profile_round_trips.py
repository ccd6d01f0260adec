"""Issue 13: every fixture plan through every builtin vehicle and back, in virtual time.

The reference GCS uploads each plan type of a fixture to a fresh profiled vehicle on the
in-memory network and downloads it again: what comes back equals what went up modulo the
profile's documented storage transforms (`Profile.stored_items`: ArduPilot's home at seq 0,
centimetre altitudes, dropped waypoint params, plain frames). The download, written as a
.plan the way `mavconform gcs download` writes it, loads in QGC (qgc_loader.py) and reads
back to the same plans, with the vehicle's identity and home. On the vehicle, each DO_JUMP
targets the item the plan's jump names (one seq higher behind ArduPilot's home item).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mavconform.reference_impl.files import load_plan, plan_from_items, save_plan
from mavconform.reference_impl.files.from_vehicle import facts_from_gcs
from mavconform.reference_impl.files.qgc_plan import fallback_home
from mavconform.reference_impl.interop.harness import build_pair, expected_plan
from mavconform.reference_impl.mission.commands import by_name
from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile

from . import qgc_loader

FIXTURES = sorted((Path(__file__).parent / "fixtures").glob("*.plan"))
# Fixtures a profiled vehicle refuses as its autopilot does: PX4 v1.16.0 takes no terrain frame
# (mavlink_mission.cpp parse_mavlink_mission_item: MAV_MISSION_UNSUPPORTED_FRAME), and QGC
# offers that frame (AltitudeMode 4, TerrainFrame) only for ArduPilot. Its terrain-relative
# mode for PX4 is AltitudeMode 3 (CalcAboveTerrain: an AMSL altitude in MAV_FRAME_GLOBAL),
# which terrain_calc_above_terrain.plan carries and every profile takes. ArduPilot refuses a
# NaN (a .plan's null) in a param its command takes no NaN in (A23, AP_Mission.cpp
# sanity_check_params; ArduCopter SITL 531699d6 answered INVALID_PARAM3 to roi_camera_gimbal's
# DO_GIMBAL_MANAGER_PITCHYAW with null pitch and yaw rates); roi_camera_gimbal_ardupilot.plan
# has 0 there, so ROI, camera and gimbal items still go up to every profile.
REFUSED = {("terrain_null_altitude", "px4"): MissionResult.UNSUPPORTED_FRAME,
           ("roi_camera_gimbal", "ardupilot"): MissionResult.INVALID_PARAM3}


def _refused(stem: str, profile_name: str) -> MissionResult | None:
    """What the profile refuses the fixture with: a vehicle-type profile (px4-fixedwing,
    ardupilot-plane, ...) takes items as its autopilot's (px4, ardupilot) does."""
    return REFUSED.get((stem, profile_name.split("-")[0]))


# (inav: it ignores the _INT mission messages, which the reference GCS does not fall back from
# yet, and it stores only NAV_WAYPOINT and RTL, which no fixture is made of)
@pytest.mark.parametrize("profile_name", [n for n in BUILTIN_PROFILES if not load_profile(n).int_messages_ignored])
@pytest.mark.parametrize("source", FIXTURES, ids=lambda p: p.stem)
def test_fixture_goes_up_and_comes_back(profile_name: str, source: Path, tmp_path: Path) -> None:
    profile = load_profile(profile_name)
    plan = load_plan(source)
    pair = build_pair(profile, seed=13)
    refused = _refused(source.stem, profile_name)
    if refused is not None:
        result = pair.upload(MissionType.MISSION, plan.mission)
        assert result is not None and result.nack == refused, result and result.summary()
        return
    for t in PLAN_TYPES:
        result = pair.upload(t, plan.items(t))
        assert result is not None and result.ok, f"upload {t.label}: {result and result.summary()}"
        assert pair.settle() is not None
    stored = pair.vehicle.store.items(MissionType.MISSION)
    home = 1 if profile.behaviour.home_at_seq0 else 0
    for position, item in enumerate(plan.mission):
        if item.command == Cmd.DO_JUMP:   # the stored jump names the seq the plan's target went to
            assert stored[position + home].param1 == item.param1 + home, f"DO_JUMP at {position}"
    got = {}
    for t in PLAN_TYPES:
        result = pair.download(t)
        assert result is not None and result.ok, f"download {t.label}: {result and result.summary()}"
        assert pair.settle() is not None
        wanted = expected_plan(profile, plan.items(t), t)
        assert tuple(result.items) == wanted, f"{t.label} differs from the upload (modulo stored_items)"
        got[t] = list(result.items)

    home, settings = facts_from_gcs(pair.gcs)   # as `mavconform gcs download` does
    path = tmp_path / "download.plan"
    save_plan(plan_from_items(*(got[t] for t in PLAN_TYPES), home, settings), path)
    assert qgc_loader.problems(json.loads(path.read_text())) == []
    back = load_plan(path)
    assert [back.items(t) for t in PLAN_TYPES] == [got[t] for t in PLAN_TYPES]
    assert (back.settings.firmware_type, back.settings.vehicle_type) == (
        pair.gcs.target_heartbeat.autopilot, pair.gcs.target_heartbeat.type)
    if profile.behaviour.home_at_seq0:      # ArduPilot: the vehicle's home is its item 0
        vehicle_home = profile.config.home
        assert back.home == (vehicle_home.lat, vehicle_home.lon, vehicle_home.alt)
    else:                                   # no HOME_POSITION from our vehicle: QGC's guess
        assert back.home == fallback_home(back.mission)


def test_roi_camera_and_gimbal_items_go_up_to_every_profile() -> None:
    """The fixtures every builtin profile takes hold an ROI, a gimbal and a camera item."""
    wanted = {by_name(n).value for n in ("DO_SET_ROI_LOCATION", "DO_GIMBAL_MANAGER_PITCHYAW", "IMAGE_START_CAPTURE")}
    for name in BUILTIN_PROFILES:
        if load_profile(name).int_messages_ignored:
            continue   # inav stores only NAV_WAYPOINT and RTL
        taken = [s.stem for s in FIXTURES
                 if _refused(s.stem, name) is None and wanted <= {it.command for it in load_plan(s).mission}]
        assert taken, f"{name} takes no fixture with ROI, gimbal and camera items"
