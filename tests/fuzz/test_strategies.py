"""The fuzz strategies reach the edge values they promise, and stay within the wire's types.

`find()` searches for an example with a property; each test fails if the strategy cannot
produce it within Hypothesis's default search (so a strategy that silently lost its NaNs,
its seq gaps or its COUNT 65535 is caught).
"""

from __future__ import annotations

import math

from hypothesis import HealthCheck, Phase, find, given, settings
from hypothesis import strategies as st

from fuzz import strategies as fs
from fuzz.protocol.faults import CutAfter, build_fault_model
from fuzz.protocol.steps import wire_to_items
from reference_impl.mission import messages as m
from reference_impl.mission.items import INT32_MAX, INT32_MIN, MissionType
from reference_impl.mission.validation import first_defect
from reference_impl.wire.codec import FrameDecoder, FrameEncoder
from reference_impl.wire.dialect import mavlink as _d

# the first example found is enough: no shrinking (which is most of find()'s time)
FIND = settings(max_examples=5000, database=None, phases=[Phase.generate],
                suppress_health_check=list(HealthCheck))
T = MissionType


def _find(strategy, condition):
    return find(strategy, condition, settings=FIND)


def test_edge_floats_include_nan_infinities_and_subnormals():
    assert math.isnan(_find(fs.edge_f32, math.isnan))
    assert _find(fs.edge_f32, lambda v: v == math.inf) == math.inf
    assert _find(fs.edge_f32, lambda v: v == -math.inf) == -math.inf
    sub = _find(fs.edge_f32, lambda v: v != 0 and abs(v) < fs.FLT_MIN_NORMAL)
    assert 0 < abs(sub) < fs.FLT_MIN_NORMAL
    assert _find(fs.edge_f32, lambda v: v == fs.FLT_MAX) == fs.FLT_MAX


def test_edge_ints_reach_both_extremes_and_negatives():
    assert _find(fs.edge_i32, lambda v: v == INT32_MIN) == INT32_MIN
    assert _find(fs.edge_i32, lambda v: v == INT32_MAX) == INT32_MAX
    assert _find(fs.edge_i32, lambda v: v == -900_000_001) == -900_000_001   # just past -90 deg
    assert _find(fs.edge_u16, lambda v: v == 65535) == 65535


def test_wire_items_carry_a_nan_param_unknown_commands_frames_and_flags():
    item = fs.wire_item(T.MISSION)
    assert math.isnan(_find(item, lambda d: math.isnan(d["param1"]))["param1"])
    found = _find(item, lambda d: d["command"] not in fs.KNOWN_COMMANDS)
    assert found["command"] not in fs.KNOWN_COMMANDS
    assert _find(item, lambda d: d["frame"] > 21)["frame"] > 21
    assert _find(item, lambda d: d["current"] > 1)["current"] > 1
    assert _find(item, lambda d: d["autocontinue"] > 1)["autocontinue"] > 1
    # and edge items are refused by the spec vehicle's validation, not just odd-looking
    edge = _find(fs.edge_wire_item(T.MISSION), lambda d: math.isinf(d["param2"]))
    (it,), _ = wire_to_items([edge], T.MISSION)
    assert first_defect(it) is not None


def test_wire_plans_have_seq_gaps_repeats_and_foreign_mission_types():
    plan = fs.wire_plan(T.MISSION, max_size=10)
    gap = _find(plan, lambda p: any(d.get("seq", i) > i for i, d in enumerate(p)))
    assert any(d.get("seq", i) > i for i, d in enumerate(gap))
    repeat = _find(plan, lambda p: any(i > 0 and d.get("seq", i) == i - 1 for i, d in enumerate(p)))
    assert any(d.get("seq") == i - 1 for i, d in enumerate(repeat))
    other = _find(plan, lambda p: any(d.get("mission_type", 0) != 0 for d in p))
    assert any(d.get("mission_type", 0) != 0 for d in other)


@settings(max_examples=150, suppress_health_check=list(HealthCheck))
@given(plan=st.sampled_from(list(T)[:3]).flatmap(lambda t: fs.wire_plan(t, max_size=6)),
       raw=fs.raw_message())
def test_everything_drawn_fits_its_wire_fields(plan, raw):
    """Edge values are edge values of the field's wire type: packing never fails."""
    enc, dec = FrameEncoder(245, 190), FrameDecoder()
    items, rewrite = wire_to_items(plan, T.MISSION)
    for it in items:
        for as_int in (True, False):
            msg = m.item_message(it, (1, 1), as_int=as_int)
            for name, value in rewrite.get(it.seq, {}).items():
                setattr(msg, name, value)
            (frame,) = dec.feed(enc.encode(msg))
            assert frame.msg.seq == rewrite.get(it.seq, {}).get("seq", it.seq)
    cls = getattr(_d, f"MAVLink_{raw['msg'].lower()}_message")
    (frame,) = dec.feed(enc.encode(cls(target_system=1, target_component=1, **raw["fields"])))
    assert frame.msg.get_type() == raw["msg"]


def test_stray_messages_include_count_65535_and_wrong_targets():
    raw = fs.raw_message()
    assert _find(raw, lambda r: r["msg"] == "MISSION_COUNT" and r["fields"]["count"] == 65535)
    assert _find(raw, lambda r: r["to"] == "other-system")["to"] == "other-system"
    found = _find(raw, lambda r: r["msg"] == "MISSION_REQUEST_INT" and r["fields"]["seq"] > 1000)
    assert found["fields"]["seq"] > 1000


def test_fault_schedules_have_bursts_scripted_drops_and_cuts():
    sched = fs.fault_schedules()
    burst = _find(sched, lambda s: len(s.get("bursts", ())) == 2)
    model = build_fault_model(burst, now=100.0)
    assert len(model.partitions) == 2 and all(start >= 100.0 for start, _ in model.partitions)
    cut = _find(sched, lambda s: s.get("cut") is not None and s["cut"]["name"] == "MISSION_ACK")
    assert any(isinstance(r, CutAfter) for r in build_fault_model(cut, 0.0).rules)
    drop = _find(sched, lambda s: any(d["nth"] == 2 and d["name"] == "MISSION_ACK" for d in s.get("drops", ())))
    assert build_fault_model(drop, 0.0).rules
    assert build_fault_model(None, 0.0).is_clean


def test_cut_after_drops_from_the_chosen_message_for_span_messages():
    cut = CutAfter("MISSION_ACK", nth=2, span=3)
    ack = _d.MAVLink_mission_ack_message(1, 1, 0, 0, 0)
    item = _d.MAVLink_mission_request_int_message(1, 1, 0, 0)
    seen = [cut.observe(msg) for msg in (ack, item, ack, item, item, item, ack)]
    assert seen == [False, False, True, True, True, False, False]
    assert cut.fresh().seen == 0


def test_operation_sequences_cover_every_step_kind():
    kinds = {"upload", "download", "clear", "set_current", "cancel", "second_gcs", "stray",
             "faults", "wait"}
    for kind in kinds:
        found = _find(fs.operation_sequences(5, 4), lambda p, k=kind: any(s["op"] == k for s in p))
        assert any(s["op"] == kind for s in found)
