"""Mutants with a broken frame decoder: planted bugs for the frame fuzzer to find.

It handles well-formed traffic exactly like the spec vehicle. The frame fuzzer finds it,
shrinks it to a truncated frame and replays it (its tests assert that); of the clauses only
MIS.FRM.05 sends a truncated frame, and fails on the crash.
"""

from __future__ import annotations

import struct

from mavconform.reference_impl.vehicle import VehicleNode

from . import mutant, vehicle_mutant

_CRC = struct.Struct("<H")


class _TrustsLengthByte(VehicleNode):
    """Pre-scans each datagram for checksums by trusting every frame's length byte, as a
    hand-written parser might: `unpack_from` past the end of a truncated frame raises."""

    def datagram_received(self, data, source, now):
        i, n = 0, len(data)
        while i < n:
            magic = data[i]
            if magic not in (0xFD, 0xFE) or i + 2 >= n:
                i += 1
                continue
            total = data[i + 1] + (12 + (13 if data[i + 2] & 1 else 0) if magic == 0xFD else 8)
            _CRC.unpack_from(data, i + total - 2)     # struct.error on a short buffer
            i += total
        super().datagram_received(data, source, now)


mutant("raises-on-truncated-frame", "its frame decoder raises on a truncated frame (a planted bug for the "
       "frame fuzzer; MIS.FRM.05 sends one too)", {"MIS.FRM.05"}, vehicle_mutant(_TrustsLengthByte))
