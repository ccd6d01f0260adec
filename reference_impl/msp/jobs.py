"""What the bridge asks of an MSP flight controller, as sans-IO jobs: write a mission and
prove it stored, read the mission, read the navigation status.

A job is a generator: it yields each request (an `MspFrame`) and is sent the reply (or None
when the flight controller stayed silent through every retry), and returns a `Done` or a
`Failed` saying which waypoint and field. `JobRunner` sends, times out, resends and feeds
the replies, with time injected (`poll(now)`, `next_deadline()`), so the same job runs in
virtual time and over a TCP or serial link.

A write is never taken on the flight controller's word: INAV answers MSP_SET_WP `>` even
for a waypoint it ignored (fc_msp.c:3082-3112), so every waypoint is read back with MSP_WP
and MSP_WP_GETINFO must then report that many, valid. MSP lets a request be sent again
safely: MSP_SET_WP n is taken only as 1 or count + 1, so a repeat of one that was taken is
ignored.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Generator

from .commands import CODE, FLAG_LAST, Waypoint, WaypointInfo, waypoint_difference
from .frame import ERROR, MspFrame

REPLY_TIMEOUT = 0.5      # s for one reply (INAV answers at once; 115200 baud moves 30 bytes in 3 ms)
RETRIES = 2              # resends of a request that got nothing
# The MultiWii NAV convention for "no mission": one RTH waypoint of zeros flagged 0xA5
# (mwptools' MSP navigation notes); it is also what MSP_WP returns for a missing waypoint.
EMPTY = Waypoint(1, 4, 0, 0, 0, 0, 0, 0, FLAG_LAST)


@dataclass(frozen=True)
class Done:
    waypoints: tuple[Waypoint, ...] = ()
    info: WaypointInfo | None = None
    payload: bytes = b""


@dataclass(frozen=True)
class Failed:
    why: str
    silent: bool = False      # the flight controller answered nothing at all


Result = Done | Failed
Job = Generator[MspFrame, "MspFrame | None", Result]


def request(name: str, payload: bytes = b"") -> MspFrame:
    return MspFrame(CODE[name], payload)


def _answer(reply: MspFrame | None, what: str) -> Failed | None:
    if reply is None:
        return Failed(f"the flight controller did not answer {what}", silent=True)
    if reply.direction == ERROR:
        return Failed(f"the flight controller refused {what} (`!`)")
    return None


def read_info() -> Job:
    reply = yield request("MSP_WP_GETINFO")
    bad = _answer(reply, "MSP_WP_GETINFO")
    if bad is not None:
        return bad
    try:
        return Done(info=WaypointInfo.unpack(reply.payload))
    except ValueError as exc:
        return Failed(f"MSP_WP_GETINFO: {exc}")


def read_waypoint(number: int) -> Job:
    reply = yield request("MSP_WP", bytes((number,)))
    bad = _answer(reply, f"MSP_WP {number}")
    if bad is not None:
        return bad
    try:
        wp = Waypoint.unpack(reply.payload)
    except ValueError as exc:
        return Failed(f"MSP_WP {number}: {exc}")
    if wp.number != number:
        return Failed(f"MSP_WP {number} was answered with waypoint {wp.number}")
    return Done((wp,))


def read_mission() -> Job:
    """MSP_WP_GETINFO, then MSP_WP 1..count."""
    got = yield from read_info()
    if isinstance(got, Failed):
        return got
    info = got.info
    assert info is not None
    waypoints = []
    for number in range(1, info.count + 1):
        one = yield from read_waypoint(number)
        if isinstance(one, Failed):
            return one
        waypoints.append(one.waypoints[0])
    return Done(tuple(waypoints), info)


def write_mission(waypoints: tuple[Waypoint, ...]) -> Job:
    """MSP_SET_WP 1..n, each read back with MSP_WP, then MSP_WP_GETINFO: n, valid."""
    for wp in waypoints:
        reply = yield request("MSP_SET_WP", wp.pack())
        bad = _answer(reply, f"MSP_SET_WP {wp.number}")
        if bad is not None:
            return bad
    for wp in waypoints:
        one = yield from read_waypoint(wp.number)
        if isinstance(one, Failed):
            return one
        diff = waypoint_difference(wp, one.waypoints[0], verb="written")
        if diff is not None:
            return Failed(f"waypoint {wp.number} did not store as written: {diff}")
    got = yield from read_info()
    if isinstance(got, Failed):
        return got
    info = got.info
    assert info is not None
    if info.count != len(waypoints) or not info.valid:
        return Failed(f"after writing {len(waypoints)} waypoints MSP_WP_GETINFO reports {info.count}, "
                      f"valid {int(info.valid)}")
    return Done(tuple(waypoints), info)


def write_home(home: Waypoint) -> Job:
    """MSP_SET_WP 0, then MSP_WP 0: what the flight controller holds as home after it."""
    reply = yield request("MSP_SET_WP", home.pack())
    bad = _answer(reply, "MSP_SET_WP 0")
    if bad is not None:
        return bad
    return (yield from read_waypoint(0))


def nav_status() -> Job:
    reply = yield request("MSP_NAV_STATUS")
    bad = _answer(reply, "MSP_NAV_STATUS")
    if bad is not None:
        return bad
    return Done(payload=reply.payload)


class JobRunner:
    """Runs one job at a time: `start(job, now, done)`, then `reply(frame, now)` for each
    frame from the flight controller and `poll(now)` when `next_deadline()` passes."""

    def __init__(self, send: Callable[[MspFrame], object], *, timeout: float = REPLY_TIMEOUT,
                 retries: int = RETRIES) -> None:
        self._send = send
        self.timeout = timeout
        self.retries = retries
        self._job: Job | None = None
        self._done: Callable[[Result, float], None] | None = None
        self._asked: MspFrame | None = None
        self._tries = 0
        self._deadline: float | None = None
        self.requests = 0
        self.resent = 0

    @property
    def busy(self) -> bool:
        return self._job is not None

    def start(self, job: Job, now: float, done: Callable[[Result, float], None]) -> None:
        if self._job is not None:
            raise RuntimeError("an MSP job is already running")
        self._job, self._done = job, done
        self._advance(None, now, first=True)

    def reply(self, frame: MspFrame, now: float) -> None:
        """A frame from the flight controller: the answer if it is for the request asked."""
        if self._asked is not None and frame.command == self._asked.command:
            self._advance(frame, now)

    def next_deadline(self) -> float | None:
        return self._deadline

    def poll(self, now: float) -> None:
        if self._deadline is None or now < self._deadline or self._asked is None:
            return
        if self._tries <= self.retries:
            self._ask(self._asked, now)
            self.resent += 1
            return
        self._advance(None, now)

    def _advance(self, reply: MspFrame | None, now: float, *, first: bool = False) -> None:
        assert self._job is not None
        try:
            nxt = next(self._job) if first else self._job.send(reply)
        except StopIteration as stop:
            job_done, self._job, self._done = self._done, None, None
            self._asked, self._deadline = None, None
            assert job_done is not None
            job_done(stop.value, now)
            return
        self._tries = 0
        self._ask(nxt, now)

    def _ask(self, frame: MspFrame, now: float) -> None:
        self._asked = frame
        self._tries += 1
        self.requests += 1
        self._deadline = now + self.timeout
        self._send(frame)
