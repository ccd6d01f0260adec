"""Sample messages and the signing key the codec tests share (test_codec.py, test_codec_decoding.py)."""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.wire.codec import FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink
from mavconform.reference_impl.wire.signing import SigningKey

FIXED_WALL = 1_700_000_000.0
KEY = SigningKey(bytes(range(32)), link_id=7)


# --- sample messages ---------------------------------------------------------------------------

def mission_item_int(seq: int = 3, mission_type: int = 0) -> Any:
    return mavlink.MAVLink_mission_item_int_message(
        target_system=1, target_component=1, seq=seq, frame=6, command=16, current=0,
        autocontinue=1, param1=0.5, param2=2.0, param3=0.0, param4=-1.25,
        x=473_977_420, y=85_455_940, z=15.5, mission_type=mission_type)


def sample_messages() -> list[Any]:
    return [
        mission_item_int(),
        mission_item_int(seq=1000, mission_type=2),
        mavlink.MAVLink_mission_count_message(1, 1, 12, mission_type=1, opaque_id=0xDEADBEEF),
        mavlink.MAVLink_mission_request_int_message(255, 190, 7, mission_type=2),
        mavlink.MAVLink_mission_ack_message(255, 190, 0, mission_type=0, opaque_id=42),
        mavlink.MAVLink_mission_current_message(4, total=9, mission_state=3, mission_mode=1,
                                                mission_id=11, fence_id=0, rally_points_id=13),
        mavlink.MAVLink_mission_clear_all_message(1, 1, mission_type=255),
        mavlink.MAVLink_mission_item_reached_message(0),
        mavlink.MAVLink_command_long_message(1, 1, 400, 0, 1.0, 0, 0, 0, 0, 0, 0),
        mavlink.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3),
    ]


def v1_capable(msgs: list[Any]) -> list[Any]:
    return [m for m in msgs if m.id <= 255]


def fields_of(msg: Any) -> dict[str, Any]:
    return {name: getattr(msg, name) for name in msg.get_fieldnames()}


def encoded(msg: Any, **kw: Any) -> bytes:
    return FrameEncoder(1, 1, **kw).encode(msg)
