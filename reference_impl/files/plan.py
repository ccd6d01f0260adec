"""The `Plan` model shared by the file formats, and the number conversions they share.

Both formats store latitude/longitude as decimal degrees while `MissionItem` stores degE7
ints. The conversions here go through `Decimal` so that reading text never loses more than
the degE7 rounding itself, and writing emits the exact decimal of the int: a file written
here reads back to the very same items (the round trip the tests hold us to).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from decimal import ROUND_HALF_EVEN, Decimal, InvalidOperation
from typing import Iterable

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.items import (
    INT32_MAX, INT32_MIN, MissionItem, MissionType, renumber, to_float32, xy_scale,
)


class PlanFileError(UsageError):
    """A mission file that cannot be read or written. `str()` is one line starting with the path."""

    def __init__(self, message: str) -> None:
        # One line is part of the contract (the CLI prints it as is); never let a quoted value
        # or an OS message break it.
        super().__init__(" ".join(message.splitlines()))


@dataclass(frozen=True)
class MissionSettings:
    """What a .plan says about the vehicle the plan is for (QGC's mission settings).

    QGC's loader requires `firmwareType` and reads the rest; the defaults are what QGC
    writes for an offline plan with no vehicle: MAV_AUTOPILOT_GENERIC, MAV_TYPE_GENERIC and
    its offline-editing speeds (QGC AppSettings offlineEditingCruiseSpeed / HoverSpeed).
    A download fills the types from the vehicle's HEARTBEAT (autopilot, type)."""

    firmware_type: int = 0           # MAV_AUTOPILOT
    vehicle_type: int = 0            # MAV_TYPE
    cruise_speed: float = 15.0       # m/s
    hover_speed: float = 5.0         # m/s


@dataclass(frozen=True)
class Plan:
    """Mission, fence and rally items as one unit, as a GCS plan file holds them."""

    mission: list[MissionItem] = field(default_factory=list)
    fence: list[MissionItem] = field(default_factory=list)
    rally: list[MissionItem] = field(default_factory=list)
    home: tuple[float, float, float] | None = None  # lat, lon, alt (.plan plannedHomePosition)
    settings: MissionSettings = MissionSettings()
    # What reading left out on purpose and the user should hear about (e.g. a version-1
    # geoFence, skipped as QGC skips it). Not part of the plan: equal plans may differ here.
    notes: tuple[str, ...] = field(default=(), compare=False)

    def items(self, t: MissionType) -> list[MissionItem]:
        """The items of one plan kind (MISSION, FENCE or RALLY)."""
        if t is MissionType.MISSION:
            return self.mission
        if t is MissionType.FENCE:
            return self.fence
        if t is MissionType.RALLY:
            return self.rally
        raise ValueError(f"a plan has no single item list for {t!r}")

    def with_items(self, t: MissionType, items: Iterable[MissionItem]) -> Plan:
        """A copy with one kind's items replaced (renumbered 0..n-1 and typed `t`)."""
        self.items(t)  # rejects ALL
        return replace(self, **{t.label: renumber(items, t)})


def plan_from_items(
    mission: Iterable[MissionItem] = (),
    fence: Iterable[MissionItem] = (),
    rally: Iterable[MissionItem] = (),
    home: tuple[float, float, float] | None = None,
    settings: MissionSettings = MissionSettings(),
    notes: Iterable[str] = (),
) -> Plan:
    """A plan whose lists are numbered 0..n-1 and carry their mission_type, whatever came in."""
    return Plan(
        mission=renumber(mission, MissionType.MISSION),
        fence=renumber(fence, MissionType.FENCE),
        rally=renumber(rally, MissionType.RALLY),
        home=home,
        settings=settings,
        notes=tuple(notes),
    )


# --- numbers shared by the formats ---------------------------------------------------------

_XY_MAX_DIGITS = 12  # beyond this many integer digits no x/y fits int32 at any scale


def xy_decimals(frame: int) -> int:
    """Decimal places of x/y in a file for a frame: 7 (degE7), 4 (metres*1e4) or 0 (raw)."""
    return round(math.log10(xy_scale(frame)))


def parse_decimal(text: str) -> Decimal | None:
    """A number as written in a file, exactly; None if it is not one."""
    try:
        value = Decimal(text.strip())
    except (InvalidOperation, ValueError):
        return None
    return None if value.is_snan() else value  # a signalling NaN cannot even become a float


def xy_from_decimal(frame: int, value: Decimal) -> int | None:
    """File x/y (degrees, metres or raw) to MISSION_ITEM_INT's int; None if it cannot be one.

    Exact decimal scaling, rounded half-even like `MissionItem.int_xy_from_float`, so
    "47.3977419" is 473977419 and never 473977418.
    """
    if not value.is_finite() or value.adjusted() > _XY_MAX_DIGITS:
        return None  # (and 1e999999999 never reaches an exponent overflow or a huge int)
    scaled = int(value.scaleb(xy_decimals(frame)).to_integral_value(ROUND_HALF_EVEN))
    return scaled if INT32_MIN <= scaled <= INT32_MAX else None


def xy_to_decimal(frame: int, value: int) -> Decimal:
    """The exact decimal a MISSION_ITEM_INT x/y stands for in a frame (473977419 -> 47.3977419)."""
    return Decimal(value).scaleb(-xy_decimals(frame))


def xy_text(frame: int, value: int) -> str:
    """x/y written with all its decimals (fixed point, never an exponent)."""
    return f"{xy_to_decimal(frame, value):.{xy_decimals(frame)}f}"


def float32_from_decimal(value: Decimal) -> float:
    """A file number as the float32 a param or z holds (NaN and infinities kept)."""
    return to_float32(float(value))


def float32_text(value: float) -> str:
    """The shortest text that reads back to the same float32 ('0.1', not '0.10000000149...')."""
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))  # -0.0 too: it equals 0.0 wherever items are compared
    for digits in range(1, 10):
        text = f"{value:.{digits}g}"
        if to_float32(float(text)) == value:
            return repr(float(text))
    return repr(value)  # unreachable: 9 significant digits always identify a float32
