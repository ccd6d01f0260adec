"""The protocol fuzzer with operator control on (`--operator-control`, issue 14).

- the control steps (request, release, allow/disallow takeover, GCS loss, B alone) run clean on
  the spec vehicle, and do what they say (control moves, a non-owner's write is refused and
  leaves the plan whole, a silent owner is dropped);
- a bounded campaign against the spec vehicle finds nothing;
- operator-control mutants (conformance/mutants/operator_control.py) are found, each by the
  invariant its bug breaks, and the saved case (found_by.handover) replays to it;
- planted bugs no mutant has (an ACCEPTED that grants nothing, control taken unasked, a
  non-owner's MISSION_START obeyed) break two-owners, owner-without-request and
  non-owner-executed;
- cases saved without the knob load and replay as before; a control step in such a case, or
  a bad found_by.handover, is a one-line usage error; the CLI says --operator-control is protocol-only;
- over UDP: a target that sends no CONTROL_STATUS is a usage error, a system manager is
  judged from the wire and a non-owner's accepted write is found.
"""

from __future__ import annotations

import json
from typing import Any

import pytest

from mavconform.cli import main
from mavconform.conformance.mutants import MUTANTS, Mutant
from mavconform.conformance.mutants.operator_control import control_mutant
from mavconform.conformance.target_uri import SUITE_CONTROL
from mavconform.fuzz.campaign import shrink_time_limit
from mavconform.fuzz.case import Case, load_case, save_case
from mavconform.fuzz.protocol import invariants, replay, search
from mavconform.fuzz.protocol.control import CONTROL_INVARIANTS
from mavconform.fuzz.protocol.steps import INVARIANTS, Runner
from mavconform.fuzz.protocol.versions import Versions, Write
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_manager import ControlManager
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire.dialect import mavlink as _d

WAYPOINT = {"frame": 3, "command": 16, "current": 0, "autocontinue": 1, "param1": 0.0,
            "param2": 0.0, "param3": 0.0, "param4": 0.0, "x": 473977420, "y": 85455940, "z": 50.0}
A, B = 245, 246
HANDOVER = {"handover": True, "latency": 0.01}


def upload(n: int, gcs: str | None = None, t: int = 0) -> dict:
    step = {"op": "upload", "type": t, "items": [dict(WAYPOINT, x=WAYPOINT["x"] + i) for i in range(n)]}
    return {**step, "gcs": gcs} if gcs else step


def control(gcs: str, action: str, *, allow: bool = False, wait: bool = False, answer: str | None = None,
            timeout: float = 10.0) -> dict:
    return {"op": "control", "gcs": gcs, "action": action, "allow": allow, "timeout": timeout,
            "wait_for_owner": wait, "answer": answer}


def silence(gcs: str, seconds: float, wait: float) -> dict:
    return {"op": "gcs_loss", "gcs": gcs, "seconds": seconds, "wait": wait}


def stray_command(command: int, frm: str, **params: float) -> dict:
    fields = {"command": command, "confirmation": 0, **{f"param{i}": 0.0 for i in range(1, 8)}}
    fields.update(params)
    return {"op": "stray", "during": None, "after": 0.0,
            "messages": [{"msg": "COMMAND_LONG", "fields": fields, "to": "target", "from": frm}]}


def run_clean(target: str, steps: list[dict], seed: int = 3) -> Runner:
    runner = Runner(target, seed, handover=True, latency=0.01)
    for i, step in enumerate(steps):
        assert runner.apply(step) is None, (i, step)
        assert runner.check() is None, (i, step)
    return runner


# --- the steps, on the spec vehicle ------------------------------------------------------------

def test_the_control_steps_do_what_they_say_on_the_spec_vehicle():
    runner = run_clean("builtin:spec", [
        control("a", "request"),                       # 0: nobody in control: granted
        upload(3, "b"),                                # 1: B is not in control: DENIED, plan untouched
        upload(2),                                     # 2: the owner's upload goes in
        control("b", "request", wait=True, answer="allow"),   # 3: refused, forwarded, A allows: B gets it
        upload(1),                                     # 4: A is no longer in control: DENIED
        control("b", "allow"), control("b", "disallow"),      # 5, 6: the owner's takeover flag
        silence("b", 7.0, 7.0),                        # 7: B silent past the 5 s owner loss: dropped
        upload(4, "b"),                                # 8: nobody in control: open (SUITE_CONTROL)
        control("a", "request"), control("a", "release"),     # 9, 10
        control("b", "release"),                       # 11: not the owner: NOT_IN_CONTROL
    ])
    w = runner.world
    assert [r.outcome.value for r in w.a.control_results] == ["granted", "granted", "released"]
    assert [r.outcome.value for r in w.b.control_results] == ["granted", "granted", "granted", "not_in_control"]
    assert [r.outcome.value for r in w.b.results] == ["nack", "success"]
    assert w.b.results[0].nack == _d.MAV_MISSION_DENIED
    assert [r.outcome.value for r in w.a.results] == ["success", "nack"]
    assert len(w.stored(MissionType.MISSION)) == 4 and w.vehicle.owner == 0
    assert any("GCS 246 lost" in e for e in w.vehicle.events)
    assert w.watch is not None and w.watch.first is None and w.watch.requests_seen >= 8


def test_a_short_silence_keeps_the_owner_and_a_non_owners_mission_start_is_refused():
    runner = run_clean("builtin:spec", [
        control("a", "request"), upload(3), silence("a", 3.0, 4.0),
        stray_command(int(_d.MAV_CMD_MISSION_START), "b"),
        {"op": "set_current", "seq": 2, "command": True, "gcs": "b"},
        {"op": "wait", "seconds": 2.0},
    ])
    w = runner.world
    assert w.vehicle.owner == A and not w.vehicle.flight.flying
    assert w.vehicle.server.progress.seq == 0
    assert w.b.results[-1].outcome.value == "rejected"


def test_every_control_step_kind_runs_clean_with_faults_and_strays():
    run_clean("builtin:spec", [
        {"op": "faults", "up": {"loss": 0.2, "duplicate": 0.2, "reorder": 0.1}, "down": {"loss": 0.2}},
        control("a", "request", allow=True, timeout=3.0),
        control("b", "request", wait=True, answer="release", timeout=3.0),
        stray_command(cm.REQUEST_CONTROL, "mute", param1=1.0, param4=248.0),
        stray_command(cm.REQUEST_CONTROL, "b", param1=7.0, param2=float("nan")),
        {"op": "second_gcs", "first": upload(5), "second": upload(2), "after": 0.01},
        {"op": "faults", "up": None, "down": None},
        {"op": "wait", "seconds": 12.0},
        control("a", "request", wait=True, answer="refuse", timeout=3.0),
        stray_command(int(_d.MAV_CMD_MISSION_START), "a"),
        {"op": "wait", "seconds": 3.0},
    ])


def test_a_bounded_campaign_finds_nothing_on_the_spec_vehicle():
    units: list[int] = []
    kinds: set[str] = set()

    class Counting(Runner):
        def apply(self, step: dict[str, Any]) -> Any:
            kinds.add(step["op"])
            return super().apply(step)

    import mavconform.fuzz.protocol.machine as machine_module
    old, machine_module.Runner = machine_module.Runner, Counting
    try:
        assert search("builtin:spec", seed=5, max_examples=120, on_example=units.append, handover=True) == []
    finally:
        machine_module.Runner = old
    assert len(units) >= 120 and {"control", "gcs_loss"} <= kinds


def test_the_report_lists_the_control_invariants_only_with_the_knob():
    assert invariants(False) == INVARIANTS
    assert list(invariants(True)) == [*INVARIANTS, *CONTROL_INVARIANTS]
    assert {"two-owners", "non-owner-executed", "owner-without-request", "control-status-lies",
            "handover-unbounded", "silent-owner-kept", "control-answer-lies"} == set(CONTROL_INVARIANTS)


# --- the operator-control mutants --------------------------------------------------------------

# mutant -> the invariant its bug breaks. A seed's programs depend on the modules loaded
# (Hypothesis draws constants from them), so seeds are tried in turn, as for the SITL crash.
FOUND = {
    "screens-commands-only": "non-owner-executed",
    "ignores-control-release": "control-answer-lies",
    "takeover-flag-sticks": "control-answer-lies",
    "any-heartbeat-keeps-owner": "silent-owner-kept",
    "never-grants-takeover": "control-answer-lies",
    "control-status-stale-stream": "control-status-lies",
}


@pytest.mark.parametrize("mutant", sorted(FOUND))
def test_an_operator_control_mutant_is_found_and_its_case_replays(mutant, tmp_path):
    want = FOUND[mutant]
    found: list[Case] = []
    with shrink_time_limit(5.0):
        for seed in range(1, 6):
            found = [c for c in search(f"mutant:{mutant}", seed=seed, max_examples=300, handover=True)
                     if c.violation.invariant == want]
            if found:
                break
    assert found, f"{mutant}: no {want} finding in 5 seeds x 300 examples"
    case = found[0]
    assert case.found_by["handover"] is True and case.violation.invariant in CONTROL_INVARIANTS
    loaded = load_case(save_case(case, tmp_path))
    assert replay(loaded) == case.violation                 # same invariant, detail and step
    assert replay(Case("protocol", "builtin:spec", case.seed, case.steps, found_by=case.found_by)) is None


# --- planted bugs for what no mutant breaks ------------------------------------------------------

class _AcceptsWithoutGranting(ControlManager):
    """ACKs a request that needs permission with ACCEPTED, and leaves the owner in control."""

    def _refuse(self, src: Any, allow: bool, timeout: float, now: float) -> list:
        return [self._ack(src, _d.MAV_RESULT_ACCEPTED)]


class _GrantsOnHeartbeat(ControlManager):
    """Makes any GCS whose HEARTBEAT it hears while nobody is in control the owner, unasked."""

    def handle(self, frame: Any, now: float) -> list:
        if frame.msg._type == "HEARTBEAT" and not self.owner and frame.source[0] == B:
            return self._grant(frame.source, False, now)[1:]
        return super().handle(frame, now)


class _ObeysEveryone(ControlManager):
    """Screens mission writes, but lets every command through."""

    def screen(self, frame: Any) -> Any:
        if frame.msg._type in ("COMMAND_LONG", "COMMAND_INT"):
            return None
        return super().screen(frame)


PLANTED = {
    "test-accepts-without-granting": (_AcceptsWithoutGranting, "two-owners",
                                      [control("a", "request"), control("b", "request")]),
    "test-grants-on-heartbeat": (_GrantsOnHeartbeat, "owner-without-request",
                                 [{"op": "wait", "seconds": 1.5}]),
    "test-obeys-everyone": (_ObeysEveryone, "non-owner-executed",
                            [control("a", "request"), upload(3),
                             stray_command(int(_d.MAV_CMD_MISSION_START), "b")]),
}


@pytest.mark.parametrize("name", sorted(PLANTED))
def test_a_planted_control_bug_breaks_its_invariant(name, monkeypatch):
    manager, want, steps = PLANTED[name]
    monkeypatch.setitem(MUTANTS, name, Mutant(name, "planted in a test", frozenset(), control_mutant(manager)))
    assert replay(Case("protocol", "builtin:spec", 0, tuple(steps), found_by=HANDOVER)) is None
    v = replay(Case("protocol", f"mutant:{name}", 0, tuple(steps), found_by=HANDOVER))
    assert v is not None and v.invariant == want, v
    assert v.step == len(steps) - 1


def test_a_bug_in_the_control_judge_is_a_tool_error_not_a_target_crash(monkeypatch):
    from mavconform.fuzz.protocol.control import ControlWatch

    def broken(self, *args):
        raise KeyError("planted in the judge")
    monkeypatch.setattr(ControlWatch, "_answers", broken)
    with pytest.raises(KeyError, match="planted in the judge"):
        replay(Case("protocol", "builtin:spec", 0, (control("a", "request"),), found_by=HANDOVER))


# --- cases, old and new ----------------------------------------------------------------------------

def test_cases_without_the_knob_load_and_replay_as_before(tmp_path):
    old = {"format": "mavconform-fuzz-case/1", "mode": "protocol", "target": "mutant:non-atomic-upload",
           "seed": 0, "violation": None, "found_by": {"search_seed": 1, "examples": 9},
           "steps": [{"op": "faults", "up": {"cut": {"name": "MISSION_ITEM_INT", "nth": 2, "span": 40}}},
                     upload(3), {"op": "upload", "type": 0, "items": []}]}
    path = tmp_path / "old.json"
    path.write_text(json.dumps(old))
    case = load_case(path)
    assert "handover" not in case.found_by
    v = replay(case)
    assert v is not None and v.invariant == "atomic-upload"
    runner = Runner("builtin:spec", 0)                     # no knob: no system manager, no watch
    assert runner.world.vehicle.control is None and runner.world.watch is None
    assert not runner.world.a.heartbeat and runner.world.a.control is None


def test_a_control_step_needs_the_knob_and_a_bad_knob_is_a_usage_error():
    steps = (control("a", "request"),)
    with pytest.raises(UsageError, match="step 0: a control step needs operator control"):
        replay(Case("protocol", "builtin:spec", 0, steps))
    with pytest.raises(UsageError, match="found_by.handover: expected true or false"):
        replay(Case("protocol", "builtin:spec", 0, steps, found_by={"handover": "yes"}))
    with pytest.raises(UsageError, match="action must be request, release, allow or disallow"):
        replay(Case("protocol", "builtin:spec", 0, ({**steps[0], "action": "steal"},), found_by=HANDOVER))


def test_the_versions_oracle_takes_a_refusal_before_any_item_as_no_write():
    """A non-atomic vehicle may hold a mix after an upload that went part way; one refused at
    its MISSION_COUNT (the control filter's DENIED to a GCS not in control) wrote nothing."""
    old = (MissionItem(0, 3, 16, x=1, y=1, z=1.0),)
    new = (MissionItem(0, 3, 16, x=2, y=2, z=2.0),)
    versions = Versions({t: () for t in (MissionType.MISSION, MissionType.FENCE, MissionType.RALLY)}, atomic=False)
    versions.observe(MissionType.MISSION, old)
    versions.apply([Write((MissionType.MISSION,), (new,), False, False, untouched=True)])
    assert versions.possible[MissionType.MISSION] == [old]
    versions.apply([Write((MissionType.MISSION,), (new,), False, False)])
    assert versions.possible[MissionType.MISSION] is None


def test_the_cli_records_the_knob_and_replays_it(tmp_path, capsys):
    found = tmp_path / "found"
    code = main(["fuzz", "--operator-control", "--target", "mutant:refuses-control-when-free", "--examples", "300",
                 "--seed", "1", "--database", "none", "--findings", str(found),
                 "--report-dir", str(tmp_path / "rep"), "-q"])
    out = capsys.readouterr().out
    assert code == 1 and "operator control on (--operator-control)" in out and "two-owners" in out
    (path,) = sorted(found.glob("*.json"))
    doc = json.loads(path.read_text())
    assert doc["found_by"]["handover"] is True and doc["violation"]["invariant"] == "control-answer-lies"
    assert doc["steps"][-1]["op"] == "control" and doc["steps"][-1]["action"] == "request"
    assert main(["fuzz", "--replay", str(path)]) == 1
    report = json.loads((tmp_path / "rep" / "fuzz.json").read_text())
    assert any(row["id"] == "FUZZ.PROTOCOL.two-owners" for row in report["clauses"])


@pytest.mark.parametrize("args, message", [
    (["--operator-control", "--mode", "frames"], "--operator-control applies to --mode protocol"),
    (["--operator-control", "--replay", "x.json"], "nor does --operator-control"),
])
def test_handover_usage_mistakes_exit_2(args, message, capsys, tmp_path):
    assert main(["fuzz", "--findings", str(tmp_path / "f"), "--report-dir", str(tmp_path / "r"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


# --- over UDP --------------------------------------------------------------------------------------

@pytest.mark.udp
def test_over_udp_a_target_without_control_status_is_a_usage_error(monkeypatch):
    import importlib
    from tests.fuzz.test_protocol_udp import served
    search_module = importlib.import_module("mavconform.fuzz.protocol.search")
    monkeypatch.setattr(search_module, "CONTROL_STATUS_WAIT", 0.5)
    with served(VehicleNode(VehicleConfig())) as target:
        with pytest.raises(UsageError, match="sent no CONTROL_STATUS in 0.5 s"):
            search(target, seed=1, max_examples=1, handover=True)


@pytest.mark.udp
def test_over_udp_a_system_manager_is_judged_from_the_wire():
    from mavconform.fuzz.protocol import Knobs
    from tests.fuzz.test_protocol_udp import served
    steps = (control("a", "request", timeout=3.0), upload(2, "b"), upload(1), {"op": "download", "type": 0},
             control("a", "release", timeout=3.0), upload(2, "b"))
    with served(VehicleNode(VehicleConfig(control=SUITE_CONTROL))) as target:
        assert replay(Case("protocol", target, 0, steps, found_by={"handover": True})) is None
        knobs = Knobs(max_items=4, steps=4, max_wait=0.5, max_burst=1.0, handover=True)
        assert search(target, seed=2, max_examples=3, knobs=knobs) == []
    with served(MUTANTS["screens-commands-only"].build(VehicleConfig())) as target:
        v = replay(Case("protocol", target, 0, steps, found_by={"handover": True}))
    assert v is not None and v.invariant == "non-owner-executed" and v.step == 1
    assert "ACCEPTED an upload of 2 mission items by GCS B" in v.detail
