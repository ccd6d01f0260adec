import json
import time

import pymavlink.dialects.v20.common as common
import pytest
from mcap.reader import make_reader

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import (CaptureRecord, FaultModel, McapCapture, SimClock, SimNetwork,
                                           UdpDriver)
from mavconform.reference_impl.net.capture import address_label, json_safe
from mavconform.reference_impl.wire import FrameEncoder

from .nodes import EchoNode, PingNode, RecorderNode, SenderNode

EPOCH = 1_767_225_600.0          # what the tests' wall clocks say: 2026-01-01T00:00:00Z
EPOCH_NS = 1_767_225_600 * 10**9


def read_all(path):
    """(summary, [(topic, body, message)]) in the order they were written."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = [(ch.topic, json.loads(msg.data), msg)
                    for _, ch, msg in reader.iter_messages(log_time_order=False)]
    return summary, messages


def sim_pair(seed=0, wall_epoch=EPOCH, **faults):
    net = SimNetwork(seed=seed, clock=SimClock(wall_epoch=wall_epoch))
    a, b = RecorderNode(), EchoNode()
    net.add_node("gcs", a)
    net.add_node("vehicle", b)
    net.connect("gcs", "vehicle", **faults)
    return net, a, b


def test_capture_of_a_sim_exchange(tmp_path):
    enc = FrameEncoder(255, 190, dialect=common)
    heartbeat = enc.encode(common.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    count = enc.encode(common.MAVLink_mission_count_message(1, 1, 3, 0))
    item = enc.encode(common.MAVLink_mission_item_int_message(
        1, 1, 0, 0, 16, 0, 1, float("nan"), float("inf"), 0.0, 0.0, 0, 0, 10.0, 0))
    net, gcs, _ = sim_pair(seed=1)
    path = tmp_path / "run.mcap"
    with McapCapture(path, dialect=common) as capture:
        net.add_capture(capture)
        net.clock.advance_to(1.5)
        gcs.send(heartbeat, "vehicle")
        gcs.send(count + item, "vehicle")   # two frames in one datagram
        gcs.send(b"\x00garbage", "vehicle")
        net.run_until_quiet(timeout=1.0)
    # 3 datagrams each way, each written once (its tx; the rx is the same frame)
    assert capture.messages == 2 * 4

    summary, messages = read_all(path)
    channels = {c.topic: c for c in summary.channels.values()}
    assert set(channels) == {"gcs -> vehicle", "vehicle -> gcs"}
    assert channels["gcs -> vehicle"].metadata == {"sender": "gcs", "receiver": "vehicle"}
    assert channels["vehicle -> gcs"].metadata == {"sender": "vehicle", "receiver": "gcs"}
    assert {c.message_encoding for c in channels.values()} == {"json"}
    assert summary.statistics.message_count == 8
    schema = next(iter(summary.schemas.values()))
    assert schema.encoding == "jsonschema" and json.loads(schema.data)["type"] == "object"
    # wall-clock log time (the SimClock's epoch + virtual seconds), driver-time publish time
    assert {m.log_time for _, _, m in messages} == {EPOCH_NS + 1_500_000_000}
    assert {m.publish_time for _, _, m in messages} == {1_500_000_000}

    bodies = [b for topic, b, _ in messages if topic == "gcs -> vehicle"]
    assert [b["msg"] for b in bodies] == ["HEARTBEAT", "MISSION_COUNT", "MISSION_ITEM_INT",
                                          "DECODE_ERROR"]
    hb, cnt, it, bad = bodies
    assert hb["fields"]["type"] == 6 and hb["sysid"] == 255 and hb["compid"] == 190
    assert hb["signature"] == "unsigned" and hb["error"] is None
    assert hb["raw"] == heartbeat.hex() and hb["time"] == 1.5
    assert cnt["fields"]["count"] == 3 and cnt["frame_index"] == 0
    assert it["frame_index"] == 1
    assert it["fields"]["param1"] == "NaN" and it["fields"]["param2"] == "Infinity"
    assert it["fields"]["z"] == 10.0
    assert bad["error"] and bad["raw"] == b"\x00garbage".hex() and bad["fields"] == {}
    assert {b["kind"] for _, b, _ in messages} == {"tx"}


def test_json_safe():
    assert json_safe([float("-inf"), b"\x01\xff", (1, 2.5), None, "s"]) == \
        ["-Infinity", "01ff", [1, 2.5], None, "s"]


def test_address_labels():
    assert address_label("gcs") == "gcs"
    assert address_label(("127.0.0.1", 14550)) == "127.0.0.1:14550"
    assert address_label(("::1", 14550, 0, 0)) == "[::1]:14550"


def test_records_without_a_wall_stamp_take_the_injected_wall_clock(tmp_path):
    path = tmp_path / "c.mcap"
    walls = iter([EPOCH + 0.25, EPOCH + 0.5])
    with McapCapture(path, dialect=common, wall_clock=lambda: next(walls)) as capture:
        capture(CaptureRecord(7.0, "gcs", "vehicle", b"a", "tx"))
        capture(CaptureRecord(8.0, "gcs", "vehicle", b"b", "tx"))
        capture(CaptureRecord(9.0, "gcs", "vehicle", b"c", "tx", wall=EPOCH + 2.0))  # stamped
    _, messages = read_all(path)
    assert [(m.log_time, m.publish_time) for _, _, m in messages] == [
        (EPOCH_NS + 250_000_000, 7 * 10**9), (EPOCH_NS + 500_000_000, 8 * 10**9),
        (EPOCH_NS + 2 * 10**9, 9 * 10**9)]


def test_a_lost_datagram_is_on_its_direction_once_and_on_the_lost_channel(tmp_path):
    """Sent and lost: its tx on "a -> b", its loss on "a -> b (lost)". A copy the link made
    (here a duplicate) is an arrival nobody sent: written once, as rx."""
    net, gcs, vehicle = sim_pair(a_to_b=FaultModel(duplicate=1.0), b_to_a=FaultModel(loss=1.0))
    path = tmp_path / "lost.mcap"
    with McapCapture(path, dialect=common) as capture:
        net.add_capture(capture)
        gcs.send(b"twice", "vehicle")        # duplicated; the vehicle echoes both copies
        net.run_until_quiet(timeout=1.0)
    assert vehicle.payloads == [b"twice", b"twice"] and gcs.received == []
    summary, messages = read_all(path)
    got = sorted((topic, b["kind"], bytes.fromhex(b["raw"])) for topic, b, _ in messages)
    assert got == [
        ("gcs -> vehicle", "rx", b"twice"),              # the duplicate
        ("gcs -> vehicle", "tx", b"twice"),              # the datagram the GCS sent
        ("vehicle -> gcs", "tx", b"twice"),              # each echo, sent ...
        ("vehicle -> gcs", "tx", b"twice"),
        ("vehicle -> gcs (lost)", "drop", b"twice"),     # ... and lost
        ("vehicle -> gcs (lost)", "drop", b"twice"),
    ]
    lost = next(c for c in summary.channels.values() if c.topic == "vehicle -> gcs (lost)")
    assert lost.metadata == {"sender": "vehicle", "receiver": "gcs", "lost": "true"}


def test_a_loss_of_a_datagram_never_seen_sent_is_only_on_the_lost_channel(tmp_path):
    """An outside peer's datagram eaten by an incoming fault: its drop is all there is."""
    path = tmp_path / "drop.mcap"
    with McapCapture(path, dialect=common, wall_clock=lambda: EPOCH) as capture:
        capture(CaptureRecord(0.25, ("127.0.0.1", 5), ("127.0.0.1", 6), b"", "drop"))
    _, messages = read_all(path)
    assert len(messages) == 1
    topic, body, message = messages[0]
    assert topic == "127.0.0.1:5 -> 127.0.0.1:6 (lost)"
    assert message.log_time == EPOCH_NS and message.publish_time == 250_000_000
    assert body["kind"] == "drop" and body["msg"] == "DECODE_ERROR"


class FixedWallClock:
    """Real monotonic time (the UDP driver waits on it), a wall clock that never moves."""

    def now(self) -> float:
        return time.monotonic()

    def wall(self) -> float:
        return EPOCH


@pytest.mark.udp
def test_two_nodes_on_one_udp_driver_each_frame_once(tmp_path):
    """A built-in target: tester and vehicle on one driver over loopback. Each datagram is
    reported sent and received; the capture holds it once, stamped by the driver's clock."""
    path = tmp_path / "udp.mcap"
    with UdpDriver(clock=FixedWallClock()) as driver, McapCapture(path, dialect=common) as capture:
        echo = EchoNode()
        echo_at = driver.add_node(echo)
        sender = SenderNode(echo_at, count=5, interval=0.0)
        sender_at = driver.add_node(sender)
        driver.add_capture(capture)
        assert driver.run_until(lambda: len(sender.received) == 5, timeout=5.0)
    summary, messages = read_all(path)
    up = f"127.0.0.1:{sender_at[1]} -> 127.0.0.1:{echo_at[1]}"
    down = f"127.0.0.1:{echo_at[1]} -> 127.0.0.1:{sender_at[1]}"
    assert {c.topic for c in summary.channels.values()} == {up, down}
    for topic in (up, down):
        raws = sorted(bytes.fromhex(b["raw"]) for t, b, _ in messages if t == topic)
        assert raws == [b"%d" % i for i in range(5)]
    assert {b["kind"] for _, b, _ in messages} == {"tx"}
    assert {m.log_time for _, _, m in messages} == {EPOCH_NS}


def test_markers_are_foxglove_logs_at_wall_time(tmp_path):
    net, gcs, _ = sim_pair(wall_epoch=EPOCH)
    path = tmp_path / "m.mcap"
    with McapCapture(path, dialect=common, wall_clock=lambda: EPOCH + 99.0) as capture:
        net.add_capture(capture)
        net.clock.advance_to(2.0)
        capture.mark("clause MISSION.UPLOAD.1", clock=net.clock)
        gcs.send(b"x", "vehicle")
        net.run_until_quiet(timeout=1.0)
        capture.mark("after", level="warning")          # no clock: the capture's wall clock
        with pytest.raises(ValueError, match="level"):
            capture.mark("x", level="loud")
    summary, messages = read_all(path)
    (markers,) = [c for c in summary.channels.values() if c.topic == "markers"]
    assert markers.message_encoding == "json"
    schema = summary.schemas[markers.schema_id]
    assert schema.name == "foxglove.Log" and schema.encoding == "jsonschema"
    got = [(b["message"], b["level"], b["timestamp"], m.log_time, m.publish_time)
           for t, b, m in messages if t == "markers"]
    assert got == [
        ("clause MISSION.UPLOAD.1", 2, {"sec": int(EPOCH) + 2, "nsec": 0}, EPOCH_NS + 2 * 10**9, 2 * 10**9),
        ("after", 3, {"sec": int(EPOCH) + 99, "nsec": 0}, EPOCH_NS + 99 * 10**9, EPOCH_NS + 99 * 10**9)]
    assert all(b["name"] == "mavconform" for t, b, _ in messages if t == "markers")
    assert [t for t, _, _ in messages] == ["markers", "gcs -> vehicle", "vehicle -> gcs", "markers"]


def lossy_capture(path, seed):
    fault = FaultModel(loss=0.1, duplicate=0.05, reorder=0.1, delay=0.01, jitter=0.02, corrupt=0.02)
    net = SimNetwork(seed=seed)
    ping, echo = PingNode("b", rounds=30), EchoNode()
    net.add_node("a", ping)
    net.add_node("b", echo)
    net.connect("a", "b", a_to_b=fault, b_to_a=fault)
    with McapCapture(path) as capture:   # default wall clock: unused, the driver stamps
        net.add_capture(capture)
        capture.mark("start", clock=net.clock)
        assert net.run_until(lambda: ping.done == 30, timeout=60.0)
        capture.mark("done", clock=net.clock)
    return path.read_bytes()


def test_seeded_virtual_capture_is_byte_identical(tmp_path):
    first = lossy_capture(tmp_path / "1.mcap", seed=3)
    assert first == lossy_capture(tmp_path / "2.mcap", seed=3)
    assert first != lossy_capture(tmp_path / "3.mcap", seed=4)
    _, messages = read_all(tmp_path / "1.mcap")
    assert {t for t, _, _ in messages} == {"a -> b", "b -> a", "a -> b (lost)", "b -> a (lost)", "markers"}
    assert all(m.log_time >= EPOCH_NS for _, _, m in messages)   # SimClock's default epoch


def test_unwritable_path_is_usage_error(tmp_path):
    with pytest.raises(UsageError, match="missing"):
        McapCapture(tmp_path / "missing" / "x.mcap", dialect=common)


def test_closed_capture_refuses_records_and_marks(tmp_path):
    capture = McapCapture(tmp_path / "c.mcap", dialect=common)
    capture.close()
    capture.close()
    with pytest.raises(ValueError):
        capture(CaptureRecord(0.0, "a", "b", b"", "tx"))
    with pytest.raises(ValueError):
        capture.mark("late")
