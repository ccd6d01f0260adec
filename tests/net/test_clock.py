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
