"""The fault-tolerance table: current in the docs, never vacuous, able to fail."""

from __future__ import annotations

from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.fault_table_cmd import default_profiles
from mavconform.reference_impl.interop import fault_table, report
from mavconform.reference_impl.interop.fault_table import FAILS_UNCLEANLY, RECOVERS, run_cell
from mavconform.reference_impl.interop.harness import build_pair, sample_plan
from mavconform.reference_impl.interop.mocklink import MODES, MODES_BY_ID, MockLinkVehicle
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.results import Operation
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.wire.codec import FrameDecoder

DOC = Path(__file__).resolve().parents[2] / "docs" / "fault-tolerance.md"
PROFILES = default_profiles()   # every builtin profile but inav (it ignores the _INT messages)


@pytest.fixture(scope="module")
def interop():
    return report.run(PROFILES)


def test_the_checked_in_document_is_what_the_command_writes(interop, tmp_path, capsys):
    out = tmp_path / "fault-tolerance.md"
    assert main(["fault-table", "--output", str(out)]) == 0
    assert DOC.read_text() == out.read_text() == report.render_markdown(interop), (
        "docs/fault-tolerance.md is stale: run `mavconform fault-table --output docs/fault-tolerance.md`")


def test_the_report_is_deterministic(interop):
    assert report.render_json(report.run(PROFILES)) == report.render_json(interop)


def test_every_cell_recovers_or_fails_cleanly_and_the_lost_first_responses_recover(interop):
    table = interop.table
    assert len(table.cells) == len(MODES) * len(PROFILES)
    assert not table.unclean, [c.text for c in table.unclean]
    for mode in MODES:
        for p in table.profiles:
            cell = table.cell(p, mode.id)
            assert cell.seconds is not None and cell.seconds <= fault_table.RESULT_BOUND
            if mode.qgc_recovers:     # QGC recovers from these; so must we
                assert cell.verdict == RECOVERS, cell.text


def test_every_round_trip_succeeds_and_reports_its_adaptations(interop):
    trips = {t.profile: t for t in interop.trips}
    assert all(t.ok for t in trips.values()), [(t.profile, s.what, s.problem) for t in trips.values() for s in t.steps if not s.ok]
    assert trips["spec"].adaptations_used == ()
    assert {"home-at-seq0", "clear-types-separately"} <= set(trips["ardupilot"].adaptations_used)


def test_every_mode_is_injected_on_the_wire(interop):
    """The table cannot be vacuous: in every cell the failure really happened, in the way
    the mode says (dropped before the vehicle, dropped from it, or rewritten)."""
    for cell in interop.table.cells:
        mode = MODES_BY_ID[cell.mode]
        assert cell.injections >= 1, f"{cell.profile}/{cell.mode}: the mode never acted"
        if mode.first_only:
            assert cell.injections == 1
        expected = {"drop": "dropped", "bump-seq": "replaced", "error-ack": "by MISSION_ACK ERROR",
                    "accept-ack": "by MISSION_ACK ACCEPTED"}[mode.action]
        assert expected in cell.first_injection, (cell.profile, cell.mode, cell.first_injection)
        where = "on its way to the vehicle" if mode.inbound else "from the vehicle"
        assert where in cell.first_injection


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.id)
def test_what_the_gcs_receives_shows_the_failure(mode):
    """Read off the wire at the GCS's side (spec vehicle): a rewritten message arrives, a
    dropped answer never does, an inbound drop swallowed every matching GCS message."""
    box = []
    pair = build_pair(load_profile("spec"), wrap=lambda v: box.append(MockLinkVehicle(v, mode)) or box[0])
    injector = box[0]
    plan = sample_plan(fault_table.PLAN_SIZE)
    assert pair.upload(T.MISSION, plan).ok and pair.settle() is not None
    seen: dict[str, list] = {"to_gcs": [], "from_gcs": []}
    decoder = FrameDecoder()

    def hook(rec):
        if rec.kind == "rx" and rec.dst == "gcs":
            seen["to_gcs"] += [f.msg for f in decoder.feed(rec.data) if getattr(f, "msg", None)]
        elif rec.kind == "tx" and rec.src == "gcs":
            seen["from_gcs"] += [f.msg for f in decoder.feed(rec.data) if getattr(f, "msg", None)]

    pair.net.add_capture(hook)
    injector.armed = True
    if mode.operation is Operation.DOWNLOAD:
        pair.download(T.MISSION)
    else:
        pair.upload(T.MISSION, sample_plan(fault_table.PLAN_SIZE, shift=7))
    pair.settle()
    got = seen["to_gcs"]
    if mode.inbound:
        sent = [m for m in seen["from_gcs"] if mode.matches(m)]
        assert sent and injector.fired == (1 if mode.first_only else len(sent))
    elif mode.action == "drop":
        assert not any(mode.matches(m) for m in got), "a message the mode drops reached the GCS"
    elif mode.action == "bump-seq":
        wrong = [m for m in got if m._type in mode.names and m.seq == mode.seq + 1]
        right = [m for m in got if m._type in mode.names and m.seq == mode.seq]
        assert wrong and not right
    else:
        code = 1 if mode.action == "error-ack" else 0
        assert any(m._type == "MISSION_ACK" and m.type == code for m in got)
        if not mode.accepted_only:
            assert not any(mode.matches(m) for m in got)


def test_a_gcs_that_never_gives_up_is_reported_unclean(monkeypatch):
    """Negative control: with the client's timers disabled, a silent vehicle leaves the
    operation without a result, and the table says so."""
    monkeypatch.setattr(MissionClient, "poll", lambda self, now: [])
    monkeypatch.setattr(MissionClient, "next_deadline", lambda self: None)
    cell = run_cell(load_profile("spec"), MODES_BY_ID["read-list-no-response"])
    assert cell.verdict == FAILS_UNCLEANLY and "no result" in cell.text


def test_a_gcs_that_hides_a_partial_upload_is_reported_unclean(monkeypatch):
    """Negative control: without the non-atomic-upload adaptation's honesty, a failed upload
    to the ArduPilot-like vehicle changes its plan while the result says it did not."""
    monkeypatch.setattr(MissionClient, "_upload_unknown", lambda self, op, code=None: False)
    cell = run_cell(load_profile("ardupilot"), MODES_BY_ID["write-req1-error-ack"])
    assert cell.verdict == FAILS_UNCLEANLY and "plan changed" in cell.text
