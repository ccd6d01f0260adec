"""The fuzz strategies reach the edge values they promise, and stay within the wire's types.

`find()` searches for an example with a property; each test fails if the strategy cannot
produce it within Hypothesis's default search (so a strategy that silently lost its NaNs,
its seq gaps or its COUNT 65535 is caught).
"""

from __future__ import annotations

import math

from hypothesis import HealthCheck, Phase, find, given, settings
from hypothesis import strategies as st
from hypothesis.errors import NoSuchExample

from mavconform.fuzz import strategies as fs
from mavconform.fuzz.protocol.faults import CutAfter, build_fault_model
from mavconform.fuzz.protocol.gcs import outgoing
from mavconform.fuzz.protocol.wire_plans import wire_to_items
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.items import (
    GLOBAL_FRAMES, INT32_MAX, INT32_MIN, LOCAL_FRAMES, MissionType, to_float32,
)
from mavconform.reference_impl.mission.validation import first_defect
from mavconform.reference_impl.wire.codec import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as _d

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


@settings(max_examples=60, suppress_health_check=list(HealthCheck))
@given(t=st.sampled_from(list(T)[:3]), data=st.data())
def test_a_long_valid_plan_is_drawn_from_a_few_items_yet_every_item_is_valid_and_its_own(t, data):
    """Issue 27: a 50-item plan costs the draws of TEMPLATES items; its copies stay items the
    spec vehicle accepts, no two alike, and step through every global frame."""
    plan = data.draw(fs.valid_wire_items(t, 50, 50))
    items, _ = wire_to_items(plan, t)
    assert len(items) == 50 and all(first_defect(it) is None for it in items)
    for k in range(fs.TEMPLATES):   # the copies of one template: each its own, every global frame
        copies = plan[k::fs.TEMPLATES]
        assert len({d["x"] for d in copies}) == len(copies)
        if copies[0]["frame"] in GLOBAL_FRAMES:
            assert {d["frame"] for d in copies} == set(GLOBAL_FRAMES)


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
            msg = outgoing(m.item_message(it, (1, 1), as_int=as_int), rewrite.get(it.seq, {}))
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


# --- out-of-range floats in every float field of MISSION_ITEM ------------------------------

# Counting over many draws needs a fixed seed to be repeatable: derandomized, generate only.
COVER = settings(FIND, derandomize=True)
OUT_OF_RANGE = {math.nan if v != v else v for v in fs.OUT_OF_RANGE_F32}
FLOAT_KEYS = ("param1", "param2", "param3", "param4", "z", "fx", "fy")   # fx/fy: MISSION_ITEM.x/y


def _key(value: float) -> float | str:
    return "nan" if value != value else value


OUT_KEYS = {_key(v) for v in OUT_OF_RANGE}


def _cover(strategy, seen_in, wanted: set, max_examples: int) -> None:
    """Draw (with a fixed seed) until every pair in `wanted` was seen; fail naming the rest.
    Five examples a draw: Hypothesis's own cost per draw is most of the time."""
    seen: set = set()

    def complete(examples) -> bool:
        for example in examples:
            seen.update(seen_in(example) & wanted)
        return seen >= wanted

    try:
        find(st.lists(strategy, min_size=5, max_size=5), complete,
             settings=settings(COVER, max_examples=max_examples // 5))
    except NoSuchExample:
        pass
    assert not wanted - seen, f"never drawn in {max_examples} examples: {sorted(map(str, wanted - seen))}"


def _kind(d: dict) -> str:
    return "global" if d["frame"] in GLOBAL_FRAMES else "local" if d["frame"] in LOCAL_FRAMES else "no-location"


def test_out_of_range_floats_are_float32_exact_and_out_of_int32_range():
    """Each survives the wire unchanged, and none is an int32 as degE7."""
    assert len(fs.OUT_OF_RANGE) == len(OUT_OF_RANGE) >= 15
    for value, why in fs.OUT_OF_RANGE:
        assert why
        assert value != value or to_float32(value) == value, value
        assert value != value or not math.isfinite(value) or not INT32_MIN <= value * 1e7 <= INT32_MAX
    for named in (1e10, -1e10, math.inf, -math.inf, 215.0, -215.0, 2.0**31, 3e9, fs.FLT_MAX):
        assert named in fs.OUT_OF_RANGE_F32
    assert "nan" in OUT_KEYS
    # and the edge floats of every float field draw them
    assert _find(fs.edge_f32, lambda v: v == 1e10) == 1e10
    assert _find(fs.edge_f32, lambda v: v == 2.0**31) == 2.0**31


def test_float_transfer_items_carry_every_out_of_range_value_in_every_float_field():
    """Every value in every float field, and the issue's values (1e10, +-inf, NaN, 215 deg)
    in x and y of items with a global or local location and without one. (Counted on
    `float_overrides`, which `float_wire_item` applies as drawn: a whole item costs ten
    times more to draw.)"""
    overrides = {kind: fs.float_overrides(kind) for kind in fs.XY_KINDS}

    @st.composite
    def by_kind(draw):
        kind = draw(st.sampled_from(fs.XY_KINDS))
        return kind, draw(overrides[kind])

    wanted = {(f, v) for f in FLOAT_KEYS for v in OUT_KEYS}
    wanted |= {(kind, f, _key(v)) for kind in fs.XY_KINDS for f in ("fx", "fy")
               for v in (1e10, -1e10, math.nan, math.inf, -math.inf, 215.0, -215.0)}
    _cover(by_kind(), lambda kd: {(f, _key(v)) for f, v in kd[1].items()}
           | {(kd[0], f, _key(v)) for f, v in kd[1].items()}, wanted, 40_000)
    # ... and the items carry them: each kind of item, in x and in y, in every plan type
    wanted = {(kind, f) for kind in fs.XY_KINDS for f in ("fx", "fy")}
    for t in (T.MISSION, T.FENCE, T.RALLY):
        _cover(fs.float_wire_item(t), lambda d: {(_kind(d), f) for f in ("fx", "fy")
                                                  if f in d and _key(d[f]) in OUT_KEYS}, wanted, 5_000)
    assert _key(_find(fs.float_wire_item(T.MISSION), lambda d: _key(d["z"]) in OUT_KEYS)["z"]) in OUT_KEYS


def test_float_overrides_are_exact_in_range_values_or_edges_and_fit_the_wire():
    """In-range overrides convert exactly (rounding and truncation agree), so the oracle's
    float plan is the only one a correct vehicle can store."""
    scale = {"global": 1e7, "local": 1e4, "no-location": 1.0}
    for kind in fs.XY_KINDS:
        for axis in ("x", "y"):
            for v in _find(st.lists(fs.exact_xy(kind, axis), min_size=50), lambda vs: len(set(vs)) > 40):
                assert to_float32(v) == v and v * scale[kind] == round(v * scale[kind]) == math.trunc(v * scale[kind])
                assert INT32_MIN <= v * scale[kind] <= INT32_MAX
            assert _find(fs.float_xy(kind, axis), lambda v: v in fs.PAST_RANGE_XY)
            try:   # no override that fits an int32 converts differently rounded and truncated
                bad = find(fs.float_xy(kind, axis), lambda v, k=scale[kind]: math.isfinite(v)
                           and INT32_MIN <= v * k <= INT32_MAX and round(v * k) != math.trunc(v * k),
                           settings=settings(FIND, max_examples=300))
                raise AssertionError(f"{kind} {axis}: {bad!r} converts to two integers")
            except NoSuchExample:
                pass
    item = _find(fs.float_wire_item(T.MISSION), lambda d: d.get("fx") == 1e10 and "fy" in d)
    (it,), rewrite = wire_to_items([item], T.MISSION)
    assert rewrite[0]["fx"] == 1e10
    enc, dec = FrameEncoder(245, 190), FrameDecoder()
    (frame,) = dec.feed(enc.encode(outgoing(m.item_message(it, (1, 1), as_int=False), rewrite[0])))
    assert frame.msg.x == 1e10 and _key(frame.msg.y) == _key(to_float32(item["fy"]))
    (frame,) = dec.feed(enc.encode(outgoing(m.item_message(it, (1, 1), as_int=True), rewrite[0])))
    assert (frame.msg.x, frame.msg.y) == (item["x"], item["y"])   # MISSION_ITEM_INT keeps its ints


def test_float_uploads_sometimes_carry_out_of_range_overrides_and_shrink_them_away():
    def overridden(op):
        return op.get("float") and any(_key(d[f]) in OUT_KEYS for d in op["items"] for f in ("fx", "fy") if f in d)
    found = _find(fs.upload_op(5), overridden)
    assert found["float"] and len(found["items"]) <= 5
    # a failing float upload that needs none of them shrinks to one without any
    small = find(fs.upload_op(5), lambda op: bool(op.get("float") and op["items"]),
                 settings=settings(FIND, phases=[Phase.generate, Phase.shrink]))
    assert not any("fx" in d or "fy" in d for d in small["items"])
    # valid-plan uploads (edges=False) never carry them
    valid = _find(fs.upload_op(5, edges=False), lambda op: op.get("float") and len(op["items"]) == 5)
    assert not any("fx" in d or "fy" in d for d in valid["items"])


def test_stray_float_items_carry_every_out_of_range_value_in_every_float_field():
    wanted = {(f, v) for f in fs.FLOAT_FIELDS for v in OUT_KEYS}
    _cover(fs.float_item_fields(), lambda d: {(f, _key(v)) for f, v in d.items()}, wanted, 20_000)
    raw = fs.raw_message()
    assert _find(raw, lambda r: r["msg"] == "MISSION_ITEM" and r["fields"]["x"] == 1e10)
    assert _find(raw, lambda r: r["msg"] == "MISSION_ITEM" and _key(r["fields"]["param3"]) == "nan")
