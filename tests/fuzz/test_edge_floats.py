"""Out-of-range floats (1e10, +-inf, NaN, 215 deg) in MISSION_ITEM, through the protocol fuzzer.

Real autopilots turn MISSION_ITEM's floats into integers (degE7, metres * 1e4, cm); a float
no int32 can hold must be refused (MAV_MISSION_INVALID_PARAM5_X / _PARAM6_Y), because a
vehicle that accepts it stores a plan nobody sent. Here, in virtual time:

- the GCS puts a wire item's "fx"/"fy" into MISSION_ITEM.x/y (never into MISSION_ITEM_INT);
- the oracle's float plan uses them, converted the vehicle's way, and has no plan at all
  for x/y that cannot be an int32;
- the spec vehicle refuses such an item in a global frame, a local frame and for a command
  without a location, and that is no finding; in-range overrides are stored and match;
- a vehicle that converts them anyway (saturating, as a C cast on ARM does) is a finding;
- short searches on builtin:spec and builtin:px4 send such uploads and find nothing.
"""

from __future__ import annotations

import math

import pytest

from mavconform.conformance.mutants import MUTANTS, Mutant, server_mutant
from mavconform.fuzz import strategies as fs
from mavconform.fuzz.case import Case
from mavconform.fuzz.protocol import Knobs, replay, search
from mavconform.fuzz.protocol import machine as machine_module
from mavconform.fuzz.protocol.gcs import outgoing
from mavconform.fuzz.protocol.steps import Runner
from mavconform.fuzz.protocol.wire_plans import float_variant, wire_to_items
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import INT32_MAX, INT32_MIN, MissionItem, MissionType, xy_scale
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.wire.dialect import mavlink as _d

WAYPOINT = {"frame": 3, "command": 16, "current": 0, "autocontinue": 1, "param1": 0.0,
            "param2": 0.0, "param3": 0.0, "param4": float("nan"), "x": 473977420,
            "y": 85455940, "z": 50.0}
LOCAL = dict(WAYPOINT, frame=1, x=100_000, y=-20_000)                   # metres * 1e4
SPEED = dict(WAYPOINT, frame=2, command=178, param1=1.0, param2=5.0,    # DO_CHANGE_SPEED: no location
             param3=-1.0, param4=0.0, x=0, y=0, z=0.0)
BAD = (1e10, float("nan"), float("inf"), float("-inf"), 215.0, -1e10)
LAX = "test-casts-float-xy"


def float_upload(*items: dict) -> dict:
    """A float (MISSION_ITEM) upload of a plain waypoint and `items`."""
    return {"op": "upload", "type": 0, "float": True, "items": [dict(WAYPOINT), *items]}


DOWNLOAD = {"op": "download", "type": 0}


def run(target: str, *steps: dict) -> Runner:
    runner = Runner(target, 3)
    for i, step in enumerate(steps):
        assert runner.apply(step) is None, (i, step)
        assert runner.check() is None, (i, step)
    return runner


def upload_result(target: str, item: dict):
    runner = run(target, float_upload(item))
    try:
        return runner.world.a.results[-1], runner.world.stored(MissionType.MISSION)
    finally:
        runner.close()


# --- a vehicle that converts what it should refuse -------------------------------------------

def _cast(value: float, scale: float) -> int:
    """A C float-to-int32 cast as ARM's VCVT does it: NaN -> 0, saturated at the limits."""
    if value != value:
        return 0
    scaled = value * scale
    if scaled >= INT32_MAX:
        return INT32_MAX
    if scaled <= INT32_MIN:
        return INT32_MIN
    return int(round(scaled))


class _CastsFloatXY(MissionServer):
    """Takes MISSION_ITEM's x/y as a cast to int32 (no range check) and checks no item rule."""

    def _on_item(self, msg, src, now):
        if msg._type == m.ITEM_FLOAT:
            scale = xy_scale(msg.frame)
            msg = _d.MAVLink_mission_item_int_message(
                msg.target_system, msg.target_component, msg.seq, msg.frame, msg.command, msg.current,
                msg.autocontinue, msg.param1, msg.param2, msg.param3, msg.param4,
                _cast(msg.x, scale), _cast(msg.y, scale), msg.z, msg.mission_type)
        return super()._on_item(msg, src, now)


@pytest.fixture
def lax(monkeypatch) -> str:
    """`mutant:` target for the lax vehicle, registered for this test only."""
    monkeypatch.setitem(MUTANTS, LAX, Mutant(LAX, "casts MISSION_ITEM x/y to int32 unchecked", frozenset(),
                                             server_mutant(_CastsFloatXY, item_rules=())))
    return f"mutant:{LAX}"


# --- the GCS and the oracle's candidate plans --------------------------------------------------

def test_fx_fy_replace_mission_item_x_y_only():
    items, rewrite = wire_to_items([dict(WAYPOINT, fx=1e10, fy=float("nan"), seq=4)], MissionType.MISSION)
    assert rewrite == {0: {"seq": 4, "fx": 1e10, "fy": rewrite[0]["fy"]}} and math.isnan(rewrite[0]["fy"])
    as_float = outgoing(m.item_message(items[0], (1, 1), as_int=False), rewrite[0])
    assert (as_float.x, as_float.seq) == (1e10, 4) and math.isnan(as_float.y)
    as_int = outgoing(m.item_message(items[0], (1, 1), as_int=True), rewrite[0])
    assert (as_int.x, as_int.y, as_int.seq) == (WAYPOINT["x"], WAYPOINT["y"], 4)


@pytest.mark.parametrize("base", [WAYPOINT, LOCAL, SPEED], ids=["global", "local", "no-location"])
def test_float_variant_converts_overrides_the_vehicles_way_and_has_no_plan_past_int32(base):
    (item,), _ = wire_to_items([base], MissionType.MISSION)
    for value in fs.OUT_OF_RANGE_F32:
        x, _ = MissionItem.int_xy_from_float(item.frame, value, 0.0)
        variant = float_variant((item,), {0: {"fx": value}})
        assert (variant is None) == (x is None), value
        if x is None:   # no int32 holds it: only a refusal is right
            assert float_variant((item,), {0: {"fy": value}}) is None
    (exact,) = float_variant((item,), {0: {"fx": 47.5, "fy": -8.25}})
    scale = xy_scale(item.frame)
    assert (exact.x, exact.y) == (round(47.5 * scale), round(-8.25 * scale))
    assert float_variant((item,), {0: {"fx": 47.5}})[0].y == float_variant((item,))[0].y   # fy: its own


# --- the spec vehicle refuses; no finding ------------------------------------------------------

@pytest.mark.parametrize("value", BAD)
@pytest.mark.parametrize("key,code", [("fx", MissionResult.INVALID_PARAM5_X), ("fy", MissionResult.INVALID_PARAM6_Y)])
def test_the_spec_vehicle_refuses_out_of_range_x_y_in_a_global_frame(value, key, code):
    result, stored = upload_result("builtin:spec", dict(WAYPOINT, **{key: value}))
    assert not result.ok and result.nack == code and not result.outcome_unknown
    assert stored == ()


@pytest.mark.parametrize("target", ["builtin:spec", "builtin:px4"])
@pytest.mark.parametrize("value", [1e10, float("nan"), float("inf")])
def test_a_float_upload_with_out_of_range_fx_is_refused_and_no_finding(target, value):
    case = Case("protocol", target, 7, (float_upload(dict(WAYPOINT, fx=value)), DOWNLOAD,
                                         {"op": "upload", "type": 0, "items": [WAYPOINT]}, DOWNLOAD))
    assert replay(case) is None


def test_local_frames_and_commands_without_a_location():
    """Spec vehicle: past int32 after * 1e4 (local) or as it is (params 5/6 of a command
    without a location, NaN included: MISSION_ITEM_INT has no NaN) is PARAM5_X; a local
    frame in range is UNSUPPORTED_FRAME; a plain param 5 in range is stored as sent."""
    for value in (1e10, float("nan"), float("-inf"), 214749.0, 2.0**31):
        result, _ = upload_result("builtin:spec", dict(LOCAL, fx=value))
        assert result.nack == MissionResult.INVALID_PARAM5_X, value
    result, _ = upload_result("builtin:spec", dict(LOCAL, fx=215.0))
    assert result.nack == MissionResult.UNSUPPORTED_FRAME
    for value in (1e10, float("nan"), float("inf"), 2.0**31, -2.0**31 - 256, 3e9, fs.FLT_MAX):
        result, _ = upload_result("builtin:spec", dict(SPEED, fy=value))
        assert result.nack == MissionResult.INVALID_PARAM6_Y, value
    for value in (215.0, 65536.0, 21474838.0):
        result, stored = upload_result("builtin:spec", dict(SPEED, fx=value))
        assert result.ok and stored[1].x == int(value)


def test_in_range_overrides_are_stored_as_converted_and_match():
    runner = run("builtin:spec", float_upload(dict(WAYPOINT, fx=47.5, fy=-8.25), dict(SPEED, fx=215.0)),
                 DOWNLOAD)
    stored = runner.world.stored(MissionType.MISSION)
    assert (stored[1].x, stored[1].y, stored[2].x) == (475_000_000, -82_500_000, 215)
    assert runner.world.a.results[-1].items == stored
    runner.close()


def test_stray_float_items_with_out_of_range_fields_are_no_finding():
    strays = [{"msg": "MISSION_ITEM", "to": "target", "from": who, "fields": dict(
        WAYPOINT, seq=seq, x=x, y=1e10, param1=2.0**31, z=float("inf"), mission_type=0)}
        for who, seq, x in (("a", 0, float("nan")), ("mute", 1, -1e10), ("b", 0, 215.0))]
    steps = ({"op": "stray", "messages": strays, "during": None, "after": 0.0},
             {"op": "stray", "messages": strays, "during": float_upload(dict(SPEED, fy=float("nan"))), "after": 0.01},
             DOWNLOAD)
    for target in ("builtin:spec", "builtin:px4"):
        assert replay(Case("protocol", target, 2, steps)) is None


# --- a vehicle that takes them is a finding -----------------------------------------------------

@pytest.mark.parametrize("value", [1e10, float("nan"), float("inf")])
def test_a_vehicle_that_converts_out_of_range_x_is_a_finding(lax, value):
    case = Case("protocol", lax, 7, (float_upload(dict(WAYPOINT, fx=value)), DOWNLOAD))
    v = replay(case)
    assert v is not None and v.invariant == "atomic-upload" and v.step == 0, v
    assert "invented" in v.detail
    # over the wire (no look at the store) the download that follows gives it away
    race = Case("protocol", lax, 7, ({"op": "second_gcs", "first": float_upload(dict(WAYPOINT, fx=value)),
                                      "second": DOWNLOAD, "after": 20.0},))
    v = replay(race)
    assert v is not None and v.invariant == "download-matches-upload", v


def test_the_lax_vehicle_is_no_finding_where_it_is_right(lax, monkeypatch):
    """In range, its conversion is the spec's: the oracle's float plan matches."""
    assert replay(Case("protocol", lax, 7, (float_upload(dict(WAYPOINT, fx=47.5), dict(SPEED, fx=215.0)),
                                             DOWNLOAD))) is None
    # relaxed item rules alone do not let 1e10 in: the conversion is what refuses it
    monkeypatch.setitem(MUTANTS, LAX, Mutant(LAX, "checks no item rule", frozenset(),
                                             server_mutant(MissionServer, item_rules=())))
    result, stored = upload_result(lax, dict(WAYPOINT, fx=1e10))
    assert result.nack == MissionResult.INVALID_PARAM5_X and stored == ()


# --- short searches -----------------------------------------------------------------------------

@pytest.mark.parametrize("target", ["builtin:spec", "builtin:px4"])
def test_short_searches_send_out_of_range_x_y_in_float_uploads_and_find_nothing(target, monkeypatch):
    """Each search finds nothing; within a few seeds one has sent an x/y no int32 holds.
    (Which seed does depends on more than the seed: Hypothesis also draws constants from
    the modules loaded, so a fixed seed's program differs between test selections.)"""
    sent: list[dict] = []

    class Recording(Runner):
        def apply(self, step):
            sent.append(step)
            return super().apply(step)

    def uploads(step):
        for key in ("of", "first", "second", "during"):
            if isinstance(step.get(key), dict):
                yield from uploads(step[key])
        if step.get("op") == "upload":
            yield step

    monkeypatch.setattr(machine_module, "Runner", Recording)
    for seed in range(1, 11):
        assert search(target, seed=seed, max_examples=40, knobs=Knobs(max_items=6, steps=8)) == []
        unrepresentable = [(d["frame"], d[f]) for s in sent for u in uploads(s) if u.get("float")
                           for d in u["items"] for f in ("fx", "fy")
                           if f in d and MissionItem.int_xy_from_float(d["frame"], d[f], 0.0)[0] is None]
        if unrepresentable:
            return
    pytest.fail("ten searches of 40 examples sent no float upload with an x/y that no int32 holds")
