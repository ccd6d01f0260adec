"""The suite's flight on every vehicle type, and never a vehicle left armed (issue 23): against
builtin vehicles in virtual time, each breaking one thing a real one did or could."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest

from mavconform.conformance import document, suite
from mavconform.conformance import session as session_module
from mavconform.conformance.catalogue import CLAUSES
from mavconform.conformance.mutants.arming import IgnoresDisarm, RefusesMissionStartArmed, arming_mutant
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.autopilot import Autopilot
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reports.text import safety_alarm

PRG = [c for c in CLAUSES if c.id.startswith("MIS.PRG")]


def _fly(target: str = "builtin:ardupilot", vehicle: VehicleNode | None = None, monkeypatch=None,
         config: VehicleConfig | None = None) -> tuple[dict[str, Any], Session]:
    """The progress clauses against `target` (or `vehicle` in its place), in virtual time."""
    if vehicle is not None:
        monkeypatch.setattr(session_module, "build_vehicle", lambda uri, **overrides: vehicle)
    with Session(parse_target(target), virtual=True, config=config) as s:
        results = {r.clause_id: r for r in run_clauses(s, PRG).results}
    return results, s


def _commands(result: Any) -> list[dict]:
    """The COMMAND_LONGs the suite sent in a clause (its exchange's tx events), as fields."""
    return [e["fields"] for e in result.exchange if e["dir"] == "tx" and e["msg"] == "COMMAND_LONG"]


def test_a_vehicle_that_refuses_the_start_after_arming_is_disarmed_and_the_report_says_so(monkeypatch):
    vehicle = arming_mutant(RefusesMissionStartArmed)(VehicleConfig())
    results, s = _fly(vehicle=vehicle, monkeypatch=monkeypatch)
    detail = results["MIS.PRG.01"].detail
    assert results["MIS.PRG.01"].outcome is Outcome.ERROR and results["MIS.PRG.02"].outcome is Outcome.ERROR
    assert "start the mission was refused with MAV_RESULT_FAILED" in detail
    assert "afterwards: disarmed by MAV_CMD_COMPONENT_ARM_DISARM 0 (MAV_RESULT_ACCEPTED)" in detail
    assert not vehicle.autopilot.armed
    assert s.flights == [{"clause": "MIS.PRG.01", "style": "ArduCopter", "plan": s.flights[0]["plan"],
                          "disarmed": True, "detail": s.flights[0]["detail"]}]


def test_a_vehicle_that_will_not_disarm_is_said_loudly_and_fails_the_run(monkeypatch, tmp_path):
    vehicle = arming_mutant(IgnoresDisarm)(VehicleConfig())
    monkeypatch.setattr(session_module, "build_vehicle", lambda uri, **overrides: vehicle)
    options = document.RunOptions(target="builtin:ardupilot", clauses="MIS.PRG.*", expectations="ardupilot")
    prepared = suite.prepare(options, report_dir=tmp_path)
    doc, _ = suite.execute(prepared, virtual=True)
    assert vehicle.autopilot.armed                          # it really is still armed
    assert doc["summary"]["left_armed"] == 1 and doc["summary"]["verdict"] == "fail"
    assert doc["summary"]["gating_failures"] == 0           # the clauses themselves are fine
    [flight] = doc["flights"]
    assert flight["disarmed"] is False and "IT MAY STILL BE ARMED" in flight["detail"]
    assert safety_alarm(doc).startswith("THE VEHICLE MAY STILL BE ARMED")
    for name in ("run.md", "run.html", "run.junit.xml"):
        assert "THE VEHICLE MAY STILL BE ARMED" in (tmp_path / name).read_text()


class _ModeNotShown(Autopilot):
    """Accepts every mode change and never shows it in its HEARTBEAT."""

    def command(self, msg: Any, source: Any, now: float) -> list[Send] | None:
        if msg.command == Cmd.DO_SET_MODE:
            return [Send(m.command_ack_message(msg.command, R.ACCEPTED, source), source)]
        return super().command(msg, source, now)


def test_nothing_is_armed_in_a_mode_the_heartbeat_does_not_show(monkeypatch):
    vehicle = VehicleNode(load_profile("ardupilot-plane").config, autopilot_class=_ModeNotShown)
    results, s = _fly(vehicle=vehicle, monkeypatch=monkeypatch)
    assert results["MIS.PRG.01"].outcome is Outcome.ERROR
    assert "not arming in a mode not seen" in results["MIS.PRG.01"].detail
    assert not vehicle.autopilot.armed and s.flights[0]["disarmed"] is not False
    sent = _commands(results["MIS.PRG.01"])
    assert any(c["command"] == Cmd.DO_SET_MODE and c["param2"] == 10 for c in sent)   # AUTO was asked for
    assert not any(c["command"] == Cmd.COMPONENT_ARM_DISARM and c["param1"] == 1 for c in sent)


@pytest.mark.parametrize("profile, mode", [("ardupilot", 4), ("ardupilot-plane", 10), ("ardupilot-rover", 10),
                                           ("px4", 0x04040000), ("px4-fixedwing", 0x04040000),
                                           ("px4-vtol", 0x04040000)])
def test_every_vehicle_type_flies_in_its_own_mode_and_ends_disarmed(profile, mode):
    """The mode each builtin vehicle type is armed in is its own (ArduPlane's 4 is ACRO, not
    GUIDED); every flight ends with it disarmed, confirmed; both clauses are decided."""
    with Session(parse_target(f"builtin:{profile}"), virtual=True) as s:
        results = {r.clause_id: r for r in run_clauses(s, PRG).results}
        assert not s.vehicle.autopilot.armed
    assert {r.outcome for r in results.values()} <= {Outcome.PASS, Outcome.FAIL}, results
    assert results["MIS.PRG.02"].outcome is Outcome.PASS
    assert [f["disarmed"] for f in s.flights] == [True]
    sent = _commands(results["MIS.PRG.01"])
    modes = [c for c in sent if c["command"] == Cmd.DO_SET_MODE]
    arms = [i for i, c in enumerate(sent) if c["command"] == Cmd.COMPONENT_ARM_DISARM and c["param1"] == 1]
    assert modes and arms and sent.index(modes[0]) < arms[0]   # the mode first, then arming
    notes = [e["msg"] for e in results["MIS.PRG.01"].exchange if e["dir"] == "note"]
    assert any(str(n).startswith("flight: the HEARTBEAT shows mode") and f"({mode})" in str(n) for n in notes), notes


def test_a_vehicle_type_the_suite_does_not_fly_is_not_applicable():
    config = dataclasses.replace(VehicleConfig(), vehicle_type=12)   # MAV_TYPE_SUBMARINE
    results, s = _fly("builtin:spec", config=config)
    assert {r.outcome for r in results.values()} == {Outcome.NOT_APPLICABLE}
    assert "SUBMARINE (MAV_TYPE 12)" in results["MIS.PRG.01"].detail and not s.flights


class _NoHome(Autopilot):
    """Has no home to report (no GPS fix yet): HOME_POSITION requests are refused."""

    def command(self, msg: Any, source: Any, now: float) -> list[Send] | None:
        if msg.command in (Cmd.REQUEST_MESSAGE, 410):
            return [Send(m.command_ack_message(msg.command, R.FAILED, source), source)]
        return super().command(msg, source, now)


def test_without_a_home_position_nothing_is_flown_and_the_clauses_are_not_applicable(monkeypatch):
    vehicle = VehicleNode(load_profile("ardupilot-plane").config, autopilot_class=_NoHome)
    results, s = _fly(vehicle=vehicle, monkeypatch=monkeypatch)
    assert {r.outcome for r in results.values()} == {Outcome.NOT_APPLICABLE}
    assert "no HOME_POSITION" in results["MIS.PRG.01"].detail
    assert not s.flights and not vehicle.autopilot.armed
