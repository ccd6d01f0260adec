"""A fuzz fleet on a real Redis (issue 27): campaigns on separate processes (machines, in a real
fleet) share their examples through `--database redis://HOST:PORT`, so a case one finds is the
first thing every other one replays.

The test starts its own redis-server, bound to 127.0.0.1 on a port the OS picked, keeping
nothing on disk, and stops it. `.ci/run` installs Debian's redis-server; where the binary is
missing the test skips and says so. Three campaigns, each with its own seed, findings folder
and reports, against the same planted bug (mutant:commits-on-cancel): the first searches and
finds it; the second, with another seed, replays it first (found within its first examples);
so does a third, later one.
"""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

REDIS = shutil.which("redis-server")
pytestmark = pytest.mark.skipif(REDIS is None, reason="redis-server is not installed (.ci/run installs Debian's)")
TARGET = "mutant:commits-on-cancel"
START_WITHIN = 5.0       # s for redis-server to answer PING


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def redis_url(tmp_path):
    import redis
    for _ in range(3):          # bounded: a port taken between the probe and the start is tried again
        port = _free_port()
        proc = subprocess.Popen([REDIS, "--bind", "127.0.0.1", "--port", str(port), "--save", "", "--appendonly", "no",
                                 "--dir", str(tmp_path), "--protected-mode", "yes"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            if _ready(proc):
                client = redis.Redis(host="127.0.0.1", port=port, socket_connect_timeout=1.0)
                assert client.ping()
                client.close()
                yield f"redis://127.0.0.1:{port}"
                return
        finally:
            proc.terminate()
            proc.wait(timeout=10)
    pytest.fail("redis-server did not start on a free port in three tries")


def _ready(proc: subprocess.Popen) -> bool:
    """Whether redis-server says it accepts connections within START_WITHIN (its log, read with
    a bounded wait; False if it exits first, e.g. the port was taken)."""
    import selectors
    import time
    deadline = time.monotonic() + START_WITHIN
    with selectors.DefaultSelector() as sel:
        sel.register(proc.stdout, selectors.EVENT_READ)
        while (left := deadline - time.monotonic()) > 0:
            if not sel.select(timeout=left):
                return False
            line = proc.stdout.readline()
            if not line:
                return False
            if "Ready to accept connections" in line:
                return True
    return False


def _campaign(tmp_path: Path, name: str, seed: int, database: str, examples: int = 400, found: bool = True) -> dict:
    proc = subprocess.run([sys.executable, "-m", "mavconform", "fuzz", "--target", TARGET, "--examples", str(examples),
                           "--seed", str(seed), "--database", database, "--findings", str(tmp_path / name / "findings"),
                           "--report-dir", str(tmp_path / name / "reports"), "-q"],
                          capture_output=True, text=True, timeout=240)
    assert proc.returncode == (1 if found else 0), proc.stdout + proc.stderr          # 1: a finding
    return json.loads((tmp_path / name / "reports" / "fuzz.json").read_text())["fuzz"]


def test_a_case_one_campaign_finds_is_the_first_every_other_replays(redis_url, tmp_path) -> None:
    first = _campaign(tmp_path, "first", 1, redis_url)
    assert len(first["findings"]) == 1
    found = first["findings"][0]
    assert first["examples"] > 20                                   # it had to search
    for name, seed in (("second", 2), ("third", 3)):
        other = _campaign(tmp_path, name, seed, redis_url)
        assert [f["name"] for f in other["findings"]] == [found["name"]]
        assert other["examples"] <= 3, f"{name} campaign searched ({other['examples']} examples) instead of replaying"
        assert other["findings"][0]["reproduced"] is True
    # the same seed without the fleet finds nothing in a budget of 3 examples: the replay was the fleet's
    alone = _campaign(tmp_path, "alone", 2, "none", examples=3, found=False)
    assert alone["findings"] == []
