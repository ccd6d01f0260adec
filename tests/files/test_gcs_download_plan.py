"""Issue 13, end to end: `mavconform gcs download` against an ArduPilot-like vehicle process
writes a .plan QGroundControl loads, with the vehicle's identity and home, that reads back to
what was uploaded (modulo the profile's storage)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import load_plan
from mavconform.reference_impl.interop.harness import expected_plan
from mavconform.reference_impl.mission.items import PLAN_TYPES
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.wire.dialect import mavlink as _d

from ..vehicle_process import vehicle_process
from . import qgc_loader

# The ArduPilot form: no null (NaN) params where ArduPilot refuses them (A23).
SOURCE = Path(__file__).parent / "fixtures" / "roi_camera_gimbal_ardupilot.plan"


@pytest.mark.udp
def test_downloaded_plan_loads_in_qgc_and_reads_back(tmp_path: Path) -> None:
    out = tmp_path / "back.plan"
    with vehicle_process("--profile", "ardupilot") as port:
        target = f"udp:127.0.0.1:{port}"
        assert main(["gcs", "upload", "--target", target, str(SOURCE)]) == 0
        assert main(["gcs", "download", "--target", target, str(out)]) == 0
    document = json.loads(out.read_text())
    assert qgc_loader.problems(document) == []
    mission = document["mission"]
    assert (mission["firmwareType"], mission["vehicleType"]) == (_d.MAV_AUTOPILOT_ARDUPILOTMEGA, _d.MAV_TYPE_QUADROTOR)
    profile = load_profile("ardupilot")
    home = profile.config.home
    assert mission["plannedHomePosition"] == [home.lat, home.lon, home.alt]   # its item 0
    sent, back = load_plan(SOURCE), load_plan(out)
    for t in PLAN_TYPES:
        assert tuple(back.items(t)) == expected_plan(profile, sent.items(t), t), t.label
