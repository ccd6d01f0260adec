import math
import random

import pymavlink.dialects.v20.common as common
import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import DropMessage, DropWhere, FaultModel, LinkStats, parse_drop_rule
from mavconform.reference_impl.wire import FrameEncoder

N = 20_000
DATA = bytes(range(40))


def run(model: FaultModel, n: int = N, seed: int = 1):
    rng = random.Random(seed)
    stats = LinkStats()
    out = [model.schedule(DATA, i * 0.001, rng, stats) for i in range(n)]
    return out, stats


def within(count: int, p: float, n: int = N) -> bool:
    """|count - np| under 5 standard deviations."""
    return abs(count - n * p) <= 5 * math.sqrt(n * p * (1 - p))


def frames(*msgs, sysid=1):
    enc = FrameEncoder(sysid, 1, dialect=common)
    return [enc.encode(m) for m in msgs]


def ack():
    return common.MAVLink_mission_ack_message(1, 1, 0, 0)


def request(seq):
    return common.MAVLink_mission_request_int_message(1, 1, seq, 0)


def test_clean_model_delivers_once_immediately():
    m = FaultModel()
    assert m.is_clean
    assert m.schedule(DATA, 0.0, random.Random(0)) == [(0.0, DATA)]
    assert not FaultModel(delay=0.01).is_clean
    assert not FaultModel(rules=(DropMessage("MISSION_ACK"),), dialect=common).is_clean


def test_loss_rate():
    out, stats = run(FaultModel(loss=0.1))
    dropped = sum(1 for copies in out if not copies)
    assert within(dropped, 0.1)
    assert stats.dropped == dropped


def test_duplicate_rate_and_copies_are_equal():
    out, stats = run(FaultModel(duplicate=0.2))
    doubled = [c for c in out if len(c) == 2]
    assert within(len(doubled), 0.2)
    assert stats.duplicated == len(doubled)
    assert all(a[1] == b[1] == DATA for a, b in doubled)
    assert all(len(c) in (1, 2) for c in out)


def test_reorder_rate_holds_back_by_reorder_delay():
    out, stats = run(FaultModel(reorder=0.3, reorder_delay=0.5, delay=0.01))
    delays = [c[0][0] for c in out]
    held = [d for d in delays if d > 0.01]
    assert within(len(held), 0.3)
    assert stats.reordered == len(held)
    assert set(delays) == {0.01, 0.51}


def test_corrupt_rate_flips_one_to_three_bytes():
    out, stats = run(FaultModel(corrupt=0.05))
    changed = [c[0][1] for c in out if c[0][1] != DATA]
    assert within(len(changed), 0.05)
    assert stats.corrupted == len(changed)
    flips = {sum(a != b for a, b in zip(d, DATA)) for d in changed}
    assert flips == {1, 2, 3}
    assert all(len(d) == len(DATA) for d in changed)


def test_delay_and_jitter_bounds():
    out, _ = run(FaultModel(delay=0.2, jitter=0.1))
    delays = [c[0][0] for c in out]
    assert min(delays) >= 0.2 and max(delays) <= 0.3
    assert max(delays) - min(delays) > 0.09  # jitter really spreads


def test_partition_drops_exactly_in_window():
    m = FaultModel(partitions=((1.0, 2.0), (5.0, math.inf)))
    rng = random.Random(0)
    for t, dropped in [(0.999, False), (1.0, True), (1.5, True), (1.9999, True), (2.0, False),
                       (4.9, False), (5.0, True), (1e9, True)]:
        assert (m.schedule(DATA, t, rng) == []) is dropped, t


def test_same_seed_same_schedule_different_seed_differs():
    m = FaultModel(loss=0.1, duplicate=0.1, reorder=0.1, corrupt=0.1, delay=0.01, jitter=0.02)
    a, _ = run(m, 2000, seed=7)
    b, _ = run(m, 2000, seed=7)
    c, _ = run(m, 2000, seed=8)
    assert a == b
    assert a != c


def test_rule_drops_every_named_message():
    m = FaultModel(rules=(DropMessage("MISSION_ACK"),), dialect=common)
    rng = random.Random(0)
    datagrams = frames(ack(), request(0), ack())
    assert [m.schedule(d, 0.0, rng) == [] for d in datagrams] == [True, False, True]


def test_rule_drops_only_the_nth():
    m = FaultModel(rules=(parse_drop_rule("MISSION_REQUEST_INT#2", common),), dialect=common)
    rng = random.Random(0)
    datagrams = frames(request(0), ack(), request(1), request(1), request(2))
    assert [m.schedule(d, 0.0, rng) == [] for d in datagrams] == [False, False, True, False, False]


def test_rule_drops_nth_onwards():
    m = FaultModel(rules=(DropMessage("MISSION_REQUEST_INT", nth=3, onwards=True),), dialect=common)
    rng = random.Random(0)
    datagrams = frames(*(request(i) for i in range(6)))
    assert [m.schedule(d, 0.0, rng) == [] for d in datagrams] == [False, False, True, True, True, True]


def test_drop_where_predicate_and_limit():
    rule = DropWhere(lambda msg: msg.get_type() == "MISSION_REQUEST_INT" and msg.seq == 1, limit=2)
    m = FaultModel(rules=(rule,), dialect=common)
    rng = random.Random(0)
    datagrams = frames(request(1), request(0), request(1), request(1))
    assert [m.schedule(d, 0.0, rng) == [] for d in datagrams] == [True, False, True, False]


def test_datagram_dropped_if_any_frame_matches_and_all_frames_counted():
    rule = DropMessage("MISSION_ACK", nth=2)
    m = FaultModel(rules=(rule,), dialect=common)
    rng = random.Random(0)
    a, r = frames(ack(), request(0))
    assert m.schedule(r + a, 0.0, rng) != []   # 1st ACK
    assert m.schedule(r + a, 0.0, rng) == []   # 2nd ACK, second frame of the datagram
    assert rule.seen == 2


def test_rules_ignore_garbage():
    m = FaultModel(rules=(DropMessage("MISSION_ACK"),), dialect=common)
    assert m.schedule(b"\x00garbage\xfd\x09", 0.0, random.Random(0)) == [(0.0, b"\x00garbage\xfd\x09")]


def test_copy_has_fresh_counters():
    m = FaultModel(loss=0.0, rules=(DropMessage("MISSION_ACK", nth=1),), dialect=common)
    rng = random.Random(0)
    (a,) = frames(ack())
    assert m.schedule(a, 0.0, rng) == []
    other = m.copy()
    assert str(other.rules[0]) == "MISSION_ACK#1" and other.rules[0] is not m.rules[0]
    assert other.schedule(a, 0.0, rng) == []    # its own 1st ACK
    assert m.schedule(a, 0.0, rng) != []        # the original's 2nd


@pytest.mark.parametrize("text, name, nth, onwards", [
    ("MISSION_ACK", "MISSION_ACK", None, False),
    ("MISSION_REQUEST_INT#2", "MISSION_REQUEST_INT", 2, False),
    ("MISSION_ITEM_INT#3+", "MISSION_ITEM_INT", 3, True),
    (" mission_ack#1 ", "MISSION_ACK", 1, False),
])
def test_parse_drop_rule_good(text, name, nth, onwards):
    rule = parse_drop_rule(text, common)
    assert (rule.name, rule.nth, rule.onwards) == (name, nth, onwards)


@pytest.mark.parametrize("text, what", [
    ("", "expected NAME"),
    ("#2", "expected NAME"),
    ("MISSION_ACK#", "expected NAME"),
    ("MISSION_ACK#x", "expected NAME"),
    ("MISSION_ACK#2+3", "expected NAME"),
    ("MISSION_ACK#0", "count from 1"),
    ("MISSION_ACKK", "no message named MISSION_ACKK"),
    ("MISSION_ACK\n#2", "expected NAME"),
])
def test_parse_drop_rule_bad(text, what):
    with pytest.raises(UsageError) as info:
        parse_drop_rule(text, common)
    assert what in str(info.value)
    assert repr(text) in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("kwargs, what", [
    ({"loss": 1.5}, "loss"),
    ({"loss": -0.1}, "loss"),
    ({"duplicate": float("nan")}, "duplicate"),
    ({"reorder": 2}, "reorder"),
    ({"corrupt": -1}, "corrupt"),
    ({"delay": -0.1}, "delay"),
    ({"jitter": math.inf}, "jitter"),
    ({"reorder_delay": -1}, "reorder_delay"),
    ({"partitions": ((2.0, 1.0),)}, "partition"),
    ({"partitions": ((-1.0, 1.0),)}, "partition"),
    ({"partitions": ((1.0,),)}, "partition"),
    ({"rules": ("MISSION_ACK",)}, "rule"),
])
def test_validation(kwargs, what):
    with pytest.raises(ValueError, match=what):
        FaultModel(**kwargs)


def test_rule_validation():
    with pytest.raises(ValueError):
        DropMessage("MISSION_ACK", nth=0)
    with pytest.raises(ValueError):
        DropMessage("MISSION_ACK", onwards=True)
    with pytest.raises(ValueError):
        DropWhere(lambda m: True, limit=-1)
