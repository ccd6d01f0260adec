"""Issue 24: stream links. Frames cut from a byte stream however it is split, a paced serial
line, a TCP link that is dropped and comes back, and the reference vehicle behind a
pseudo-terminal; every wait is the driver's, bounded."""

from __future__ import annotations

import os
import socket

from hypothesis import given, settings, strategies as st

from mavconform.conformance.harness import tester_node
from mavconform.reference_impl.net import UdpDriver
from mavconform.reference_impl.net import tcp_link
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.net.stream_framer import StreamFramer
from mavconform.reference_impl.net.stream_link import StreamLink
from mavconform.reference_impl.net.uri import parse_link_uri
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire import FrameEncoder
from mavconform.reference_impl.wire.codec import default_dialect

_ENC = FrameEncoder(1, 1)
_MAV = default_dialect()
FRAMES = [_ENC.encode(_MAV.MAVLink_mission_count_message(1, 1, n, 0)) for n in range(1, 6)] + \
         [_ENC.encode(_MAV.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3))]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(FRAMES), st.binary(max_size=12).filter(lambda b: 0xFD not in b
                                                                                   and 0xFE not in b)),
                min_size=1, max_size=12),
       st.lists(st.integers(1, 40), min_size=1, max_size=30))
def test_frames_come_out_whole_however_the_stream_is_split(pieces, cuts):
    stream = b"".join(noise + frame for frame, noise in pieces)
    framer, out, at = StreamFramer(), [], 0
    for cut in cuts * (len(stream) // sum(cuts) + 1):
        out += framer.feed(stream[at:at + cut])
        at += cut
        if at >= len(stream):
            break
    assert out == [frame for frame, _ in pieces]
    assert framer.skipped == sum(len(noise) for _, noise in pieces) and framer.bad == 0


def test_a_damaged_frame_is_passed_on_bad_and_the_next_one_found():
    damaged = bytearray(FRAMES[0])
    damaged[-1] ^= 0xFF
    framer = StreamFramer()
    out = framer.feed(bytes(damaged) + b"\x00\x01" + FRAMES[1])
    assert out == [bytes(damaged), FRAMES[1]] and framer.bad == 1 and framer.skipped == 2


def test_a_serial_line_is_paced_at_its_baud_rate_in_injected_time():
    """5760 bytes/s at 57600 baud: what is written by time t is at most the line's worth."""
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)
    link = StreamLink("serial:test", "peer", "here", bytes_per_second=5760.0)
    link._connected(write_end, 0.0, "test pipe")
    for frame in FRAMES * 20:
        assert link.send(frame, 0.0)
    queued = sum(len(f) for f in FRAMES) * 20
    t = 0.0
    for _ in range(10_000):
        link.flush(t)
        assert link.written <= 5760.0 * t + 5760.0 * 0.005 + 1
        if link.written == queued:
            break
        t = link.next_deadline()
    assert link.written == queued and abs(t - queued / 5760.0) < 0.01
    link.close()
    os.close(read_end)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_dropped_tcp_link_is_reported_and_reconnected(monkeypatch):
    monkeypatch.setattr(tcp_link, "RETRY_DELAYS", (0.05, 0.05, 0.1))
    with UdpDriver() as driver:
        vehicle = VehicleNode(VehicleConfig())
        peer, _ = attach(driver, vehicle, parse_link_uri("tcpin:0", role="listen"), listen=True)
        vehicle.endpoint.add_address(peer)
        server = driver.stream_of(vehicle)
        tester = tester_node.TesterNode("t", 245, 190)
        target, _ = attach(driver, tester, parse_link_uri(f"tcp:127.0.0.1:{server.address[1]}"))
        tester.endpoint.add_address(target)
        client = driver.stream_of(tester)
        assert driver.run_until(lambda: any(f.msg._type == "HEARTBEAT" for _, f in tester.inbox), timeout=5)
        server._lost(driver.clock.now(), "dropped by the test")     # the vehicle hangs up
        assert driver.run_until(lambda: client.generation == 2 and server.up, timeout=5)
        heard = len(tester.inbox)
        assert driver.run_until(lambda: len(tester.inbox) > heard, timeout=5)   # frames flow again
        events = [e for _, e in client.history]
        assert events[0] == "connected" and "closed by the peer" in events and events[-1] == "connected"
        assert client.describe()["connections"] == 2


def test_a_tcp_target_that_never_listens_is_given_up_on_bounded(monkeypatch):
    monkeypatch.setattr(tcp_link, "RETRY_DELAYS", (0.02, 0.02, 0.02))
    with UdpDriver() as driver:
        tester = tester_node.TesterNode("t", 245, 190)
        attach(driver, tester, parse_link_uri(f"tcp:127.0.0.1:{_free_port()}"))
        link = driver.stream_of(tester)
        assert driver.run_until(lambda: link.gave_up, timeout=5)
        assert not link.up and [e for _, e in link.history][-1] == "gave up after 3 attempts"
        assert driver.run_until(lambda: False, timeout=0.1) is False   # and the loop still runs


def test_the_reference_vehicle_behind_a_pty_answers_over_the_device_it_names():
    with UdpDriver() as driver:
        vehicle = VehicleNode(VehicleConfig())
        peer, _ = attach(driver, vehicle, parse_link_uri("pty:921600", role="listen"), listen=True)
        vehicle.endpoint.add_address(peer)
        device = driver.stream_of(vehicle).device
        tester = tester_node.TesterNode("t", 245, 190)
        target, _ = attach(driver, tester, parse_link_uri(f"serial:{device}:921600"))
        tester.endpoint.add_address(target)
        assert driver.run_until(lambda: any(f.msg._type == "HEARTBEAT" for _, f in tester.inbox), timeout=5)
        tester.send(_MAV.MAVLink_mission_request_list_message(1, 1, 0))
        assert driver.run_until(lambda: any(f.msg._type == "MISSION_COUNT" for _, f in tester.inbox), timeout=5)
        assert driver.receive_queue(tester).drops is None   # a serial line does not count them


def test_a_paced_line_nobody_reads_waits_for_the_kernel_not_in_a_busy_loop():
    """The pty's buffer fills when nobody reads it: the link then has no deadline (which
    would wake the driver at once, again and again) and waits to be writable instead."""
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)
    link = StreamLink("serial:test", "peer", "here", bytes_per_second=1e9)
    link.max_queued = 1 << 24
    link._connected(write_end, 0.0, "test pipe")
    t = 0.0
    for _ in range(100_000):   # fill the pipe
        link.send(b"x" * 4096, t)
        link.flush(t)
        t += 1.0
        if link.wanted(t)[0][2]:   # it waits to write
            break
    assert link.next_deadline() is None and link.wanted(t) == [(write_end, True, True)]
    os.read(read_end, 1 << 20)   # someone reads: what waited goes out
    link.flush(t)
    assert link.wanted(t) == [(write_end, True, False)] and link.written == 4096 * (t)
    link.close()
    os.close(read_end)
