"""Mutants that break the error clauses (MIS.ERR.*)."""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.actions import Send
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import SlotState

from . import mutant, server_mutant

UNDEFINED_RESULT = 99   # no MAV_MISSION_RESULT has this value


class _UndefinedUnsupportedCode(MissionServer):
    def _unsupported(self, raw_type, src):
        return [Send(m.ack_message(UNDEFINED_RESULT, raw_type, src), src)]


class _BusyAfterInvalidRequest(MissionServer):
    def _on_request(self, msg, src, now):
        t = self._plan_type(msg.mission_type)
        slot = self._slots[t] if t is not None else None
        if slot is not None and slot.state is SlotState.SENDING and slot.partner == src \
                and msg.seq >= self.store.count(t):
            # the error is sent, but the download is kept open for its partner
            return [Send(m.ack_message(MissionResult.INVALID_SEQUENCE, t, src), src)]
        return super()._on_request(msg, src, now)


mutant("undefined-result-code", f"refuses an unknown mission_type with MISSION_ACK type {UNDEFINED_RESULT}, "
       "which is no MAV_MISSION_RESULT", {"MIS.ERR.01"}, server_mutant(_UndefinedUnsupportedCode))
mutant("busy-after-error", "after answering a request beyond the list with INVALID_SEQUENCE, keeps the "
       "download open", {"MIS.ERR.02"}, server_mutant(_BusyAfterInvalidRequest))


class _DiesOnUnknownAckResult(MissionServer):
    """Looks the GCS's MISSION_ACK result up in a table that has only the defined values,
    as a C `switch` without a default might index an array: an undefined one raises. The
    vehicle then dies (in its own process: the process exits with the traceback)."""

    def _on_ack(self, msg, src, now):
        MissionResult(msg.type)          # ValueError for a result code MAV_MISSION_RESULT lacks
        return super()._on_ack(msg, src, now)


mutant("dies-on-unknown-ack-result", "dies on a MISSION_ACK whose result code MAV_MISSION_RESULT does not "
       "define (a planted crash for the fuzzers: no clause sends one)", set(), server_mutant(_DiesOnUnknownAckResult))


class _DiesOnOutOfRangeParam(MissionServer):
    """Converts param1 of a received item to a 16-bit integer as ArduPilot does
    (AP_Mission.cpp `mavlink_int_to_mission_cmd`: `cmd.p1 = packet.param1`, p1 a uint16_t),
    without a range check: ArduCopter SITL, whose floating-point exceptions are enabled
    (AP_HAL_SITL/Scheduler.cpp `feenableexcept`), aborts with "Floating point exception" on
    a MISSION_ITEM whose param1 is 1.4e37. Here the process dies the same way."""

    def _on_item(self, msg, src, now):
        value = getattr(msg, "param1", 0.0)
        if value == value and not -1.0 < value < 65536.0:
            raise FloatingPointError(f"param1 {value!r} does not fit the 16-bit field it is stored in")
        return super()._on_item(msg, src, now)


mutant("dies-on-out-of-range-param", "dies on an item whose param1 does not fit 16 bits, as ArduCopter "
       "SITL did (a planted crash for the fuzzers: no clause sends one)", set(),
       server_mutant(_DiesOnOutOfRangeParam))
