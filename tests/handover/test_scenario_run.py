"""The scenario runner in virtual time: the shipped delivery flights hand over out and back, the
timeline says so, the same seed gives the same bytes, and a handover that cannot complete or a
flight that cannot end is reported as such (reference_impl/handover/scenario_run.py,
reports/handover_report.py)."""

from __future__ import annotations

import json

import pytest

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, ScenarioError, load_scenario, scenario_from_dict
from mavconform.reference_impl.handover.scenario_fleet import flight_items, roster_of, vehicle_config
from mavconform.reference_impl.handover.scenario_run import THESIS_STEPS, run_scenario
from mavconform.reference_impl.net import McapCapture
from mavconform.reports.handover_report import FORMAT, dump_timeline, handover_html, timeline

SHIPPED = ["delivery_flight.json", "delivery_flight_circles.json", "delivery_flight_waypoints.json"]


def shipped(name: str = "delivery_flight.json"):
    return load_scenario(SCENARIOS_DIR / name)


def changed(name: str = "delivery_flight.json", **edits):
    """The shipped scenario with top-level fields replaced (`gcs1_link` for GCS B's link)."""
    data = json.loads((SCENARIOS_DIR / name).read_text(encoding="utf-8"))
    if "gcs1_link" in edits:
        data["gcs"][1]["link"] = edits.pop("gcs1_link")
    if "gcs0_link" in edits:
        data["gcs"][0]["link"] = edits.pop("gcs0_link")
    data.update(edits)
    return scenario_from_dict(data, source="edited.json")


@pytest.mark.parametrize("name", SHIPPED)
def test_each_shipped_delivery_flight_hands_over_twice_and_owners_per_segment_are_a_b_a(name):
    run = run_scenario(shipped(name))
    doc = timeline(run)
    assert run.finished and run.flight_complete
    assert [(h["commander"], h["partner"], h["outcome"], h["owner_after"]) for h in doc["handovers"]] == [
        ("A", "B", "COMPLETED", "B"), ("B", "A", "COMPLETED", "A")]
    assert [s["owner"] for s in doc["segments"]] == ["A", "B", "A"]
    assert doc["summary"]["verdict"] == "pass" and doc["summary"]["problems"] == []
    for h in doc["handovers"]:
        assert [s["step"] for s in h["steps"]] == [1, 2, 3, 4, 5, 6]
        assert [s["message"] for s in h["steps"]] == [THESIS_STEPS[n] for n in range(1, 7)]
        assert 0 < h["duration_s"] <= run.scenario.timeouts.handover_bound_s
    # the segments join where control moved (step 4 of each handover)
    grants = [next(s["t"] for s in h["steps"] if s["step"] == 4) for h in doc["handovers"]]
    assert [s["end_s"] for s in doc["segments"][:-1]] == grants
    assert doc["segments"][0]["start_s"] == doc["run"]["mission_started_s"]
    assert doc["segments"][-1]["end_s"] == doc["run"]["flight_ended_s"]


def test_the_timeline_is_in_time_order_and_tells_the_flight_from_start_to_end():
    doc = timeline(run_scenario(shipped()))
    events = doc["events"]
    assert [e["t"] for e in events] == sorted(e["t"] for e in events)
    kinds = [e["kind"] for e in events]
    assert kinds.index("control-changed") < kinds.index("mission-uploaded") < kinds.index("mission-started")
    assert kinds[-1] == "flight-ended"
    assert kinds.count("handover-started") == kinds.count("handover-finished") == 2
    assert kinds.count("handover-step") == 12
    assert [e["seq"] for e in events if e["kind"] == "waypoint-reached"] == list(range(9))
    # the handover region is entered (the geometry) before the handover starts (after the 1 s dwell)
    entered = [e["t"] for e in events if e["kind"] == "region-entered" and e["region"] == "A+B"]
    started = [e["t"] for e in events if e["kind"] == "handover-started"]
    assert len(entered) == 2
    for region_t, handover_t in zip(entered, started):
        assert 1.0 <= handover_t - region_t <= 1.2
    assert {e["gcs"] for e in events if e["kind"] == "coverage-left"} == {"A", "B"}
    assert doc["format"] == FORMAT
    assert doc["scenario"]["gcs"][0]["signing"] == {"fingerprint": "1503db6d", "link_id": 0}   # never the key


def test_each_handover_carries_its_exchange_from_the_invitation_to_the_last_step():
    """The captured messages between a handover's start and end, as the report draws them: the
    vehicle's invitation to the partner first, the partner's request, the forward to the
    commander, CONTROL_STATUS naming the partner; no telemetry."""
    doc = timeline(run_scenario(shipped()))
    for h in doc["handovers"]:
        ex = h["exchange"]
        assert all(h["started_s"] <= e["t"] <= h["finished_s"] for e in ex)
        first = ex[0]
        assert (first["dir"], first["peer"], first["msg"]) == ("rx", h["partner"], "COMMAND_LONG")
        assert first["fields"]["command"] == cm.REQUEST_CONTROL and first["fields"]["param4"] == \
            doc["scenario"]["gcs"][[g["name"] for g in doc["scenario"]["gcs"]].index(h["partner"])]["sysid"]
        assert any(e["dir"] == "tx" and e["peer"] == h["partner"] and e["msg"] == "COMMAND_LONG" for e in ex)
        assert any(e["dir"] == "rx" and e["peer"] == h["commander"] and e["msg"] == "COMMAND_LONG" for e in ex)
        assert any(e["msg"] == "CONTROL_STATUS" for e in ex)
        assert not {e["msg"] for e in ex} & {"HEARTBEAT", "GLOBAL_POSITION_INT"}


def test_same_seed_same_bytes_of_timeline_and_capture_and_another_seed_another_run(tmp_path):
    scenario = shipped()
    outputs = []
    for i, seed in enumerate((None, None, 7)):
        path = tmp_path / f"{i}.mcap"
        with McapCapture(path) as capture:
            run = run_scenario(scenario, seed=seed, capture=capture)
        outputs.append((dump_timeline(timeline(run)), path.read_bytes()))
    assert outputs[0] == outputs[1]
    assert outputs[2][0] != outputs[0][0] and outputs[2][1] != outputs[0][1]
    assert json.loads(outputs[2][0])["run"]["seed"] == 7


def test_the_capture_has_every_frame_and_a_marker_at_each_handover_start_and_end(tmp_path):
    from mcap.reader import make_reader
    path = tmp_path / "handover.mcap"
    with McapCapture(path) as capture:
        run_scenario(shipped(), capture=capture)
    with open(path, "rb") as f:
        reader = make_reader(f)
        markers = [json.loads(m.data)["message"] for _, ch, m in reader.iter_messages() if ch.topic == "markers"]
        topics = {ch.topic for ch in reader.get_summary().channels.values()}
    assert markers[0] == "mission started" and markers[-1] == "flight ended"
    assert [m.split(" after ")[0] for m in markers if m.startswith("handover")] == [
        "handover 1 A->B started (region A+B)", "handover 1 A->B COMPLETED",
        "handover 2 B->A started (region A+B)", "handover 2 B->A COMPLETED"]
    assert {"A -> vehicle", "vehicle -> A", "B -> vehicle", "vehicle -> B"} <= topics


def test_a_partner_whose_requests_never_arrive_costs_two_aborts_and_a_failing_verdict():
    """GCS B's link drops every COMMAND_LONG it sends (its requests for control): each entry of
    the region starts a handover that aborts at the commit deadline, and A commands the whole
    flight. The exchange shows each lost request as a note."""
    run = run_scenario(changed(gcs1_link={"up": {"delay": 0.05, "drop": ["COMMAND_LONG"]}, "down": {"delay": 0.05}}))
    doc = timeline(run)
    assert [(h["commander"], h["partner"], h["outcome"]) for h in doc["handovers"]] == [("A", "B", "ABORTED")] * 2
    assert [s["owner"] for s in doc["segments"]] == ["A"]
    assert doc["summary"]["verdict"] == "fail"
    assert doc["summary"]["problems"] == [f"handover {n} A->B ABORTED: control not granted to GCS 254 within 11.25 s"
                                          for n in (1, 2)]
    assert run.finished                                  # the flight itself ended
    notes = [e["msg"] for e in doc["handovers"][0]["exchange"] if e["dir"] == "note" and e["peer"] == "B"]
    assert len(notes) >= 2 and set(notes) == {"lost on the link B -> vehicle: COMMAND_LONG (command 32100)"}


def test_a_flight_cut_short_by_the_run_bound_is_reported_not_ended():
    run = run_scenario(changed(timeouts={"max_duration_s": 120.0, "dwell_s": 1.0, "handover_bound_s": 15.0}))
    doc = timeline(run)
    assert run.stopped_by == "max-duration" and run.end == pytest.approx(120.0)
    assert doc["summary"]["problems"] == ["the flight did not end within max_duration_s (120 s)"]
    assert doc["events"][-1]["kind"] == "run-stopped"
    assert [h["outcome"] for h in doc["handovers"]] == ["COMPLETED"]


def test_a_parent_that_cannot_take_control_is_a_setup_failure():
    run = run_scenario(changed(gcs0_link={"up": {"drop": ["COMMAND_LONG"]}}))      # A's commands never arrive
    doc = timeline(run)
    assert run.setup_failure.startswith("the parent GCS A did not get control")
    assert doc["summary"]["verdict"] == "fail" and doc["handovers"] == [] and doc["track"] == []
    assert doc["summary"]["problems"][0].startswith("setup failed: the parent GCS A did not get control")


def test_the_page_is_self_contained_with_map_tables_and_a_diagram_per_handover():
    scenario = shipped()
    doc = timeline(run_scenario(scenario))
    page = handover_html(doc, scenario)
    assert page.count('<svg class="handover-map"') == 1 and page.count('<svg class="sequence"') == 2
    assert "<script" not in page and "http://" not in page.replace("http://www.w3.org/2000/svg", "")
    assert page.count(">COMPLETED</span>") >= 4 and "Owner per segment" in page
    for message in THESIS_STEPS.values():
        assert message in page


def test_signing_is_all_or_nothing_and_the_vehicle_takes_the_scenarios_settings():
    s = shipped()
    config = vehicle_config(s)
    assert config.system == 1 and config.speed == 12 and config.require_signature
    assert sorted(g.sysid for g in config.roster.gcss) == [254, 255]
    mc = config.handover
    assert (mc.parent, mc.dwell, mc.bound, set(dict(mc.coverages))) == (255, 1.0, 15.0, {254, 255})
    assert config.control.owner_loss_timeout == 5.0
    assert [(i.seq, i.z) for i in flight_items(s)][:2] == [(0, 30.0), (1, 60.0)]
    data = json.loads((SCENARIOS_DIR / "delivery_flight.json").read_text(encoding="utf-8"))
    del data["gcs"][1]["signing"]
    with pytest.raises(ScenarioError, match=r"gcs\[1\]\.signing: missing for 'B', while 'A' signs"):
        roster_of(scenario_from_dict(data, source="mixed.json"))
    for g in data["gcs"]:
        g.pop("signing", None)
    unsigned = scenario_from_dict(data, source="unsigned.json")
    assert roster_of(unsigned) is None and not vehicle_config(unsigned).require_signature


def test_a_commander_silent_past_the_loss_timeout_shows_as_an_emergency_in_the_timeline():
    """GCS B's link is cut for 12 s while B commands: the manager drops it after 5 s and, where
    the mission computer has the emergency procedure, the vehicle diverts to a refuge and lands.
    The timeline carries whatever the vehicle reported, and the last segment has no owner."""
    from mavconform.reference_impl.handover.mission_computer import MissionComputerConfig
    data_link = {"delay": 0.05, "partitions": [[250.0, 262.0]]}
    run = run_scenario(changed(gcs1_link=data_link))
    doc = timeline(run)
    lost = [e for e in doc["events"] if e["kind"] == "owner-lost"]
    assert [(e["gcs"], e["silent_s"]) for e in lost] == [("B", 5.0)]
    assert [s["owner"] for s in doc["segments"]][:2] == ["A", "B"]
    if "emergency" not in MissionComputerConfig.__dataclass_fields__:
        pytest.skip("this build's mission computer has no emergency procedure")
    kinds = [e["kind"] for e in doc["events"]]
    assert kinds.count("emergency-started") == 1 and kinds.count("emergency-ended") == 1
    assert doc["summary"]["emergencies"] == 1 and doc["summary"]["owners"] == ["A", "B", None]
    assert run.flight_ended is not None and not run.flight_complete and run.finished
    started = next(e for e in doc["events"] if e["kind"] == "emergency-started")
    assert started["t"] == lost[0]["t"] and started["type"] == "EmergencyStarted"
    page = handover_html(doc, run.scenario)
    assert "emergency at 254.1 s" in page and "1 emergency;" in page


def test_a_plan_flight_uploads_the_plans_mission_and_hands_over_out_and_back(tmp_path):
    """A .plan flight (takeoff, a speed change, waypoints, one in AMSL, then RETURN_TO_LAUNCH):
    the plan's items go up with their seqs, each place where the scenario reads it; the flight
    goes out to the delivery point and home again, so command goes A, B, A."""
    from mavconform.reference_impl.mission.constants import Cmd
    from .test_scenario import _write_plan
    _write_plan(tmp_path)
    data = json.loads((SCENARIOS_DIR / "delivery_flight.json").read_text(encoding="utf-8"))
    data["flight"] = {"plan": "delivery.plan"}
    (tmp_path / "plan-scenario.json").write_text(json.dumps(data), encoding="utf-8")
    s = load_scenario(tmp_path / "plan-scenario.json")
    items = flight_items(s)
    assert [i.seq for i in items] == list(range(7))
    assert items[1].command == Cmd.DO_CHANGE_SPEED and items[6].command == Cmd.NAV_WAYPOINT
    assert items[5].frame == 3 and items[5].z == pytest.approx(20.0, abs=1e-3)
    doc = timeline(run_scenario(s))
    assert [(h["commander"], h["partner"], h["outcome"]) for h in doc["handovers"]] == [
        ("A", "B", "COMPLETED"), ("B", "A", "COMPLETED")]
    assert doc["summary"]["owners"] == ["A", "B", "A"] and doc["run"]["flight_complete"]
