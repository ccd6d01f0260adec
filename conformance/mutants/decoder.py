"""Mutants with a broken frame decoder: planted bugs for the frame fuzzer to find.

The conformance clauses judge the target's behaviour on well-formed traffic, which this
mutant handles exactly like the spec vehicle, so it breaks no clause: it exists to show
that `mavconform fuzz --mode frames` finds what the clause suite cannot see (the frame
fuzzer's tests assert that it is found, shrunk to a truncated frame, and replayed).
"""

from __future__ import annotations

import struct

from reference_impl.vehicle import VehicleNode

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
       "frame fuzzer; no conformance clause sends one)", set(), vehicle_mutant(_TrustsLengthByte))
