"""Frame-fuzz campaigns: the spec vehicle passes, the planted decoder bug is found, shrunk,
saved, loaded and replayed to the same violation; the same seed sends the same frames."""

from __future__ import annotations

import pytest

from mavconform.conformance.mutants import MUTANTS
from mavconform.fuzz.case import Case, load_case, save_case
from mavconform.fuzz.frames import FrameCampaign, replay, search
from mavconform.fuzz.frames import engine
from mavconform.fuzz.outcomes import TargetUnresponsive
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import UdpDriver
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode

PLANTED = "mutant:raises-on-truncated-frame"


def test_a_bounded_campaign_passes_on_the_spec_vehicle() -> None:
    sent: list[int] = []
    campaign = FrameCampaign("builtin:spec", seed=11, max_examples=12, on_example=sent.append)
    assert campaign.run() == []
    assert campaign.examples == len(sent) == 12 and sum(sent) == campaign.frames_sent > 12 * 16
    assert campaign.neutralised > 0     # the admission rule was exercised


def test_a_bounded_campaign_passes_on_builtin_inav() -> None:
    """INAV reads only the float forms: the oracle's downloads use them (from the vehicle's
    own config), and an intact stray item, which INAV may append, is never sent."""
    assert FrameCampaign("builtin:inav", seed=11, max_examples=12).run() == []


def test_the_planted_decoder_bug_is_found_shrunk_saved_and_replayed(tmp_path) -> None:
    assert MUTANTS["raises-on-truncated-frame"].breaks == frozenset({"MIS.FRM.05"})   # the one clause that sends a truncated frame
    (case,) = search(PLANTED, seed=3, max_examples=30)
    assert case.violation.invariant == "no-exception" and "unpack_from" in case.violation.detail
    sends = [s for s in case.steps if "send" in s]
    assert len(sends) == 1 and len(sends[0]["send"]) <= 2, "minimised to one datagram"
    frames = sends[0]["send"]
    assert any(f["made"].startswith(("truncate", "signed_flag_unsigned", "bad_length")) for f in frames)
    for i in range(len(frames)):   # 1-minimal: without any one of its frames it passes
        fewer = ({"setup": {"signing": False}}, {"send": frames[:i] + frames[i + 1:]})
        assert replay(Case("frames", PLANTED, case.seed, fewer)) is None
    assert case.found_by["shrunk"] is True
    loaded = load_case(save_case(case, tmp_path))
    assert loaded == case
    again = replay(loaded)
    assert again == case.violation
    # the same bytes do no harm to the spec vehicle: the bug is the mutant's
    assert replay(Case("frames", "builtin:spec", case.seed, case.steps)) is None


def test_the_planted_bug_is_a_truncated_frame() -> None:
    vehicle = MUTANTS["raises-on-truncated-frame"].build(VehicleConfig())
    whole = VehicleNode(VehicleConfig()).endpoint.encoder.encode(vehicle._heartbeat())
    vehicle.datagram_received(whole, "gcs", 0.0)
    with pytest.raises(Exception, match="unpack_from"):
        vehicle.datagram_received(whole[:-3], "gcs", 0.0)


def _first_frames(seed: int) -> list[bytes]:
    seen: list[bytes] = []
    original = engine.Rig.send

    def spy(self, frames):
        seen.extend(frames)
        original(self, frames)

    engine.Rig.send = spy
    try:
        FrameCampaign("builtin:spec", seed=seed, max_examples=3).run()
    finally:
        engine.Rig.send = original
    return seen


def test_the_same_seed_sends_the_same_frames() -> None:
    a, b, c = _first_frames(5), _first_frames(5), _first_frames(6)
    assert a == b and len(a) > 50
    assert a != c


def test_a_signed_vehicle_ignores_what_it_cannot_verify() -> None:
    """Unsigned, wrong-key and stale copies of MISSION_CLEAR_ALL go out intact to a vehicle
    that requires signatures; the plan must survive them."""
    from mavconform.fuzz.frames.mutators import MUTATORS
    from mavconform.fuzz.frames.program import FrameSpec
    from mavconform.fuzz.frames.templates import TEMPLATE_NAMES
    from mavconform.fuzz.frames.rig import Rig
    from mavconform.conformance.target_uri import parse_target
    clear = TEMPLATE_NAMES.index("MISSION_CLEAR_ALL all")
    names = list(MUTATORS)
    rig = Rig(parse_target("builtin:spec"), seed=1, signing=True)
    assert rig.start() is None
    sent = []
    for mutator in ("wrong_key_signature", "stale_timestamp", "as_mavlink1"):
        frames, fixed = rig.builder.datagram([FrameSpec(0, clear, names.index(mutator), 9)])
        assert fixed == []
        sent.append(frames)
        rig.send(frames)
        rig.flush()
    assert rig.vehicle.endpoint.rejected_signatures >= 3
    assert rig.check() is None


def test_replay_rejects_a_malformed_frames_case() -> None:
    with pytest.raises(UsageError, match=r"steps\[1\]"):
        replay(Case("frames", "builtin:spec", 1, ({"setup": {"signing": False}}, {"send": "x"})))
    with pytest.raises(UsageError, match="signing"):
        replay(Case("frames", PLANTED, 1, ({"setup": {"signing": True}},)))


@pytest.mark.udp
def test_a_short_campaign_over_udp_loopback() -> None:
    """The builtin vehicle on loopback sockets, then the planted bug over real UDP."""
    campaign = FrameCampaign("builtin:spec", seed=2, max_examples=4, transport="udp")
    assert campaign.run() == []
    assert campaign.rig.counted.received >= campaign.rig.datagrams_sent   # nothing lost on loopback
    (case,) = search(PLANTED, seed=3, max_examples=20, transport="udp")
    assert case.violation.invariant == "no-exception" and case.found_by["transport"] == "udp"


@pytest.mark.udp
def test_a_silent_udp_target_is_unresponsive_not_a_hang_nor_a_finding() -> None:
    with UdpDriver() as driver:
        silent = driver.add_node(_Silent())
        host, port = silent
        with pytest.raises(TargetUnresponsive, match="no HEARTBEAT"):
            FrameCampaign(f"udp:{host}:{port}", seed=1, max_examples=1, scale=0.05).run()


class _Silent:
    def datagram_received(self, data, source, now): pass
    def poll(self, now): pass
    def next_deadline(self): return None
    def take_outgoing(self): return []
