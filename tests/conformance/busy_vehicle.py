"""A busy autopilot's telemetry for the in-process vehicles: bursts of GLOBAL_POSITION_INT.

Real autopilots stream hundreds of frames a second (PX4's fixed-wing SIH ~360/s). Here
every time the vehicle sends anything (a reply, a HEARTBEAT) a burst of telemetry frames
follows it in the same flush, so the burst reaches the tester's socket right behind the
message it follows: against a small receive buffer the kernel keeps that message and drops
most of the burst, every time, without any real-time race (the driver reads the tester's
socket before each flush). The frames are numbered by the vehicle's own encoder, so a
mutant's packet sequence stays what the mutant makes it.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.vehicle import VehicleNode

BURST = 200   # telemetry frames after each thing the vehicle sends


class _Bursts:
    """Mixin before a VehicleNode class: whatever it sends is followed by `burst` frames."""

    burst = BURST
    telemetry_sent = 0

    def take_outgoing(self) -> list[tuple[bytes, Any]]:
        out = super().take_outgoing()   # type: ignore[misc]
        if out:
            position = self._position(0.0)   # type: ignore[attr-defined]
            for _ in range(self.burst):
                self.endpoint.send(position)   # type: ignore[attr-defined]
            self.telemetry_sent += self.burst
            out += super().take_outgoing()   # type: ignore[misc]
        return out


def make_busy(vehicle: VehicleNode, burst: int = BURST) -> VehicleNode:
    """`vehicle` (the spec vehicle, a profile's, a mutant) with a bursty telemetry stream."""
    vehicle.__class__ = type(f"Busy{type(vehicle).__name__}", (_Bursts, type(vehicle)), {"burst": burst})
    return vehicle
