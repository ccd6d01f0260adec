"""Drive one sans-IO engine by hand: feed it real frames from a chosen sender, read its sends.

Frames are built by encoding and decoding through the real codec, so a test exercises the
same path as the wire.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.mission.actions import Finished, Send
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d

GCS = (255, 190)
OTHER_GCS = (254, 190)
VEHICLE = (1, 1)


class Script:
    def __init__(self, engine: Any) -> None:
        self.engine = engine
        self.now = 0.0
        self._encoders: dict[tuple[int, int, int], FrameEncoder] = {}
        self._decoder = FrameDecoder()
        self.sent: list[Send] = []
        self.sent_at: list[tuple[float, Any]] = []   # (time, message) of every send
        self.results: list[Any] = []

    def frame(self, msg: Any, src: tuple[int, int], version: int = 2):
        key = (*src, version)
        enc = self._encoders.get(key)
        if enc is None:
            enc = self._encoders[key] = FrameEncoder(src[0], src[1], version=version)
        (frame,) = self._decoder.feed(enc.encode(msg))
        return frame

    def feed(self, msg: Any, src: tuple[int, int] = GCS, version: int = 2) -> list[Any]:
        return self._take(self.engine.handle(self.frame(msg, src, version), self.now))

    def call(self, actions: list[Any]) -> list[Any]:
        return self._take(actions)

    def advance(self, dt: float) -> list[Any]:
        """Move time forward by dt, firing every deadline on the way (in order)."""
        end = self.now + dt
        out: list[Any] = []
        for _ in range(100_000):
            nd = self.engine.next_deadline()
            if nd is None or nd > end:
                break
            self.now = max(self.now, nd)
            out += self._take(self.engine.poll(self.now))
        self.now = end
        return out

    def _take(self, actions: list[Any]) -> list[Any]:
        msgs = []
        for a in actions:
            if isinstance(a, Send):
                self.sent.append(a)
                self.sent_at.append((self.now, a.msg))
                msgs.append(a.msg)
            elif isinstance(a, Finished):
                self.results.append(a.result)
                msgs.append(a)
        return msgs


def names(msgs: list[Any]) -> list[str]:
    return [m.get_type() if hasattr(m, "get_type") else type(m).__name__ for m in msgs]


def only(msgs: list[Any], name: str) -> list[Any]:
    return [m for m in msgs if hasattr(m, "get_type") and m.get_type() == name]


def count(n: int, mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_count_message(target[0], target[1], n, mission_type, 0)


def ack(result: int, mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_ack_message(target[0], target[1], result, mission_type, 0)


def request_list(mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_request_list_message(target[0], target[1], mission_type)


def request_int(seq: int, mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_request_int_message(target[0], target[1], seq, mission_type)


def request_float(seq: int, mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_request_message(target[0], target[1], seq, mission_type)


def clear_all(mission_type: int = 0, target=VEHICLE) -> Any:
    return d.MAVLink_mission_clear_all_message(target[0], target[1], mission_type)
