"""The profiled vehicle's HEARTBEAT says who it is and which mode it is in, in the
autopilot's own numbering, so a GCS shows a real mode instead of "unknown" (virtual time)."""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.reference_impl.gcs import GcsNode
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcs


def px4_mode(main: int, sub: int) -> int:
    """PX4's union px4_custom_mode: reserved uint16, then main_mode, then sub_mode (little-endian)."""
    return main << 16 | sub << 24


PX4_AUTO, PX4_LOITER, PX4_MISSION = 4, 3, 4       # px4_custom_mode.h
COPTER_STABILIZE, COPTER_AUTO = 0, 3              # ArduCopter mode.h Mode::Number

# profile -> (autopilot, custom_mode idle, custom_mode flying the mission)
EXPECTED = {
    "spec": (d.MAV_AUTOPILOT_GENERIC_MISSION_FULL, 0, 0),
    "px4": (d.MAV_AUTOPILOT_PX4, px4_mode(PX4_AUTO, PX4_LOITER), px4_mode(PX4_AUTO, PX4_MISSION)),
    "ardupilot": (d.MAV_AUTOPILOT_ARDUPILOTMEGA, COPTER_STABILIZE, COPTER_AUTO),
}


def _beats(gcs: GcsNode) -> list:
    return [msg for msg in gcs.received if msg.get_type() == "HEARTBEAT"]


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_heartbeat_carries_the_profiles_autopilot_and_mode(name: str) -> None:
    autopilot, idle, flying = EXPECTED[name]
    rig = vehicle_and_gcs(dataclasses.replace(load_profile(name).config, autostart=True), seed=1)
    net, gcs, session = rig.net, rig.gcs, rig.session
    net.run_for(2.0)
    beat = _beats(gcs)[-1]
    assert (beat.autopilot, beat.custom_mode) == (autopilot, idle)
    assert beat.base_mode == d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED and beat.system_status == d.MAV_STATE_STANDBY
    far = MissionItem(0, 3, int(Cmd.NAV_WAYPOINT), x=round(47.5 * 1e7), y=round(8.6 * 1e7), z=20.0)
    assert session.upload(MissionType.MISSION, [far]).ok        # autostart: flies at once
    gcs.received.clear()
    net.run_for(2.0)
    beat = _beats(gcs)[-1]
    assert (beat.autopilot, beat.custom_mode) == (autopilot, flying)
    # flying, every vehicle says it is armed (the spec vehicle needs no arming, but says so too)
    assert beat.base_mode == (d.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | d.MAV_MODE_FLAG_AUTO_ENABLED
                              | d.MAV_MODE_FLAG_SAFETY_ARMED)
    assert beat.system_status == d.MAV_STATE_ACTIVE


def test_px4_modes_are_auto_loiter_and_auto_mission() -> None:
    rules = load_profile("px4").config.flight_rules
    assert rules.mode_named(rules.boot_mode).number == 0x03040000
    assert rules.mode_named("AUTO.MISSION").number == 0x04040000
    for profile in ("px4", "ardupilot"):
        modes, boot = load_profile(profile).setting("modes"), load_profile(profile).setting("boot_mode")
        assert ("px4_custom_mode.h" if profile == "px4" else "mode.h") in modes.source and "mode.h" in boot.source
        assert boot.variant == "HB"
