"""Mutants that break the framing clauses (MIS.FRM.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.vehicle import VehicleNode

from . import mutant, vehicle_mutant


class _CorruptsRallyItems(VehicleNode):
    """Every other rally MISSION_ITEM(_INT) leaves with a broken checksum (a GCS's resend
    gets a good copy, so transfers still complete)."""

    _rally_items = 0

    def _send(self, actions):
        endpoint = self.endpoint
        for msg, to in actions:
            before = len(endpoint._outbox)
            endpoint.send(msg, to)
            if msg._type in ("MISSION_ITEM_INT", "MISSION_ITEM") and msg.mission_type == MissionType.RALLY:
                self._rally_items += 1
                if self._rally_items % 2:
                    endpoint._outbox[before:] = [(data[:-1] + bytes([data[-1] ^ 0x5A]), address)
                                                 for data, address in endpoint._outbox[before:]]


class _RepeatsPacketSeq(VehicleNode):
    """Every 8th frame does not advance the packet sequence: the next frame repeats its seq."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        encoder = self.endpoint.encoder
        encode = encoder.encode
        count = [0]

        def encode_repeating(msg, **kw):
            data = encode(msg, **kw)
            count[0] += 1
            if count[0] % 8 == 0:
                encoder._mav.seq = (encoder._mav.seq - 1) & 0xFF
            return data

        encoder.encode = encode_repeating


class _SkipsPacketSeq(VehicleNode):
    """Every 8th frame advances the packet sequence by two: one value is never sent."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        encoder = self.endpoint.encoder
        encode = encoder.encode
        count = [0]

        def encode_skipping(msg, **kw):
            data = encode(msg, **kw)
            count[0] += 1
            if count[0] % 8 == 0:
                encoder._mav.seq = (encoder._mav.seq + 1) & 0xFF
            return data

        encoder.encode = encode_skipping


class _HeartbeatOnce(VehicleNode):
    """Sends its first HEARTBEAT (so it can be found), then never again."""

    def poll(self, now):
        sent = self._next_heartbeat is not None and now >= self._next_heartbeat
        super().poll(now)
        if sent:
            self._next_heartbeat = None


mutant("mavlink1", "speaks MAVLink 1 only, so no frame carries mission_type (or any other extension)",
       {"MIS.FRM.01", "MIS.TYP.02"}, vehicle_mutant(VehicleNode, mavlink_version=1))
mutant("corrupts-rally-items", "sends every other rally item with a bad checksum",
       {"MIS.FRM.02"}, vehicle_mutant(_CorruptsRallyItems))
mutant("repeats-packet-seq", "every 8th frame repeats the packet sequence number of the one before",
       {"MIS.FRM.03"}, vehicle_mutant(_RepeatsPacketSeq))
mutant("skips-packet-seq", "every 8th frame skips a packet sequence number (a gap no lost frame explains)",
       {"MIS.FRM.03"}, vehicle_mutant(_SkipsPacketSeq))
mutant("heartbeat-once", "sends one HEARTBEAT at start-up and no more",
       {"MIS.FRM.04"}, vehicle_mutant(_HeartbeatOnce))


_MAGIC_V2, _V2_OVERHEAD = 0xFD, 12


class _IgnoresChecksum(VehicleNode):
    """Acts on a frame whatever its checksum says (the checksum is made right before the
    frame is decoded)."""

    def datagram_received(self, data, source, now):
        if len(data) > 10 and data[0] == _MAGIC_V2 and not data[2] & 1 and len(data) == data[1] + _V2_OVERHEAD:
            from mavconform.fuzz.frames import wire
            data = wire.rechecksum(data)
        super().datagram_received(data, source, now)


class _PadsTruncatedFrames(VehicleNode):
    """Takes a frame cut short as if its missing bytes were zeros (and its checksum right)."""

    def datagram_received(self, data, source, now):
        if len(data) > 10 and data[0] == _MAGIC_V2 and not data[2] & 1 and len(data) < data[1] + _V2_OVERHEAD:
            from mavconform.fuzz.frames import wire
            data = wire.rechecksum(data.ljust(data[1] + _V2_OVERHEAD, b"\0"))
        super().datagram_received(data, source, now)


mutant("ignores-checksum", "acts on frames whose checksum is wrong",
       {"MIS.FRM.05"}, vehicle_mutant(_IgnoresChecksum))
mutant("pads-truncated-frames", "acts on a frame cut short, as if its missing bytes were zeros",
       {"MIS.FRM.05"}, vehicle_mutant(_PadsTruncatedFrames))
