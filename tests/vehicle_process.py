"""A `mavconform vehicle` in its own process, as a GCS or a CI job would meet it."""

from __future__ import annotations

import contextlib
import subprocess
import sys
from typing import Iterator

LISTENING = "listening on udp:127.0.0.1:"


@contextlib.contextmanager
def vehicle_process(*options: str) -> Iterator[int]:
    """Start `mavconform vehicle --listen udp:127.0.0.1:0 --duration 60 OPTIONS`; yield the
    port it printed; kill it afterwards. The first line is read without a timeout: the
    process exits after --duration at the latest."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "mavconform", "vehicle", "--listen", "udp:127.0.0.1:0",
         "--duration", "60", *options],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert LISTENING in line, line + proc.stderr.read()
        yield int(line.split(LISTENING)[1].split()[0])
    finally:
        proc.kill()
        proc.wait(timeout=10)
