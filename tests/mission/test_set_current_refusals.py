"""A set-current the vehicle refuses for good ends after one attempt, the refusal named; only
a missing answer (or a vehicle that says it is busy, P12) is worth asking again. Virtual time."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.adaptations import ARDUPILOT, NONE, PX4
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import CommandResult
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.results import Outcome
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..rigs import vehicle_and_gcs
from .conftest import plan
from .script import GCS, VEHICLE, Script, names

ADAPTATIONS = [NONE, PX4, ARDUPILOT]
SET_CURRENT_CMD = 224


def client(adaptations) -> Script:
    return Script(MissionClient(*GCS, VEHICLE, adaptations=adaptations))


def text(s: str):
    return d.MAVLink_statustext_message(d.MAV_SEVERITY_WARNING, s.encode(), 0, 0)


def sends(s: Script, name: str) -> list[float]:
    return [t for t, msg in s.sent_at if msg.get_type() == name]


def only_result(s: Script):
    assert len(s.results) == 1, s.results
    return s.results[0]


@pytest.mark.parametrize("adaptations", ADAPTATIONS, ids=lambda a: a.name)
@pytest.mark.parametrize(("refusal", "named"), [
    (text("WPM: WP CURR CMD: Not in list"), "vehicle said: WPM: WP CURR CMD: Not in list"),    # PX4
    (text("Set current failed: seq 9 not in mission of 3"), "not in mission of 3"),          # ours
    (m.ack_message(R.UNSUPPORTED, MissionType.MISSION, GCS), "MISSION_ACK UNSUPPORTED"),
], ids=["px4-not-in-list", "reference-not-in-mission", "mission-ack-unsupported"])
def test_a_definitive_refusal_of_the_message_ends_it_after_one_attempt(adaptations, refusal, named) -> None:
    s = client(adaptations)
    s.call(s.engine.set_current(9, s.now))
    out = s.feed(refusal, VEHICLE)
    assert "MISSION_ACK" not in names(out)       # no cancels sent: nothing to wait out
    r = only_result(s)
    assert r.outcome is Outcome.REJECTED and named in r.detail and r.retries == 0
    s.advance(30)
    assert sends(s, "MISSION_SET_CURRENT") == [0.0] and len(s.results) == 1


@pytest.mark.parametrize("adaptations", ADAPTATIONS, ids=lambda a: a.name)
@pytest.mark.parametrize("code", [CommandResult.DENIED, CommandResult.UNSUPPORTED, CommandResult.FAILED],
                         ids=lambda c: c.name)
def test_a_definitive_refusal_of_the_command_ends_it_after_one_attempt(adaptations, code) -> None:
    s = client(adaptations)
    s.call(s.engine.set_current(9, s.now, via_command=True))
    s.feed(m.command_ack_message(SET_CURRENT_CMD, code, GCS), VEHICLE)
    r = only_result(s)
    assert r.outcome is Outcome.REJECTED and r.detail == f"COMMAND_ACK {code.name}" and r.retries == 0
    s.advance(30)
    assert sends(s, "COMMAND_LONG") == [0.0]


@pytest.mark.parametrize("adaptations", ADAPTATIONS, ids=lambda a: a.name)
def test_a_missing_answer_is_still_retried(adaptations) -> None:
    s = client(adaptations)
    s.call(s.engine.set_current(1, s.now))
    s.advance(30)
    assert sends(s, "MISSION_SET_CURRENT") == pytest.approx([0.0, 1.5, 3.0, 4.5, 6.0, 7.5])
    r = only_result(s)
    assert r.outcome is Outcome.TIMEOUT and r.retries == 5 and "no MISSION_CURRENT" in r.detail


def test_a_busy_vehicle_is_asked_again_and_the_answer_counts() -> None:
    s = client(PX4)
    s.call(s.engine.set_current(1, s.now, via_command=True))
    s.feed(m.command_ack_message(SET_CURRENT_CMD, CommandResult.TEMPORARILY_REJECTED, GCS), VEHICLE)
    assert s.results == []
    s.advance(1.5)
    assert sends(s, "COMMAND_LONG") == pytest.approx([0.0, 1.5])
    s.feed(m.command_ack_message(SET_CURRENT_CMD, CommandResult.ACCEPTED, GCS), VEHICLE)
    s.feed(m.current_message(1, 3, 2, 2, (0, 0, 0)), VEHICLE)
    assert only_result(s).ok


def test_in_progress_is_not_a_refusal() -> None:
    s = client(NONE)
    s.call(s.engine.set_current(1, s.now, via_command=True))
    s.feed(m.command_ack_message(SET_CURRENT_CMD, CommandResult.IN_PROGRESS, GCS), VEHICLE)
    assert s.results == []
    s.feed(m.current_message(1, 3, 2, 2, (0, 0, 0)), VEHICLE)
    assert only_result(s).ok


# --- against the reference vehicle's PX4 and ArduPilot profiles -------------------------------
def _rig(profile: str) -> GcsSession:
    session = vehicle_and_gcs(load_profile(profile).config, seed=3).session
    assert session.upload(MissionType.MISSION, plan(3)).ok
    return session


@pytest.mark.parametrize(("profile", "via_command", "named"), [
    ("px4", False, "not in mission of 3"),            # P12 vehicle, idle: a STATUSTEXT
    ("px4", True, "COMMAND_ACK UNSUPPORTED"),         # P18: PX4 has no such command
    ("ardupilot", True, "COMMAND_ACK FAILED"),
])
def test_the_reference_gcs_gives_up_at_once_on_a_definitive_refusal(profile, via_command, named) -> None:
    r = _rig(profile).set_current(9, via_command=via_command)
    assert r.outcome is Outcome.REJECTED and named in r.detail
    assert r.retries == 0 and r.finished - r.started < 0.5


def test_the_reference_gcs_still_retries_a_vehicle_that_says_nothing() -> None:
    # A21: ArduPilot drops a MISSION_SET_CURRENT beyond the plan without a word
    r = _rig("ardupilot").set_current(9)
    assert r.outcome is Outcome.TIMEOUT and r.retries == 5
