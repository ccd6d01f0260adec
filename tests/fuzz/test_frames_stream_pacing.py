"""The frame fuzzer never overruns a stream link's queue, and paces a TCP target.

A stream link drops whole frames when its queue is full (a serial line holds half a second
of line time), and INAV's SITL drops bytes when a TCP burst outruns its 2048-byte receive
ring: either way the target would read a stream the admission model did not, and a plan
change would be the fuzzer's doing. So a batch goes out a datagram at a time, each waiting
for room, and a TCP target gets the bytes of a 57600-baud radio.
"""

from __future__ import annotations

import subprocess
import sys

from mavconform.fuzz.frames.rig import Rig


class _Line:
    """A stream link that sends `rate` bytes per driver round and drops what overruns it."""

    def __init__(self, max_queued: int, rate: int) -> None:
        self.max_queued, self.rate, self.up = max_queued, rate, True
        self.bytes_per_second = float(rate)
        self.buffer, self.wire, self.dropped = bytearray(), bytearray(), 0

    @property
    def queued(self) -> int:
        return len(self.buffer)

    def take(self, datagrams: list[bytes]) -> None:
        for d in datagrams:
            if len(self.buffer) + len(d) > self.max_queued:
                self.dropped += 1
            else:
                self.buffer += d
        datagrams.clear()


class _Driver:
    def __init__(self, line: _Line, station) -> None:
        self.line, self.station, self.rounds = line, station, 0

    def run_until(self, condition, timeout: float) -> bool:
        for _ in range(1 + int(timeout * 10)):       # bounded, like the real driver
            self.rounds += 1
            self.line.take(self.station.outbox)
            sent = self.line.buffer[:self.line.rate]
            self.line.wire += sent
            del self.line.buffer[:len(sent)]
            if condition():
                return True
        return False


class _Station:
    def __init__(self) -> None:
        self.outbox: list[bytes] = []


def test_a_batch_larger_than_the_queue_goes_out_whole_and_in_order():
    rig = Rig.__new__(Rig)
    rig.station = _Station()
    line = _Line(max_queued=200, rate=50)
    rig.driver = _Driver(line, rig.station)
    batch = [bytes([i]) * 37 for i in range(40)]     # 1480 bytes through a 200-byte queue
    rig.station.outbox = list(batch)
    rig._flush_stream(line)
    assert line.dropped == 0
    assert bytes(line.wire) == b"".join(batch) and line.queued == 0


def test_handing_the_whole_batch_over_at_once_would_drop_frames():
    """What the rig did before: the same batch handed to the same queue in one go."""
    line = _Line(max_queued=200, rate=50)
    line.take([bytes([i]) * 37 for i in range(40)])
    assert line.dropped > 0


def test_a_tcp_target_is_fuzzed_clean(tmp_path):
    """The reference vehicle served over TCP: a frames campaign through the paced stream
    path finds nothing."""
    vehicle = subprocess.Popen([sys.executable, "-m", "mavconform", "vehicle", "--listen", "tcpin:0", "--quiet",
                                "--duration", "120"], stdout=subprocess.PIPE, text=True)
    try:
        where = vehicle.stdout.readline().split("listening on ")[1].split()[0]
        done = subprocess.run([sys.executable, "-m", "mavconform", "fuzz", "--target", where.replace("tcpin:", "tcp:"),
                               "--mode", "frames", "--examples", "2", "--findings", str(tmp_path / "f"),
                               "--report-dir", str(tmp_path / "r"), "-q"],
                              capture_output=True, text=True, timeout=120)
    finally:
        vehicle.kill()
        vehicle.wait(timeout=10)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "findings: none" in done.stdout
