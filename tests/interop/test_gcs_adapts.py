"""The GCS picks its adaptations from the vehicle's HEARTBEAT, and they are what makes the
profiled vehicles interoperate (without them, the ArduPilot-like vehicle eats the first item
and float items lose precision)."""

from __future__ import annotations

import dataclasses

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.interop.harness import build_pair, expected_plan, sample_plan
from mavconform.reference_impl.mission.adaptations import ARDUPILOT, NONE, PX4, for_autopilot
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.net import SimNetwork
from mavconform.reference_impl.profiles import load_profile

from ..vehicle_process import vehicle_process


@pytest.mark.parametrize("name, chosen", [("spec", NONE), ("px4", PX4), ("ardupilot", ARDUPILOT)])
def test_the_set_follows_the_heartbeat_autopilot(name, chosen):
    pair = build_pair(load_profile(name))
    assert pair.gcs.adaptations is chosen
    assert pair.gcs.client.adaptations is chosen
    assert for_autopilot(pair.gcs.target_heartbeat.autopilot) is chosen


def test_a_gcs_given_its_target_adapts_when_the_heartbeat_comes():
    net = SimNetwork()
    net.add_node("vehicle", load_profile("ardupilot").vehicle())
    gcs = GcsNode(GcsConfig(target=(1, 1)), remote="vehicle", wall_clock=net.clock.wall)
    net.add_node("gcs", gcs)
    net.connect("gcs", "vehicle")
    assert gcs.adaptations is NONE and gcs.connected
    assert net.run_until(lambda: gcs.target_heartbeat is not None, timeout=5)
    assert gcs.adaptations is ARDUPILOT and gcs.client.adaptations is ARDUPILOT


def test_a_fixed_set_is_kept_and_without_adaptations_the_plan_is_mangled():
    profile = load_profile("ardupilot")
    plan = sample_plan(4)
    adapted = build_pair(profile)
    assert adapted.upload(T.MISSION, plan).ok
    assert adapted.download(T.MISSION).items == expected_plan(profile, plan, T.MISSION)

    net = SimNetwork()
    net.add_node("vehicle", profile.vehicle())
    gcs = GcsNode(GcsConfig(adaptations=NONE), remote="vehicle", wall_clock=net.clock.wall)
    net.add_node("gcs", gcs)
    net.connect("gcs", "vehicle")
    assert net.run_until(lambda: gcs.connected, timeout=5) and gcs.adaptations is NONE
    done = len(gcs.results)
    gcs.upload(T.MISSION, plan, net.clock.now())
    assert net.run_until(lambda: len(gcs.results) > done, timeout=60) and gcs.results[-1].ok
    done = len(gcs.results)
    gcs.download(T.MISSION, net.clock.now())
    assert net.run_until(lambda: len(gcs.results) > done, timeout=60)
    got = gcs.results[-1].items
    wanted = expected_plan(profile, plan, T.MISSION)
    assert got[0] != wanted[0] and (got[0].frame, got[0].z) == (0, 0.0)   # item 0 is the vehicle's home
    # and MISSION_ITEM (float) answers to MISSION_REQUEST cost x/y precision (A6)
    assert all(g.x != w.x and abs(g.x - w.x) < 100 for g, w in zip(got[1:], wanted[1:]))
    assert gcs.adaptations_used == ()


@pytest.fixture
def ardupilot_port():
    """`mavconform vehicle --profile ardupilot` on 127.0.0.1, OS-chosen port; killed afterwards."""
    with vehicle_process("--profile", "ardupilot") as port:
        yield port


@pytest.mark.udp
def test_gcs_command_prints_the_adaptations_it_chose_and_used(ardupilot_port, tmp_path, capsys):
    target = f"udp:127.0.0.1:{ardupilot_port}"
    assert main(["gcs", "upload", "--target", target, str(SAMPLES_DIR / "demo.plan")]) == 0
    out = capsys.readouterr().out
    assert "adaptations: ardupilot (home-at-seq0," in out
    assert "adaptations used: home-at-seq0" in out
    assert main(["gcs", "clear", "--target", target]) == 0
    assert "adaptations used: clear-types-separately" in capsys.readouterr().out
    assert main(["gcs", "clear", "--target", target, "--adapt", "none"]) == 1   # A10: ALL is UNSUPPORTED
    out = capsys.readouterr().out
    assert "adaptations: none (none)" in out and "UNSUPPORTED" in out and "adaptations used: none" in out


@pytest.mark.parametrize("name", ["spec", "px4", "ardupilot"])
def test_a_lost_final_ack_is_recovered_on_every_profile(name):
    """The vehicle repeats ACCEPTED for a late copy of the last item; on ArduPilot that copy
    must be compared in the form the vehicle stored it (compact items), or it never matches."""
    from mavconform.reference_impl.net import DropMessage, FaultModel

    profile = load_profile(name)
    plan = [dataclasses.replace(item, frame=6, z=50.5 + item.seq) for item in sample_plan(3)]
    pair = build_pair(profile, down=FaultModel(rules=(DropMessage("MISSION_ACK", 1),)))
    result = pair.upload(T.MISSION, plan)
    assert result.ok, result
    assert pair.download(T.MISSION).items == expected_plan(profile, plan, T.MISSION)
