"""Mutant MSP flight controllers: each breaks named MSP clauses, to prove the checks can fail.

A mutant is `builtin:msp` (reference_impl/msp/flight_controller.py) with one behaviour
changed by a subclass overriding one method, or, for the framing clauses, the node around it.
The bugs are ones an MSP waypoint store can plausibly have (an off-by-one in INAV's JUMP
index/number conversion, a count not reset by a new mission, a list that keeps old slots).
`breaks` lists exactly the clauses the change fails; tests/conformance/msp/ asserts that each
of them fails on the mutant, every other MSP clause passes, and every clause has a mutant.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from mavconform.reference_impl.msp.commands import FLAG_LAST, Waypoint
from mavconform.reference_impl.msp.flight_controller import ACTIONS, MspFlightController
from mavconform.reference_impl.msp.frame import V2_FRAME_ID, MspFrame, Version, crc8_dvb_s2, xor_checksum
from mavconform.reference_impl.msp.nodes import MspServerNode
from mavconform.reference_impl.msp.parser import MspParser

JUMP = 6


@dataclass(frozen=True)
class MspMutant:
    name: str
    description: str
    breaks: frozenset[str]
    build: Callable[[], MspServerNode]


class JumpReadAsIndex(MspFlightController):
    """Stores a JUMP's target as an index (number - 1), as INAV does, and forgets to add the
    1 back when MSP_WP reads it."""

    def store(self, wp: Waypoint) -> None:
        super().store(replace(wp, p1=wp.p1 - 1) if wp.action == JUMP else wp)


class InfoCountStale(MspFlightController):
    """MSP_WP_GETINFO's count is the highest number ever stored, not the list's length."""

    highest = 0

    def store(self, wp: Waypoint) -> None:
        super().store(wp)
        self.highest = max(self.highest, wp.number)

    def info(self):
        return replace(super().info(), count=self.highest)


class ValidWithoutFlag(MspFlightController):
    """The list is valid as soon as it holds a waypoint, 0xA5 or not."""

    def store(self, wp: Waypoint) -> None:
        super().store(wp)
        self.valid = True


class TakesOnePastMax(MspFlightController):
    """Reports 120 waypoints at most and stores 121 (an array one too long)."""

    def takes(self, wp: Waypoint) -> bool:
        return (wp.number == self.max_waypoints + 1 == len(self.waypoints) + 1
                and wp.action in ACTIONS) or super().takes(wp)


class WrongSizeTaken(MspFlightController):
    """MSP_SET_WP pads a short payload with zeros and ignores bytes past the 21st."""

    def _set_wp(self, payload: bytes) -> bytes | None:
        return super()._set_wp(payload[:21].ljust(21, b"\x00"))


class NumbersWrap(MspFlightController):
    """A number past the maximum wraps round onto the mission (121 is taken as 1)."""

    def _set_wp(self, payload: bytes) -> bytes | None:
        number = payload[0] if payload else 0
        if len(payload) == 21 and self.max_waypoints < number < 254:
            payload = bytes(((number - 1) % self.max_waypoints + 1,)) + payload[1:]
        return super()._set_wp(payload)


class GapTaken(MspFlightController):
    """Takes any number 1..max, leaving empty slots in a gap (a sparse list)."""

    def takes(self, wp: Waypoint) -> bool:
        return 1 <= wp.number <= self.max_waypoints and wp.action in ACTIONS

    def store(self, wp: Waypoint) -> None:
        if wp.number == 1:
            self.waypoints = []
        while len(self.waypoints) < wp.number - 1:
            self.waypoints.append(Waypoint(len(self.waypoints) + 1, 0, 0, 0, 0))
        if wp.number <= len(self.waypoints):
            self.waypoints[wp.number - 1] = wp
        else:
            self.waypoints.append(wp)
        self.valid = self.waypoints[-1].flag == FLAG_LAST


class StaleReadback(MspFlightController):
    """A new mission shortens the count but MSP_WP still reads the old slots past it."""

    def __init__(self) -> None:
        super().__init__()
        self.slots: dict[int, Waypoint] = {}

    def store(self, wp: Waypoint) -> None:
        super().store(wp)
        self.slots[wp.number] = wp

    def _wp(self, payload: bytes) -> bytes:
        number = payload[0] if payload else 0
        if number > len(self.waypoints) and number in self.slots:
            return self.slots[number].pack()
        return super()._wp(payload)


class SaveNotKept(MspFlightController):
    """MSP_WP_MISSION_SAVE answers `>` and keeps nothing."""

    def _save(self, payload: bytes) -> bytes | None:
        return None if len(payload) != 1 or not self.valid else b""


class AnswersInV1(MspFlightController):
    """Every reply goes out as MSP v1, whatever framing the request came in."""

    def handle(self, frame: MspFrame) -> list[MspFrame]:
        return [replace(r, version=Version.V1) if r.command < V2_FRAME_ID else r for r in super().handle(frame)]


class SilentOnUnknown(MspFlightController):
    """A command it does not know gets no reply at all."""

    def handle(self, frame: MspFrame) -> list[MspFrame]:
        return super().handle(frame) if frame.command in self._handlers else []


def _fixed(data: bytes) -> bytes:
    """`data` with the checksum of every whole request in it made right: a parser that never
    looks at checksums, as a flight controller that skips the check would read."""
    out = bytearray(data)
    i = out.find(b"$")
    while 0 <= i < len(out) - 4:
        kind = out[i + 1:i + 3]
        if kind == b"M<":
            size = out[i + 3]
            end = i + 5 + size
            if end < len(out):
                out[end] = xor_checksum(out[i + 3:end])
        elif kind == b"X<" and i + 8 <= len(out):
            size = int.from_bytes(out[i + 6:i + 8], "little")
            end = i + 8 + size
            if end < len(out):
                out[end] = crc8_dvb_s2(out[i + 3:end])
        i = out.find(b"$", i + 1)
    return bytes(out)


class _UncheckedParser(MspParser):
    def feed(self, data: bytes) -> list[MspFrame]:
        return super().feed(_fixed(data))


def _said(cls: type) -> str:
    return " ".join((cls.__doc__ or "").split())


def _node(controller: type[MspFlightController]) -> Callable[[], MspServerNode]:
    return lambda: MspServerNode(controller())


MUTANT_LIST = (
    MspMutant("jump-read-as-index", _said(JumpReadAsIndex), frozenset({"MSP.WP.01", "MSP.WP.04", "MSP.WP.09"}),
              _node(JumpReadAsIndex)),
    MspMutant("info-count-stale", _said(InfoCountStale), frozenset({"MSP.WP.02"}), _node(InfoCountStale)),
    MspMutant("valid-without-flag", _said(ValidWithoutFlag), frozenset({"MSP.WP.03"}), _node(ValidWithoutFlag)),
    MspMutant("takes-one-past-max", _said(TakesOnePastMax), frozenset({"MSP.WP.04"}), _node(TakesOnePastMax)),
    MspMutant("wrong-size-taken", _said(WrongSizeTaken), frozenset({"MSP.WP.05"}), _node(WrongSizeTaken)),
    MspMutant("numbers-wrap", _said(NumbersWrap), frozenset({"MSP.WP.06"}), _node(NumbersWrap)),
    MspMutant("gap-taken", _said(GapTaken), frozenset({"MSP.WP.07"}), _node(GapTaken)),
    MspMutant("stale-readback", _said(StaleReadback), frozenset({"MSP.WP.08"}), _node(StaleReadback)),
    MspMutant("save-not-kept", _said(SaveNotKept), frozenset({"MSP.WP.09"}), _node(SaveNotKept)),
    MspMutant("answers-in-v1", _said(AnswersInV1), frozenset({"MSP.FR.01"}), _node(AnswersInV1)),
    MspMutant("ignores-checksum", "Reads requests without checking their checksum (v1 XOR, v2 CRC-8).",
              frozenset({"MSP.FR.02"}), lambda: MspServerNode(parser=lambda: _UncheckedParser(accept="<"))),
    MspMutant("silent-on-unknown", _said(SilentOnUnknown), frozenset({"MSP.FR.03"}), _node(SilentOnUnknown)),
)
MSP_MUTANTS: dict[str, MspMutant] = {m.name: m for m in MUTANT_LIST}
assert len(MSP_MUTANTS) == len(MUTANT_LIST)
