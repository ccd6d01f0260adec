"""A busy autopilot's telemetry for the in-process vehicles: bursts of frames.

Real autopilots stream hundreds of frames a second (PX4's fixed-wing SIH ~360/s), most of
them messages our dialect lacks. Here every time the vehicle sends anything (a reply, a
HEARTBEAT) a burst of telemetry frames follows it in the same flush, so the burst reaches
the tester's socket right behind the message it follows: against a small receive buffer the
kernel keeps that message and drops most of the burst. Where two flushes come before the
tester's next read (the driver reads when select wakes it; a busy machine), one gap between
two frames we read holds more than 255 dropped frames and the 8-bit sequence wraps. The
frames are numbered by the vehicle's own encoder, so a mutant's packet sequence stays what
the mutant makes it.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.vehicle import VehicleNode

BURST = 200          # telemetry frames after each thing the vehicle sends
UNKNOWN_ID = 30      # ATTITUDE: a common message our dialect lacks


class _Bursts:
    """Mixin before a VehicleNode class: whatever it sends is followed by `burst` frames,
    `per_datagram` to a datagram; `unknown`: of a message id our dialect lacks."""

    burst = BURST
    per_datagram = 1
    unknown = False
    telemetry_sent = 0

    def take_outgoing(self) -> list[tuple[bytes, Any]]:
        out = super().take_outgoing()   # type: ignore[misc]
        if not out:
            return out
        position = self._position(0.0)   # type: ignore[attr-defined]
        for _ in range(self.burst):
            self.endpoint.send(position)   # type: ignore[attr-defined]
        self.telemetry_sent += self.burst
        burst = super().take_outgoing()   # type: ignore[misc]
        if self.unknown:   # the id rewritten: pymavlink cannot check what it cannot decode
            burst = [(data[:7] + bytes([UNKNOWN_ID, 0, 0]) + data[10:], to) for data, to in burst]
        frames: dict[Any, list[bytes]] = {}   # by destination (every GCS it knows)
        for data, to in burst:
            frames.setdefault(to, []).append(data)
        step = self.per_datagram
        for to, datas in frames.items():
            out += [(b"".join(datas[i:i + step]), to) for i in range(0, len(datas), step)]
        return out


def make_busy(vehicle: VehicleNode, burst: int = BURST, *, per_datagram: int = 1,
              unknown: bool = False) -> VehicleNode:
    """`vehicle` (the spec vehicle, a profile's, a mutant) with a bursty telemetry stream."""
    mixin = {"burst": burst, "per_datagram": per_datagram, "unknown": unknown}
    vehicle.__class__ = type(f"Busy{type(vehicle).__name__}", (_Bursts, type(vehicle)), mixin)
    return vehicle
