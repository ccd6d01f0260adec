"""The suite's MSP client: one request, one bounded wait for its reply, and the evidence.

A check asks (`ask`) and gets the reply frame or None; every wait ends at `reply_timeout`
(stretched by the run's time scale), so a flight controller that goes silent costs a bound,
never a hang. A reply is the next frame from the flight controller with the request's
command (`>` or `!`); one for another command (a late answer to an earlier request) is
skipped. Every frame sent and every reply read goes into the clause's exchange with its
fields decoded (the waypoint record, the GETINFO reply), so a report shows what was written
and what came back.
"""

from __future__ import annotations

from typing import Any, Callable

from mavconform.reference_impl.msp.capture import frame_fields, frame_name
from mavconform.reference_impl.msp.commands import CODE, Waypoint, WaypointInfo
from mavconform.reference_impl.msp.frame import ERROR, MspFrame, Version
from mavconform.reference_impl.msp.nodes import MspClientNode

from ..harness.exchange import Exchange
from ..outcome import ClauseFailed, TargetUnresponsive

REPLY_TIMEOUT = 1.0      # s: INAV answers at once; a 57600-baud line moves a waypoint in 5 ms
STORAGE_TIMEOUT = 3.0    # s: MSP_WP_MISSION_SAVE writes flash before it answers


class MspTester:
    def __init__(self, driver: Any, node: MspClientNode, *, scale: float = 1.0, allowance: float = 0.0) -> None:
        self.driver = driver
        self.node = node
        self.scale = scale
        self.allowance = allowance   # s a slow link adds to each reply (harness/link_timing.py)
        self.exchange: Exchange | None = None
        self.requests = 0
        self.unanswered = 0          # requests in a row that got nothing at all
        self.forced_wait = 0.0       # s spent waiting out silences a clause asked for

    def now(self) -> float:
        return self.driver.clock.now()

    # --- the exchange ----------------------------------------------------------------------
    def _record(self, direction: str, frame: MspFrame) -> int | None:
        if self.exchange is None:
            return None
        return self.exchange.add(self.now(), direction, "tester", frame_name(frame.command), frame_fields(frame))

    def note(self, text: str) -> None:
        if self.exchange is not None:
            self.exchange.note(self.now(), "tester", text)

    def decide(self, index: int | None) -> None:
        if self.exchange is not None and index is not None:
            self.exchange.decide(index)

    # --- asking ----------------------------------------------------------------------------
    def ask(self, command: str | int, payload: bytes = b"", *, version: Version = Version.V1,
            raw: bytes | None = None, timeout: float = REPLY_TIMEOUT) -> MspFrame | None:
        """Send a request (or `raw` bytes standing for it) and wait for its reply; None if
        none came within the bound."""
        code = CODE[command] if isinstance(command, str) else command
        frame = MspFrame(code, payload, version=version)
        start = len(self.node.inbox)
        if raw is None:
            self.node.send(frame)
            self._record("tx", frame)
        else:
            self.node.send_raw(raw)
            self.note(f"sent {len(raw)} bytes: {raw.hex()}")
        self.requests += 1
        reply = self._await(lambda f: f.command == code, start, timeout)
        if reply is None:
            self.unanswered += 1
            self.note(f"no reply to {frame_name(code)} within {timeout * self.scale:g} s")
        else:
            self.unanswered = 0
        return reply

    def _await(self, match: Callable[[MspFrame], bool], start: int, timeout: float) -> MspFrame | None:
        inbox = self.node.inbox
        cursor = [start]
        found: list[MspFrame] = []

        def arrived() -> bool:
            while not found and cursor[0] < len(inbox):
                frame = inbox[cursor[0]][1]
                cursor[0] += 1
                self._record("rx", frame)   # a late reply to something earlier is shown, not taken
                if match(frame):
                    found.append(frame)
            return bool(found)

        began = self.now()
        if not self.driver.run_until(arrived, timeout=timeout * self.scale + self.allowance):
            self.forced_wait += self.now() - began
        return found[0] if found else None

    def silence(self, seconds: float) -> list[MspFrame]:
        """Listen for `seconds` (scaled): what the flight controller sent meanwhile."""
        start = len(self.node.inbox)
        self.driver.run_for(seconds * self.scale)
        self.forced_wait += seconds * self.scale
        got = [f for _, f in self.node.inbox[start:]]
        for frame in got:
            self._record("rx", frame)
        return got

    # --- the waypoint commands -------------------------------------------------------------
    def info(self) -> WaypointInfo:
        """MSP_WP_GETINFO, decoded; a missing or malformed reply fails the clause."""
        reply = self.expect("MSP_WP_GETINFO")
        try:
            return WaypointInfo.unpack(reply.payload)
        except ValueError as exc:
            raise ClauseFailed(f"MSP_WP_GETINFO's reply: {exc}") from None

    def set_wp(self, wp: Waypoint) -> MspFrame:
        """MSP_SET_WP; the reply (`>` or `!`), which says nothing of whether it was stored."""
        return self.expect("MSP_SET_WP", wp.pack())

    def wp(self, number: int) -> Waypoint:
        reply = self.expect("MSP_WP", bytes((number,)))
        if reply.direction == ERROR:
            raise ClauseFailed(f"MSP_WP {number} was answered `!`")
        try:
            return Waypoint.unpack(reply.payload)
        except ValueError as exc:
            raise ClauseFailed(f"MSP_WP {number}'s reply: {exc}") from None

    def expect(self, command: str, payload: bytes = b"", *, timeout: float = REPLY_TIMEOUT,
               version: Version = Version.V1) -> MspFrame:
        """`ask`, where no reply at all means the flight controller is not answering."""
        reply = self.ask(command, payload, timeout=timeout, version=version)
        if reply is None:
            raise TargetUnresponsive(f"no reply to {command} within {timeout * self.scale:g} s")
        return reply

    def write(self, waypoints: list[Waypoint]) -> list[MspFrame]:
        return [self.set_wp(wp) for wp in waypoints]

    def read(self, count: int) -> list[Waypoint]:
        return [self.wp(n) for n in range(1, count + 1)]

    def stored(self) -> list[Waypoint]:
        """The mission the flight controller holds now: GETINFO's count, each read back."""
        return self.read(self.info().count)
