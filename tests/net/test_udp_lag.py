"""UdpDriver.lag: how late the driver served what was due, the host's share of a timing
verdict (conformance/host_lag.py). A host that stalls is modelled by a clock that jumps
forward while a node runs, as a descheduled process finds the clock when it runs again."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.net import UdpDriver

from .nodes import JumpingClock, TimerNode

pytestmark = pytest.mark.udp


class StallingTimer(TimerNode):
    """A timer node whose first poll stalls the host for `seconds`."""

    def __init__(self, deadlines: list[float], clock: JumpingClock, seconds: float) -> None:
        super().__init__(deadlines)
        self.clock, self.seconds = clock, seconds

    def poll(self, now: float) -> None:
        super().poll(now)
        if self.seconds:
            self.clock.stall(self.seconds)
            self.seconds = 0.0


def _lag_with_stall(seconds: float) -> tuple[float, float]:
    """(the driver's lag, how late the second timer was polled)"""
    clock = JumpingClock()
    with UdpDriver(clock) as drv:
        start = clock.now()
        drv.add_node(StallingTimer([start + 0.02], clock, seconds))
        later = TimerNode([start + 0.04])
        drv.add_node(later)
        drv.run_until(lambda: bool(later.polls), timeout=2.0)
        return drv.take_lag(), later.polls[0] - (start + 0.04)


def test_a_deadline_served_late_because_the_host_stalled_is_lag():
    lag, late = _lag_with_stall(0.5)
    # the second timer was due 0.02 s after the first: the 0.5 s stall made it 0.48 s late
    assert lag == pytest.approx(late, abs=1e-6)
    assert 0.45 <= lag < 0.5 + 0.05


def test_without_a_stall_the_driver_keeps_its_clock():
    lag, late = _lag_with_stall(0.0)
    assert lag < 0.05 and late < 0.05


def test_a_deadline_already_past_when_first_seen_is_not_lag():
    """A node that starts with a deadline long gone (the vehicle's first HEARTBEAT is due at
    0.0) is polled at once: the driver never promised to be there earlier."""
    clock = JumpingClock()
    with UdpDriver(clock) as drv:
        node = TimerNode([0.0])
        drv.add_node(node)
        drv.run_until(lambda: bool(node.polls), timeout=1.0)
        assert node.polls and drv.take_lag() < 0.05


def test_take_lag_starts_counting_afresh():
    clock = JumpingClock()
    with UdpDriver(clock) as drv:
        start = clock.now()
        drv.add_node(StallingTimer([start + 0.01], clock, 0.3))
        later = TimerNode([start + 0.02])
        drv.add_node(later)
        drv.run_until(lambda: bool(later.polls), timeout=2.0)
        assert drv.take_lag() >= 0.25
        assert drv.lag == 0.0 and drv.take_lag() == 0.0
