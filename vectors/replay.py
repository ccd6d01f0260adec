"""Replaying an exchange vector's GCS side against a target, and where its replies differ.

What is sent: every frame the recorded GCS sent that reached the vehicle (frames the link
lost are not sent), at the recorded times (times `--time-scale` over UDP) from a node with
the recorded GCS's ids. Against a target whose ids differ from the recorded vehicle's, the
frames' target_system / target_component are rewritten to the target's (and re-encoded);
otherwise the recorded bytes go out as they are.

What is compared: the target's frames against every frame the recorded vehicle sent (lost
or not: the target sends them either way), in order, message by message and field by
field, leaving out the streams (HEARTBEAT, GLOBAL_POSITION_INT, MISSION_CURRENT,
CONTROL_STATUS, MISSION_ITEM_REACHED: their count depends on timing, not on the exchange);
MISSION_CURRENT's distinct `seq` values are compared apart, in order of first appearance.

`builtin:` and `mutant:` targets run in virtual time on a `SimNetwork` with the recorded
latency, so replaying an exchange against the profile that recorded it shows no difference
(a test holds that) and against another profile shows exactly how they differ. `udp:` and
`udpin:` targets run over real sockets with bounded waits.

Handover exchanges (exchanges/handover/, two GCSs) are not replayed: a UsageError (exit 2)
says so; their frames are checked by `verify` like every other exchange's.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mavconform.conformance.session import build_vehicle
from mavconform.conformance.target_uri import TargetUri
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.messages import is_vehicle_heartbeat
from mavconform.reference_impl.net import FaultModel, MonotonicClock, SimNetwork, UdpDriver
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.net.uri import local_bind_for
from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder

from .dialect_info import DialectInfo
from .fields import field_differences, message_fields

STREAMED = frozenset({"HEARTBEAT", "GLOBAL_POSITION_INT", "MISSION_CURRENT", "CONTROL_STATUS",
                      "MISSION_ITEM_REACHED"})
SETTLE = 1.0            # s after the recorded exchange's last frame to collect late replies
DISCOVERY_TIMEOUT = 5.0  # s for a UDP target's first HEARTBEAT (scaled)


@dataclass
class Difference:
    index: int                 # position among the compared (non-stream) replies
    expected: str              # "MISSION_ACK sent at 0.080 s" or "nothing"
    got: str
    fields: list[str] = field(default_factory=list)

    def __str__(self) -> str:
        head = f"reply {self.index + 1}: expected {self.expected}, got {self.got}"
        return head + "".join(f"\n    {line}" for line in self.fields)


@dataclass
class ReplayResult:
    exchange: str
    target: str
    sent: int
    replies: int
    expected: int
    differences: list[Difference]
    current_expected: list[int]
    current_got: list[int]
    responsive: bool = True

    @property
    def ok(self) -> bool:
        return self.responsive and not self.differences and self.current_expected == self.current_got


class ReplayNode:
    """A `DatagramNode` that sends scheduled frames and keeps every frame it receives."""

    def __init__(self, frames: list[tuple[float, bytes]], dialect: DialectInfo, peer: Address | None) -> None:
        self._queue = list(frames)
        self._queue.sort(key=lambda f: f[0])
        self._next = 0
        self._offset: float | None = None       # set when the schedule starts
        self.peer = peer
        self.decoder = FrameDecoder(dialect=dialect.module)
        self.received: list[tuple[float, Any]] = []   # (time since start, Frame)
        self._out: list[tuple[bytes, Address]] = []
        self.scale = 1.0

    def start(self, now: float, first: float) -> None:
        """Begin the schedule: the frame recorded at `first` goes out at `now`."""
        self._offset = now - first * self.scale

    def schedule(self, frames: list[tuple[float, bytes]]) -> None:
        self._queue = sorted(frames, key=lambda f: f[0])
        self._next = 0

    def send_now(self, data: bytes) -> None:
        if self.peer is not None:
            self._out.append((data, self.peer))

    @property
    def sent(self) -> int:
        return self._next

    @property
    def done(self) -> bool:
        return self._next >= len(self._queue)

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        if self.peer is None:
            self.peer = source
        since = now - self._offset if self._offset is not None else 0.0
        for item in self.decoder.feed(data):
            if hasattr(item, "msg"):
                self.received.append((since, item))

    def poll(self, now: float) -> None:
        while (self._offset is not None and self._next < len(self._queue) and self.peer is not None
               and self._offset + self._queue[self._next][0] * self.scale <= now):
            self._out.append((self._queue[self._next][1], self.peer))
            self._next += 1

    def next_deadline(self) -> float | None:
        if self._offset is None or self._next >= len(self._queue) or self.peer is None:
            return None
        return self._offset + self._queue[self._next][0] * self.scale

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out, self._out = self._out, []
        return out


def replay(transcript: dict[str, Any], uri: TargetUri, dialect: DialectInfo, *, scale: float = 1.0) -> ReplayResult:
    """Send the transcript's GCS side to the target; compare its replies with the vehicle's.
    A handover exchange (two GCSs) is refused with a UsageError: replay speaks as one GCS."""
    if "gcs2" in transcript.get("peers", {}):
        raise UsageError(f"{transcript.get('id')}: a handover exchange has two GCSs (gcs, gcs2) and replay sends "
                         f"one GCS's side: fly it with `mavconform handover run` instead")
    events = [e for e in transcript["events"] if e.get("msg") != "DECODE_ERROR"]
    vehicle = transcript["peers"]["vehicle"]
    recorded_ids = (vehicle["sysid"], vehicle["compid"])
    gcs_events = [e for e in events if e["from"] == "gcs" and not e["lost"]]
    end = max((e["t"] for e in events), default=0.0)
    if uri.in_process:
        node, target_ids = _run_virtual(transcript, uri, dialect, gcs_events, end)
    else:
        node, target_ids = _run_udp(uri, dialect, gcs_events, end, recorded_ids, scale)
    if target_ids is None:
        return ReplayResult(transcript["id"], str(uri), 0, 0, 0, [], [], [], responsive=False)
    expected = [e for e in events if e["from"] == "vehicle"]
    got = [(t, f) for t, f in node.received if f.source == target_ids]
    differences = _compare([e for e in expected if e["msg"] not in STREAMED],
                           [(t, f) for t, f in got if f.name not in STREAMED], dialect)
    return ReplayResult(transcript["id"], str(uri), node.sent, len(got),
                        sum(1 for e in expected if e["msg"] not in STREAMED), differences,
                        _distinct(e["fields"]["seq"] for e in expected if e["msg"] == "MISSION_CURRENT"),
                        _distinct(f.msg.seq for _, f in got if f.name == "MISSION_CURRENT"))


def _run_virtual(transcript: dict[str, Any], uri: TargetUri, dialect: DialectInfo,
                 gcs_events: list[dict[str, Any]], end: float) -> tuple[ReplayNode, tuple[int, int]]:
    net = SimNetwork(seed=transcript["seed"])
    vehicle = build_vehicle(uri, wall_clock=net.clock.wall)
    node = ReplayNode([(e["t"], bytes.fromhex(e["hex"])) for e in gcs_events], dialect, "vehicle")
    net.add_node("vehicle", vehicle)
    net.add_node("gcs", node)
    latency = transcript["link"]["latency"]
    net.connect("gcs", "vehicle", a_to_b=FaultModel(delay=latency), b_to_a=FaultModel(delay=latency))
    vehicle.endpoint.add_address("gcs")
    node.start(0.0, 0.0)
    net.run_until(lambda: False, timeout=end + SETTLE)
    return node, (vehicle.config.system, vehicle.config.component)


def _run_udp(uri: TargetUri, dialect: DialectInfo, gcs_events: list[dict[str, Any]], end: float,
             recorded_ids: tuple[int, int], scale: float) -> tuple[ReplayNode, tuple[int, int] | None]:
    udp = uri.udp
    with UdpDriver(clock=MonotonicClock()) as driver:
        peer = udp.address if uri.kind == "udp" else None
        node = ReplayNode([], dialect, peer)
        node.scale = scale
        bind = (local_bind_for(udp.host), 0) if uri.kind == "udp" else udp.address
        driver.add_node(node, bind=bind)
        hello = [e for e in gcs_events if e["msg"] == "HEARTBEAT"][:1]
        if hello:    # a target that listens learns of us from a HEARTBEAT
            node.send_now(bytes.fromhex(hello[0]["hex"]))
        if not driver.run_until(lambda: _target(node) is not None, timeout=DISCOVERY_TIMEOUT * scale):
            return node, None
        target_ids = _target(node)
        node.received.clear()
        node.schedule([(e["t"], _retarget(e, recorded_ids, target_ids, dialect)) for e in gcs_events])
        first = gcs_events[0]["t"] if gcs_events else 0.0
        node.start(driver.clock.now(), first)
        driver.run_until(lambda: False, timeout=(end - first) * scale + SETTLE * scale)
        return node, target_ids


def _target(node: ReplayNode) -> tuple[int, int] | None:
    """The (sysid, compid) of the first vehicle HEARTBEAT heard, if any."""
    return next((f.source for _, f in node.received if is_vehicle_heartbeat(f.msg)), None)


def _retarget(event: dict[str, Any], recorded: tuple[int, int], target: tuple[int, int],
              dialect: DialectInfo) -> bytes:
    """The recorded bytes, or, for a target with other ids, the same message addressed to it."""
    raw = bytes.fromhex(event["hex"])
    fields = event.get("fields", {})
    if recorded == target or (fields.get("target_system"), fields.get("target_component")) != recorded:
        return raw
    frame = FrameDecoder(dialect=dialect.module).feed(raw)[0]
    msg = frame.msg
    msg.target_system, msg.target_component = target
    encoder = FrameEncoder(frame.src_system, frame.src_component, dialect=dialect.module, version=frame.version)
    encoder._mav.seq = frame.seq      # keep the recorded sequence number (FrameEncoder has no parameter)
    return encoder.encode(msg)


def _compare(expected: list[dict[str, Any]], got: list[tuple[float, Any]], dialect: DialectInfo) -> list[Difference]:
    by_id = {m.id: m for m in dialect.messages}
    out = []
    for i in range(max(len(expected), len(got))):
        want = expected[i] if i < len(expected) else None
        have = got[i] if i < len(got) else None
        if want is None:
            out.append(Difference(i, "nothing", _what(have[1].name, have[0], "received")))
            continue
        if have is None:
            out.append(Difference(i, _what(want["msg"], want["t"]), "nothing"))
            continue
        t, frame = have
        if frame.name != want["msg"]:
            out.append(Difference(i, _what(want["msg"], want["t"]), _what(frame.name, t, "received")))
            continue
        info = by_id.get(frame.msgid)
        if info is None:
            continue
        diffs = field_differences(want["fields"], message_fields(frame.msg, info), info)
        if diffs:
            out.append(Difference(i, _what(want["msg"], want["t"]), _what(frame.name, t, "received"), diffs))
    return out


def _what(name: str, t: float, how: str = "sent") -> str:
    return f"{name} {how} at {t:.3f} s"


def _distinct(values: Any) -> list[int]:
    out: list[int] = []
    for v in values:
        if v not in out:
            out.append(v)
    return out


def render(result: ReplayResult) -> str:
    """The lines `mavconform vectors replay` prints."""
    lines = [f"replayed {result.exchange} against {result.target}: {result.sent} frames sent, "
             f"{result.replies} received"]
    if not result.responsive:
        lines.append("FAIL target unresponsive: no HEARTBEAT from the target")
        return "\n".join(lines)
    lines += [f"DIFF {d}" for d in result.differences]
    if result.current_expected != result.current_got:
        lines.append(f"DIFF MISSION_CURRENT seq values: expected {result.current_expected}, "
                     f"got {result.current_got}")
    lines.append("same replies as recorded" if result.ok else
                 f"{len(result.differences)} of {max(result.expected, 1)} compared replies differ")
    return "\n".join(lines)
