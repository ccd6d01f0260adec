"""`mavconform gcs upload` says what reading the file left out before it uploads: a .plan
whose version-1 geoFence / rallyPoints block was skipped (as QGroundControl skips it) clears
the vehicle's fence and rally points, and the user is told so, one warning line per note."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR, load_plan

from ..vehicle_process import vehicle_process

V1 = Path(__file__).parent / "fixtures" / "fence_rally_v1.plan"
DEMO = SAMPLES_DIR / "demo.plan"


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("mavconform: warning: ")]


@pytest.mark.udp
def test_skipped_blocks_are_warned_about_and_the_upload_clears_them(tmp_path: Path, capsys) -> None:
    back = tmp_path / "back.plan"
    with vehicle_process() as port:
        target = f"udp:127.0.0.1:{port}"
        assert main(["gcs", "upload", "--target", target, str(DEMO)]) == 0
        assert _warnings(capsys.readouterr().err) == []            # nothing skipped: silent
        assert main(["gcs", "upload", "--target", target, str(V1)]) == 0
        out, err = capsys.readouterr()
        assert main(["gcs", "download", "--target", target, str(back)]) == 0
    warnings = _warnings(err)
    assert warnings == [f"mavconform: warning: {note}" for note in load_plan(V1).notes]
    assert [w.split(": ")[3] for w in warnings] == ["$.geoFence", "$.rallyPoints"]
    assert all(f"warning: {V1}: " in w and "clears the vehicle's" in w for w in warnings)
    assert "upload fence: success" in out and "upload rally: success" in out
    assert load_plan(back).fence == [] and load_plan(back).rally == []   # what the warning said


@pytest.mark.udp
def test_the_warning_comes_before_any_traffic(capsys) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as silent:   # a target that never answers
        silent.bind(("127.0.0.1", 0))
        target = f"udp:127.0.0.1:{silent.getsockname()[1]}"
        code = main(["gcs", "upload", "--target", target, "--heartbeat-timeout", "0.2", str(V1)])
    _, err = capsys.readouterr()
    assert code == 1 and "target unresponsive" in err
    assert len(_warnings(err)) == 2 and err.index("warning:") < err.index("target unresponsive")
