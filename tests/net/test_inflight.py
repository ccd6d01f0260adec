import pytest

from mavconform.reference_impl.net.inflight import InFlight


def test_settles_each_sent_datagram_once_per_direction():
    f = InFlight()
    f.sent("a", "b", b"x")
    f.sent("a", "b", b"x")          # the same bytes sent twice: two datagrams
    assert not f.settle("b", "a", b"x")              # other direction
    assert f.settle("a", "b", b"x") and f.settle("a", "b", b"x")
    assert not f.settle("a", "b", b"x")              # a third arrival: a copy the link made
    assert not f.settle("a", "c", b"y") and len(f) == 0


def test_keeps_the_newest_limit_per_direction():
    f = InFlight(limit=2)
    for data in (b"1", b"2", b"3"):
        f.sent("a", "outside", data)   # never settles: a peer the driver does not host
    f.sent("b", "outside", b"1")
    assert len(f) == 3
    assert not f.settle("a", "outside", b"1")        # forgotten: the oldest went first
    assert f.settle("a", "outside", b"3") and f.settle("b", "outside", b"1")


def test_limit_must_be_positive():
    with pytest.raises(ValueError):
        InFlight(limit=0)
