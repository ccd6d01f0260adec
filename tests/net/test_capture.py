import json

import pymavlink.dialects.v20.common as common
import pytest
from mcap.reader import make_reader

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import CaptureRecord, McapCapture, SimNetwork
from mavconform.reference_impl.net.capture import json_safe
from mavconform.reference_impl.wire import FrameEncoder

from .nodes import EchoNode, RecorderNode


def read_all(path):
    with open(path, "rb") as f:
        reader = make_reader(f)
        summary = reader.get_summary()
        messages = [(ch.topic, ch.message_encoding, schema.encoding, msg.log_time,
                     json.loads(msg.data)) for schema, ch, msg in reader.iter_messages()]
    return summary, messages


def test_capture_of_a_sim_exchange(tmp_path):
    enc = FrameEncoder(255, 190, dialect=common)
    heartbeat = enc.encode(common.MAVLink_heartbeat_message(6, 8, 0, 0, 0, 3))
    count = enc.encode(common.MAVLink_mission_count_message(1, 1, 3, 0))
    item = enc.encode(common.MAVLink_mission_item_int_message(
        1, 1, 0, 0, 16, 0, 1, float("nan"), float("inf"), 0.0, 0.0, 0, 0, 10.0, 0))
    gcs, vehicle = RecorderNode(), EchoNode()
    net = SimNetwork(seed=1)
    net.add_node("gcs", gcs)
    net.add_node("vehicle", vehicle)
    net.connect("gcs", "vehicle")
    path = tmp_path / "run.mcap"
    with McapCapture(path, dialect=common) as capture:
        net.add_capture(capture)
        net.clock.advance_to(1.5)
        gcs.send(heartbeat, "vehicle")
        gcs.send(count + item, "vehicle")   # two frames in one datagram
        gcs.send(b"\x00garbage", "vehicle")
        net.run_until_quiet(timeout=1.0)
    # 3 datagrams each way, tx + rx each: frames 1 + 2 + 1 per record
    assert capture.messages == 4 * 4

    summary, messages = read_all(path)
    topics = {c.topic for c in summary.channels.values()}
    assert topics == {"gcs->vehicle", "vehicle->gcs"}
    assert summary.statistics.message_count == 16
    assert {(m[1], m[2]) for m in messages} == {("json", "jsonschema")}
    assert all(m[3] == 1_500_000_000 for m in messages)
    schema = json.loads(next(iter(summary.schemas.values())).data)
    assert schema["type"] == "object"

    bodies = [m[4] for m in messages if m[0] == "gcs->vehicle" and m[4]["kind"] == "tx"]
    assert [b["msg"] for b in bodies] == ["HEARTBEAT", "MISSION_COUNT", "MISSION_ITEM_INT",
                                          "DECODE_ERROR"]
    hb, cnt, it, bad = bodies
    assert hb["fields"]["type"] == 6 and hb["sysid"] == 255 and hb["compid"] == 190
    assert hb["signature"] == "unsigned" and hb["error"] is None
    assert hb["raw"] == heartbeat.hex()
    assert cnt["fields"]["count"] == 3 and cnt["frame_index"] == 0
    assert it["frame_index"] == 1
    assert it["fields"]["param1"] == "NaN" and it["fields"]["param2"] == "Infinity"
    assert it["fields"]["z"] == 10.0
    assert bad["error"] and bad["raw"] == b"\x00garbage".hex() and bad["fields"] == {}
    kinds = {m[4]["kind"] for m in messages}
    assert kinds == {"tx", "rx"}


def test_json_safe():
    assert json_safe([float("-inf"), b"\x01\xff", (1, 2.5), None, "s"]) == \
        ["-Infinity", "01ff", [1, 2.5], None, "s"]


def test_drop_and_empty_datagram_are_recorded(tmp_path):
    path = tmp_path / "drop.mcap"
    with McapCapture(path, dialect=common) as capture:
        capture(CaptureRecord(0.25, ("127.0.0.1", 5), ("127.0.0.1", 6), b"", "drop"))
    _, messages = read_all(path)
    assert len(messages) == 1
    topic, _, _, log_time, body = messages[0]
    assert topic == "127.0.0.1:5->127.0.0.1:6"
    assert log_time == 250_000_000
    assert body["kind"] == "drop" and body["msg"] == "DECODE_ERROR"


def test_unwritable_path_is_usage_error(tmp_path):
    with pytest.raises(UsageError, match="missing"):
        McapCapture(tmp_path / "missing" / "x.mcap", dialect=common)


def test_closed_capture_refuses_records(tmp_path):
    capture = McapCapture(tmp_path / "c.mcap", dialect=common)
    capture.close()
    capture.close()
    with pytest.raises(ValueError):
        capture(CaptureRecord(0.0, "a", "b", b"", "tx"))
