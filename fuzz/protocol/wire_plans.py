"""A fuzz step's wire items as the plan the reference client uploads (`wire_to_items`), and
the plan a vehicle stores when they came as MISSION_ITEM floats (`float_variant`)."""

from __future__ import annotations

import math
from typing import Any

from mavconform.reference_impl.mission.items import MissionItem, MissionType

from .versions import Plan

WIRE_FIELDS = ("frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z",
               "current", "autocontinue")


def wire_to_items(wire: list[dict[str, Any]], t: MissionType
                  ) -> tuple[list[MissionItem], dict[int, dict[str, int | float]]]:
    """Wire items -> the `MissionItem`s the client uploads, and the fields to rewrite on the
    way out: a "seq" or "mission_type" that differs from the transfer's (on either item
    message), and "fx"/"fy", floats that go out in MISSION_ITEM.x/y instead of the item's
    int x/y converted (MISSION_ITEM_INT keeps the int x/y; `fuzz.protocol.gcs.outgoing`)."""
    items, rewrite = [], {}
    for seq, d in enumerate(wire):
        items.append(MissionItem(seq, int(d["frame"]), int(d["command"]), float(d["param1"]),
                                 float(d["param2"]), float(d["param3"]), float(d["param4"]),
                                 int(d["x"]), int(d["y"]), float(d["z"]), int(d["current"]),
                                 int(d["autocontinue"]), t))
        over: dict[str, int | float] = {k: int(d[k]) for k in ("seq", "mission_type") if k in d}
        over.update((k, float(d[k])) for k in ("fx", "fy") if k in d)
        if over:
            rewrite[seq] = over
    return items, rewrite


def float_variant(plan: Plan, rewrite: dict[int, dict[str, Any]] | None = None, *,
                  truncate: bool = False) -> Plan | None:
    """The plan as a vehicle stores it when the items came as MISSION_ITEM (float x/y):
    each item's x/y as it went out (its int x/y converted, or the "fx"/"fy" override in
    `rewrite[seq]`), rounded to float32 by the wire and converted back the vehicle's way
    (`MissionItem.int_xy_from_float`, the spec vehicle's own). None if some item's x/y
    cannot be an int32 there (NaN, +-inf, 1e10, 215 deg): a vehicle must refuse that item
    (MAV_MISSION_INVALID_PARAM5_X / _PARAM6_Y), and one that accepts it stores a plan
    nobody can know, which then matches no candidate and is a finding.

    `truncate`: the conversion a C vehicle does, a float32 product cast to int32, which
    truncates toward zero (ArduPilot, GCS_Common.cpp `convert_MISSION_ITEM_to_MISSION_ITEM_INT`:
    `x = packet.x * 1.0e7f`): seen on ArduCopter SITL, a rally point sent as x = -1940
    degE7 by MISSION_ITEM came back as -1939."""
    from mavconform.reference_impl.mission.items import to_float32, xy_scale
    out = []
    for it in plan:
        fx, fy = it.float_xy()
        over = rewrite.get(it.seq) if rewrite else None
        if over:
            fx = to_float32(over["fx"]) if "fx" in over else fx
            fy = to_float32(over["fy"]) if "fy" in over else fy
        x, y = MissionItem.int_xy_from_float(it.frame, fx, fy)
        if x is None or y is None:
            return None
        if truncate:
            scale = to_float32(xy_scale(it.frame))
            x, y = (math.trunc(to_float32(fx * scale)), math.trunc(to_float32(fy * scale)))
        out.append(MissionItem(it.seq, it.frame, it.command, it.param1, it.param2, it.param3,
                               it.param4, x, y, it.z, it.current, it.autocontinue, it.mission_type))
    return tuple(out)
