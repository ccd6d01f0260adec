"""Mission items as the engines store and compare them.

The canonical form is MISSION_ITEM_INT's: params 1-4 and z are float32, x and y are int32
(degE7 for global frames, metres*1e4 for local frames, the raw value otherwise). Every item
that arrives as MISSION_ITEM (float) is converted into this form once, on receipt; every
MISSION_ITEM sent is converted out of it. Keeping one form means "downloaded == uploaded"
is a plain comparison, and the float path's precision loss shows up exactly where the
spec says it does (seed 000: "MISSION_ITEM_INT ... without the loss of precision").
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, replace
from enum import IntEnum
from typing import Iterable

from ..wire.dialect import mavlink as _d


class MissionType(IntEnum):
    """MAV_MISSION_TYPE: the three plan kinds the protocol stores independently."""

    MISSION = 0
    FENCE = 1
    RALLY = 2
    ALL = 255  # only meaningful for MISSION_CLEAR_ALL

    @property
    def label(self) -> str:
        return self.name.lower()


PLAN_TYPES: tuple[MissionType, ...] = (MissionType.MISSION, MissionType.FENCE, MissionType.RALLY)
# MissionType.MISSION bound once, for code that reads it for every frame or item: on Python 3.11
# a member read off its enum class is a slow metaclass lookup (about ten times a global's).
MISSION_PLAN = MissionType.MISSION
# Wire value -> plan type; a dict lookup is much cheaper than calling the enum.
PLAN_TYPE_BY_VALUE: dict[int, MissionType] = {int(t): t for t in PLAN_TYPES}

# MAV_FRAME values whose x/y are latitude/longitude (degE7 in MISSION_ITEM_INT).
GLOBAL_FRAMES = frozenset({0, 3, 5, 6, 10, 11})
# *_INT frame -> its plain frame: upstream common.xml supersedes 5, 6, 11 as "synonymous
# replacements" of 0, 3, 10 (a 15-byte command record cannot tell them apart either).
PLAIN_FRAME = {5: 0, 6: 3, 11: 10}
# MAV_FRAME values whose x/y are local metres (metres*1e4 in MISSION_ITEM_INT).
LOCAL_FRAMES = frozenset({1, 7, 8, 9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21})
# MAV_FRAME_MISSION: x/y are plain parameters, carried unscaled.
FRAME_MISSION = _d.MAV_FRAME_MISSION

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1

_F32 = struct.Struct("<f")


def to_float32(value: float) -> float:
    """Round a Python float to the nearest float32, as the wire does."""
    try:
        return _F32.unpack(_F32.pack(value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


def xy_scale(frame: int) -> float:
    """Factor between MISSION_ITEM's float x/y and MISSION_ITEM_INT's int x/y for a frame."""
    if frame in GLOBAL_FRAMES:
        return 1e7
    if frame in LOCAL_FRAMES:
        return 1e4
    return 1.0


def _float_key(value: float) -> float | str:
    return "nan" if value != value else value


@dataclass(frozen=True, slots=True)
class MissionItem:
    """One mission item in MISSION_ITEM_INT form. `seq` is its index in the plan."""

    seq: int
    frame: int
    command: int
    param1: float = 0.0
    param2: float = 0.0
    param3: float = 0.0
    param4: float = 0.0
    x: int = 0
    y: int = 0
    z: float = 0.0
    current: int = 0
    autocontinue: int = 1
    mission_type: MissionType = MissionType.MISSION

    def key(self) -> tuple:
        """Comparison key: NaN equals NaN (a NaN param means 'default' and survives a trip)."""
        return (
            self.seq, self.frame, self.command,
            _float_key(self.param1), _float_key(self.param2), _float_key(self.param3),
            _float_key(self.param4), self.x, self.y, _float_key(self.z),
            self.current, self.autocontinue, int(self.mission_type),
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MissionItem):
            return NotImplemented
        return self.key() == other.key()

    def __hash__(self) -> int:
        return hash(self.key())

    def float_xy(self) -> tuple[float, float]:
        """x, y as MISSION_ITEM carries them (float32 after the wire rounds them)."""
        scale = xy_scale(self.frame)
        return to_float32(self.x / scale), to_float32(self.y / scale)

    @staticmethod
    def int_xy_from_float(frame: int, x: float, y: float) -> tuple[int | None, int | None]:
        """MISSION_ITEM x/y to MISSION_ITEM_INT x/y; None where it cannot be represented."""
        scale = xy_scale(frame)
        return _scaled_int(x, scale), _scaled_int(y, scale)


def _scaled_int(value: float, scale: float) -> int | None:
    if not math.isfinite(value):
        return None
    scaled = round(value * scale)
    if scaled < INT32_MIN or scaled > INT32_MAX:
        return None
    return scaled


def renumber(items: Iterable[MissionItem], mission_type: MissionType | None = None) -> list[MissionItem]:
    """Items with seq 0..n-1 in the given order (and the given mission_type, if any)."""
    out = []
    for seq, item in enumerate(items):
        t = item.mission_type if mission_type is None else mission_type
        # most plans are numbered already: keep those items rather than copying them
        out.append(item if item.seq == seq and item.mission_type is t
                   else replace(item, seq=seq, mission_type=t))
    return out

