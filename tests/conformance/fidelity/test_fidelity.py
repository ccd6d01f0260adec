"""The fidelity survey (issue 26, frames × plan types): each builtin profile's matrix equals what
its declared rules predict, cell for cell; three mutants are caught in exactly the cells they
break; the classes follow the rules; `mavconform fidelity` writes run.json, run.md and run.html."""

from __future__ import annotations

import json
from dataclasses import replace

import pytest

from mavconform.cli import main
from mavconform.conformance.fidelity.cells import FRAMES, entry_key, frame_cells
from mavconform.conformance.fidelity.classify import UPSTREAM_RESERVED, classify
from mavconform.conformance.fidelity.predict import predict
from mavconform.conformance.fidelity.run import survey
from mavconform.conformance.harness.stored_form import StoredForm
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.profiles import load_profile
from mavconform.reports.run_document import check_run


def _cells(target: str) -> dict[tuple, dict]:
    doc = survey(parse_target(target), virtual=True).doc
    return {entry_key(e)[:3]: e for e in doc["fidelity"]["cells"]}


@pytest.mark.parametrize("profile", ["spec", "px4", "px4-fixedwing", "ardupilot", "ardupilot-plane"])
def test_a_builtin_profile_comes_out_as_its_rules_predict(profile: str) -> None:
    cells = _cells(f"builtin:{profile}")
    assert len(cells) == 5 * len(FRAMES)
    unlike = {k: (e["class"], e["predicted"]) for k, e in cells.items() if not e["as_predicted"]}
    assert not unlike
    assert {e["class"].split(":")[0] for e in cells.values()} >= {"exact", "refused"}


@pytest.mark.parametrize("mutant,broken", [
    ("rounds-circle-radius", {("fence", f, 5003): "changed:param1 {r}->{w}" for f in (0, 3, 5, 6, 10, 11)}),
    ("drops-relative-alt-int", {("mission", 6, 16): "changed:frame 6->5"}),
    ("refuses-terrain-frames", {("mission", 10, 16): "refused:UNSUPPORTED_FRAME",
                                ("mission", 11, 16): "refused:UNSUPPORTED_FRAME"}),
])
def test_a_mutant_is_caught_in_the_cells_it_breaks(mutant: str, broken: dict) -> None:
    cells = _cells(f"mutant:{mutant}")
    unlike = {k: e["class"] for k, e in cells.items() if not e["as_predicted"]}
    assert set(unlike) == set(broken)
    for key, want in broken.items():
        radius = 150.25 + FRAMES.index(key[1])
        assert unlike[key] == want.format(r=radius, w=float(round(radius)))
        assert cells[key]["predicted"] == "exact"


def _wp(frame: int, **changes) -> MissionItem:
    return replace(MissionItem(0, frame, Cmd.NAV_WAYPOINT, 0.0, 0.0, 0.0, 0.0, 473977420, 85455940, 30.0, 0, 1),
                   **changes)


def test_the_classes_follow_the_rules() -> None:
    spec = StoredForm()
    assert classify([_wp(3)], [_wp(3, current=1)], spec) == "exact"
    assert classify([_wp(3)], [_wp(6)], spec) == "int_twin"
    assert classify([_wp(3)], [_wp(0)], spec) == "changed:frame 3->0"
    assert classify([_wp(3)], [_wp(3, z=30.5)], spec) == "changed:z 30.0->30.5"
    vertex = MissionItem(0, 3, 5001, 3.0, 0.0, 0.0, 0.0, 1, 2, 0.0, 0, 1, MissionType.FENCE)
    assert classify([vertex], [replace(vertex, frame=5)], spec) == f"changed:frame 3->5 (rule: {UPSTREAM_RESERVED})"
    compact = StoredForm(storage="compact15", basis="A13")
    ret = MissionItem(0, 0, 5000, 0.0, 0.0, 0.0, 0.0, 1, 2, 20.0, 0, 1, MissionType.FENCE)   # no altitude kept
    assert classify([ret], [replace(ret, z=0.0)], compact) == "changed:z 20.0->0.0 (rule: compact15 item storage)"
    assert classify([ret], [replace(ret, z=0.0)], spec) == "changed:z 20.0->0.0"


def test_a_refusal_is_predicted_with_its_code() -> None:
    px4 = load_profile("px4")
    cell = next(c for c in frame_cells() if c.key == ("mission", 1, 16, ""))
    assert predict(cell, px4.behaviour, StoredForm()) == "refused:UNSUPPORTED_FRAME"


@pytest.mark.udp
def test_the_command_writes_the_matrix(tmp_path, capsys) -> None:
    assert main(["fidelity", "--target", "builtin:spec", "-q", "--report-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "110 cells in" in out and "profile spec: 0 unlike its prediction" in out
    doc = json.loads((tmp_path / "run.json").read_text())
    check_run(doc)
    fid = doc["fidelity"]
    assert fid["format"] == "mavconform-fidelity/1" and fid["scope"] == "frames" and len(fid["cells"]) == 110
    entry = next(e for e in fid["cells"] if (e["plan_type"], e["frame"], e["command"]) == ("fence", 3, 5001))
    assert set(entry) == {"plan_type", "frame", "command", "sent", "back", "class", "predicted", "as_predicted", "exchange"}
    assert fid["exchanges"][entry["exchange"]][0]["msg"] == "MISSION_COUNT" and len(fid["exchanges"]) == fid["uploads"]
    assert len(entry["sent"]) == 3 and entry["class"] == "exact" and entry["back"] == entry["sent"]
    assert doc["restore"]["status"] in ("restored", "unchanged")
    assert "| 3 GLOBAL_RELATIVE_ALT | exact |" in (tmp_path / "run.md").read_text()
    page = (tmp_path / "run.html").read_text()
    assert page.count("<td class=\"exact\" title=\"exact\">") == 30 and "MISSION_COUNT" in page
    assert f'href="#e{entry["exchange"]}"' in page and f'id="e{entry["exchange"]}"' in page
    assert main(["fidelity", "--target", "mutant:drops-relative-alt-int", "-q", "--report-dir", str(tmp_path)]) == 1
    assert "⚠ profile: exact" in (tmp_path / "run.md").read_text()
    assert '<td class="changed ruleless unlike" title="changed:frame 6-&gt;5">' in (tmp_path / "run.html").read_text()


def test_report_diff_shows_exactly_the_cells_that_differ(tmp_path, capsys) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    main(["fidelity", "--target", "builtin:spec", "-q", "--report-dir", str(a)])
    main(["fidelity", "--target", "mutant:refuses-terrain-frames", "-q", "--report-dir", str(b)])
    capsys.readouterr()
    assert main(["report", "diff", str(a / "run.json"), str(a / "run.json")]) == 0
    capsys.readouterr()
    assert main(["report", "diff", str(a / "run.json"), str(b / "run.json")]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == ["cell mission frame 10 command 16: exact -> refused:UNSUPPORTED_FRAME",
                       "cell mission frame 11 command 16: exact -> refused:UNSUPPORTED_FRAME"]
    assert out[-1].startswith("2 difference(s) between")


def test_builtin_px4_refuses_fence_and_rally_where_px4s_parser_does() -> None:
    """Learnt from PX4 v1.16 SIH (docs/real-targets.md): its one parser takes fence and rally items
    only in the global frames (frame_lists_all_plans)."""
    cells = _cells("builtin:px4")
    for plan_type, command in (("fence", 5001), ("fence", 5003), ("fence", 5000), ("rally", 5100)):
        assert cells[(plan_type, 2, command)]["class"] == "refused:UNSUPPORTED"
        assert cells[(plan_type, 10, command)]["class"] == cells[(plan_type, 11, command)]["class"] == \
            "refused:UNSUPPORTED_FRAME"
        assert cells[(plan_type, 3, command)]["class"] == "exact"
    spec = _cells("builtin:spec")
    assert spec[("fence", 2, 5001)]["class"] == "refused:UNSUPPORTED_FRAME" and spec[("rally", 10, 5100)]["class"] == "exact"
