"""The fidelity survey's command × param matrix (issue 26): the probes follow upstream's param
definitions, each builtin profile's matrix equals its prediction, a mutant that rounds one
param is caught in exactly the cell it breaks, a refusal inside a batch decides its own cell
only, and the reports carry the matrix."""

from __future__ import annotations

import json
import math

import pytest

from mavconform.cli import main
from mavconform.conformance.fidelity.cells import entry_key
from mavconform.conformance.fidelity.command_facts import COMMANDS
from mavconform.conformance.fidelity.probes import INT32_MAX, VALUE, command_cells
from mavconform.conformance.fidelity.run import scope_cells, survey
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.mission.items import to_float32


def _survey(target: str, scope: str = "commands") -> dict:
    return survey(parse_target(target), scope=scope, virtual=True).doc["fidelity"]


def _probes(command: int) -> dict[str, float]:
    out = {}
    for cell in command_cells([command]):
        it = cell.items[0]
        index = int(cell.probe[1]) if cell.probe != "nominal" else 0
        out[cell.probe] = (None if index == 0 else
                           (it.param1, it.param2, it.param3, it.param4, it.x, it.y, it.z)[index - 1])
    return out


def test_probes_come_from_each_params_upstream_definition() -> None:
    delay = _probes(93)                     # NAV_DELAY: p2 hour, -1..23 step 1; p5-7 reserved
    assert command_cells([93])[0].items[0].param2 == -1 and "p2:min" not in delay    # the nominal item has it
    assert delay["p2:max"] == 23 and delay["p2:below"] == -2 and delay["p2:above"] == 24
    assert delay["p2:inside"] == 11 and delay["p2:off-increment"] == 11.5 and delay["p5:reserved"] == 1
    wp = _probes(16)                        # NAV_WAYPOINT: p4 yaw, NaN means "current heading"
    assert math.isnan(wp["p4:nan"]) and wp["p4:value"] == VALUE == to_float32(1234.5678) and "p5:int32_max" not in wp
    orbit = _probes(34)                     # DO_ORBIT: INT32_MAX in x/y means "current position"
    assert orbit["p5:int32_max"] == orbit["p6:int32_max"] == INT32_MAX
    land = _probes(21)                      # NAV_LAND p2: PRECISION_LAND_MODE 0..2
    assert (land["p2:enum-last"], land["p2:enum-invalid"]) == (2, 3)
    every = command_cells()
    assert len({c.key for c in every}) == len(every)             # one cell per probe
    assert {c.command for c in every if c.probe == "nominal"} == set(COMMANDS)
    assert not {5000, 5001, 5003, 5100} & set(COMMANDS)          # plan-type items: the frame matrix's
    for cell in every:
        it = cell.items[0]
        assert cell.frame == (6 if COMMANDS[cell.command].has_location else 2) == it.frame
        assert all(v != v or v == to_float32(v) for v in (it.param1, it.param2, it.param3, it.param4, it.z))


@pytest.mark.parametrize("profile", ["spec", "px4", "px4-fixedwing", "ardupilot", "ardupilot-plane"])
def test_a_builtin_profiles_command_matrix_is_as_its_rules_predict(profile: str) -> None:
    fid = _survey(f"builtin:{profile}")
    assert fid["scope"] == "commands"
    unlike = [(e["command"], e["probe"], e["class"], e["predicted"]) for e in fid["cells"] if not e["as_predicted"]]
    assert not unlike
    nominal = [e for e in fid["cells"] if e["probe"] == "nominal"]
    assert len(nominal) == len(COMMANDS)
    taken = {e["command"] for e in nominal if not e["class"].startswith("refused:")}
    assert {e["command"] for e in fid["cells"] if e["probe"] != "nominal"} == taken     # params of taken ones only
    assert fid["uploads"] < len(fid["cells"]) / 2                                        # batched


def test_builtin_px4_keeps_what_px4s_mission_item_record_keeps() -> None:
    """Learnt from PX4 v1.16 SIH (P28): a waypoint's pass radius is not kept, its yaw wraps to
    [0, 360), a DO_JUMP repeat of -1 comes back 65535, a bad region-of-interest mode is refused."""
    cells = {entry_key(e)[2:]: e for e in _survey("builtin:px4")["cells"]}
    assert cells[(16, "p3:value")]["back"][0]["param3"] == 0.0
    assert cells[(16, "p4:negative")]["back"][0]["param4"] == 347.625
    assert cells[(16, "p1:below")]["class"] == "exact"                    # a negative hold time: no check
    assert cells[(177, "p2:below")]["back"][0]["param2"] == 65535.0
    assert cells[(201, "p1:enum-last")]["class"] == "refused:INVALID_PARAM1"
    assert cells[(80, "nominal")]["back"][0]["command"] == 201
    assert "(rule: px4 item storage" in cells[(19, "p2:value")]["class"]
    spec = {entry_key(e)[2:]: e for e in _survey("builtin:spec")["cells"]}
    assert spec[(16, "p3:value")]["class"] == "exact" and spec[(16, "p1:below")]["class"] == "refused:INVALID_PARAM1"


def test_a_mutant_that_rounds_a_param_is_caught_in_the_cell_it_breaks() -> None:
    fid = _survey("mutant:rounds-change-speed")
    unlike = {(e["command"], e["probe"]): e for e in fid["cells"] if not e["as_predicted"]}
    assert set(unlike) == {(178, "p2:inside")}
    assert unlike[(178, "p2:inside")]["class"] == "changed:param2 10.375->10.0"
    assert unlike[(178, "p2:inside")]["predicted"] == "exact"
    assert unlike[(178, "p2:inside")]["precision"] == {"param2": 0.375}


def test_a_refusal_in_a_batch_decides_its_own_cell_and_the_rest_go_up_again() -> None:
    """builtin:spec refuses NAV_DELAY's out-of-range probes? No: it keeps any value. PX4's model
    refuses a DO_SET_ROI mode 4 and 5 within the command's batch; every other probe of it is
    still judged from a download."""
    fid = _survey("builtin:px4")
    roi = [e for e in fid["cells"] if e["command"] == 201]
    refused = [e["probe"] for e in roi if e["class"].startswith("refused:")]
    assert refused == ["p1:enum-last", "p1:enum-invalid"]
    assert all(e["back"] is not None for e in roi if not e["class"].startswith("refused:"))
    ups = {e["exchange"] for e in roi}
    assert len(ups) == 4          # nominal, the batch refused at mode 4, at mode 5, then the rest


@pytest.mark.udp
def test_the_command_writes_both_matrices(tmp_path, capsys) -> None:
    assert main(["fidelity", "--target", "builtin:px4", "--matrix-scope", "all", "-q",
                 "--report-dir", str(tmp_path)]) == 0
    assert "profile px4: 0 unlike its prediction" in capsys.readouterr().out
    doc = json.loads((tmp_path / "run.json").read_text())
    fid = doc["fidelity"]
    taken = {e["command"] for e in fid["cells"] if e.get("probe") == "nominal" and not e["class"].startswith("refused")}
    assert fid["scope"] == "all" and len(fid["cells"]) == 110 + sum(
        1 for c in scope_cells("commands") if c.probe == "nominal" or c.command in taken)
    probe = next(e for e in fid["cells"] if e.get("probe") == "p4:negative" and e["command"] == 16)
    assert set(probe) >= {"plan_type", "frame", "command", "probe", "sent", "back", "class", "precision"}
    md = (tmp_path / "run.md").read_text()
    assert "### Frames × plan types (110 cells)" in md and "### Commands × params" in md
    assert "Refused UNSUPPORTED as such (70): " in md and "18 NAV_LOITER_TURNS, " in md
    assert "- rule px4 storage: px4 item storage of the profile (px4 item storage (the builtin:px4 profile))" in md
    page = (tmp_path / "run.html").read_text()
    assert "<h2>Commands × params" in page and 'class="chip changed' in page and "<th>16 NAV_WAYPOINT</th>" in page


def test_report_diff_names_the_probe(tmp_path, capsys) -> None:
    a, b = tmp_path / "a", tmp_path / "b"
    main(["fidelity", "--target", "builtin:spec", "--matrix-scope", "commands", "-q", "--report-dir", str(a)])
    main(["fidelity", "--target", "mutant:rounds-change-speed", "--matrix-scope", "commands", "-q",
          "--report-dir", str(b)])
    capsys.readouterr()
    assert main(["report", "diff", str(a / "run.json"), str(b / "run.json")]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out == ["cell mission frame 2 command 178 p2:inside: exact -> changed:param2 10.375->10.0",
                   f"1 difference(s) between {a / 'run.json'} and {b / 'run.json'}"]
