"""The traffic of each handover, kept for its sequence diagram (docs/handover.md's six steps).

A capture hook on the scenario's network. Decoding every frame of a ten-minute flight would
cost more than flying it, so the hook only keeps the raw datagrams sent (and lost) while the
mission computer has a handover under way, and for `TAIL_S` after (the last answers of a
handover go out in the step that ends it); `exchange` decodes one handover's window into the
event dicts `reports/sequence_svg.sequence_diagram` draws (t, dir, peer, msg, fields). The MCAP
capture, beside it, keeps everything.
"""

from __future__ import annotations

from typing import Any

from ..net.capture import json_safe
from ..net.sim import CaptureRecord
from ..vehicle import VehicleNode
from ..wire import FrameDecoder

__all__ = ["HandoverTraffic", "TELEMETRY"]

TAIL_S = 1.0
MAX_RECORDS = 100_000        # kept datagrams in all (a bound for pathological scenarios)
MAX_EVENTS = 400             # per exchange; the MCAP has the rest
# streamed on their own clock: they would bury the exchange (the MCAP has them)
TELEMETRY = frozenset({"HEARTBEAT", "GLOBAL_POSITION_INT", "MISSION_CURRENT", "MISSION_ITEM_REACHED"})


class HandoverTraffic:
    """Capture hook: the datagrams around handovers, by send time."""

    def __init__(self, vehicle: VehicleNode, vehicle_address: str, lanes: dict[str, str]) -> None:
        self._mc = vehicle.mission_computer
        self._vehicle = vehicle_address
        self._lanes = lanes                  # node address -> lane name (the GCS's name)
        self._keep_until = -1.0
        self.records: list[tuple[float, str, str, bytes, bool]] = []   # (t, src, dst, data, lost)
        self.overflow = 0

    def __call__(self, record: CaptureRecord) -> None:
        if self._mc is not None and self._mc.attempt is not None:
            self._keep_until = record.time + TAIL_S
        if record.kind == "rx" or record.time > self._keep_until:
            return
        if len(self.records) >= MAX_RECORDS:
            self.overflow += 1
            return
        self.records.append((record.time, record.src, record.dst, record.data, record.kind == "drop"))

    def exchange(self, start: float, end: float) -> list[dict[str, Any]]:
        """The messages sent in [start, end] between the vehicle and the GCSs, telemetry left
        out; a datagram a link lost is a note saying which message it was."""
        decoders: dict[tuple[str, bool], FrameDecoder] = {}
        out: list[dict[str, Any]] = []
        omitted = 0
        for t, src, dst, data, lost in self.records:
            if not start <= t <= end:
                continue
            from_vehicle = src == self._vehicle
            peer = self._lanes.get(dst if from_vehicle else src, str(dst if from_vehicle else src))
            # a lost copy is the same bytes as the sent one: its own decoder, so streams stay whole
            decoder = decoders.setdefault((src, lost), FrameDecoder())
            for frame in decoder.feed(data):
                msg = getattr(frame, "msg", None)
                if msg is None or msg._type in TELEMETRY:
                    continue
                if len(out) >= MAX_EVENTS:
                    omitted += 1
                    continue
                name = msg._type
                if lost:
                    who = f"vehicle -> {peer}" if from_vehicle else f"{peer} -> vehicle"
                    out.append({"t": round(t, 6), "dir": "note", "peer": peer,
                                "msg": f"lost on the link {who}: {name}{_command(msg)}", "fields": {}})
                else:
                    out.append({"t": round(t, 6), "dir": "rx" if from_vehicle else "tx", "peer": peer,
                                "msg": name, "fields": {f: json_safe(getattr(msg, f)) for f in msg.get_fieldnames()}})
        if omitted:
            out.append({"t": out[-1]["t"], "dir": "note", "peer": out[-1]["peer"],
                        "msg": f"... {omitted} more messages in handover.mcap", "fields": {}})
        return out


def _command(msg: Any) -> str:
    """' (command 32100)' for a COMMAND_LONG / COMMAND_ACK, so a lost step is recognisable."""
    command = getattr(msg, "command", None)
    return f" (command {command})" if command is not None else ""
