import math

import pytest

from mavconform.reference_impl.net import MonotonicClock, SimClock


def test_simclock_starts_and_advances():
    c = SimClock()
    assert c.now() == 0.0
    assert c.wall() == 1767225600.0
    c.advance(1.5)
    c.advance_to(2.0)
    assert c.now() == 2.0
    assert c.wall() == 1767225602.0


def test_simclock_start_and_epoch():
    c = SimClock(start=10.0, wall_epoch=100.0)
    assert (c.now(), c.wall()) == (10.0, 110.0)


def test_simclock_never_goes_backwards():
    c = SimClock(start=5.0)
    c.advance_to(5.0)  # standing still is fine
    with pytest.raises(ValueError, match="backwards"):
        c.advance_to(4.999)
    with pytest.raises(ValueError):
        c.advance(-0.1)
    with pytest.raises(ValueError):
        c.advance_to(math.inf)
    assert c.now() == 5.0


def test_monotonic_clock_is_monotonic_and_wall_is_unix():
    c = MonotonicClock()
    a, b = c.now(), c.now()
    assert b >= a
    assert c.wall() > 1.6e9


def test_scaled_clock_lives_speed_seconds_in_every_real_one(monkeypatch):
    """Issue 27: an in-process vehicle and its testers share a faster clock; deadlines and
    signing timestamps move together."""
    from mavconform.reference_impl.net.clock import ScaledClock
    real = {"mono": 100.0, "wall": 1767225600.0}
    monkeypatch.setattr("time.monotonic", lambda: real["mono"])
    monkeypatch.setattr("time.time", lambda: real["wall"])
    c = ScaledClock(4.0)
    start, wall = c.now(), c.wall()
    real["mono"] += 2.5
    real["wall"] += 2.5
    assert c.now() - start == 10.0 and c.wall() - wall == 10.0
    assert c.speed == 4.0 and MonotonicClock.speed == 1.0


@pytest.mark.parametrize("speed", [0.0, -1.0, math.nan, math.inf])
def test_scaled_clock_refuses_a_speed_that_is_no_speed(speed):
    from mavconform.reference_impl.net.clock import ScaledClock
    with pytest.raises(ValueError, match="speed"):
        ScaledClock(speed)
