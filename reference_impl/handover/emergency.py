"""The emergency procedure as data: when it fires, and where the vehicle goes (seed 003, 4.7).

The thesis leaves the procedure to future work but says what it should do: on a
communication failure or when "the drone is flying outside a coverage area", send RTL, and
"if the mission disposes of a list of rally points, the mission computer can calculate the
distance of the nearest rally point considering the amount of battery remaining". Here that
is two pure functions, so the mission computer, a conformance check and a property test all
decide the same way:

- `due_triggers(now, ...)`: which triggers have fired (the commander silent for
  `loss_timeout_s`; the vehicle outside every coverage for `outside_grace_s`).
- `choose_refuge(position, home, rally, battery, model)`: where to go, with the reason.

Energy model (deliberately simple; every number is the scenario's, none is guessed here).
A multicopter at cruise draws roughly constant power P at ground speed v, so the energy per
metre of ground track is P / v: `consumption_wh_per_m` (e.g. 120 W at 12 m/s is 0.0028 Wh/m).
Of the energy left, `reserve_wh` is never planned to be spent: it pays for the descent, the
landing, wind, and the climb to a safe altitude, which this model does not count separately.
So the range still available is

    usable_range_m = max(0, remaining_wh - reserve_wh) / consumption_wh_per_m

and a refuge is *reachable* iff its horizontal (haversine) distance from the vehicle is at
most `usable_range_m` (one formula, used by every caller, so no two of them can round
differently). Wind, altitude changes and the battery's voltage sag are not modelled: they
belong in the reserve.

Choice. The refuges are home (the launch point: RTL) and the rally points. The vehicle goes to
the nearest reachable one; on a tie home wins (RTL is what an operator expects), then the rally
point listed first. Because reachability is a distance threshold, "nearest reachable" is the
nearest refuge when that one is reachable, and otherwise nothing is: then the last resort is
to land where it is (`LAND_HERE`). It follows that more battery never changes a choice except
from `LAND_HERE` to the nearest refuge, which the property tests hold us to.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import Sequence

from .geo import GeoPoint, haversine_m

__all__ = ["BatteryModel", "BatteryState", "Refuge", "RefugeKind", "Trigger", "TriggerKind",
           "TriggerPolicy", "choose_refuge", "due_triggers", "usable_range_m"]


def _finite(name: str, value: object, *, positive: bool = False) -> float:
    """A finite number >= 0 (> 0 with `positive`), else ValueError naming it."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if value < 0 or (positive and value == 0):
        raise ValueError(f"{name} must be {'more than' if positive else 'at least'} 0, got {value!r}")
    return float(value)


# --- energy --------------------------------------------------------------------------------

@dataclass(frozen=True)
class BatteryModel:
    """The vehicle's energy budget: pack size, cost of a metre at cruise, and what to keep back.

    `reserve_wh` is absolute (a fraction of the pack is `BatteryModel.with_reserve_fraction`):
    what a landing needs does not shrink with the charge left.
    """

    capacity_wh: float
    consumption_wh_per_m: float
    reserve_wh: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "capacity_wh", _finite("battery capacity_wh", self.capacity_wh, positive=True))
        object.__setattr__(self, "consumption_wh_per_m",
                           _finite("battery consumption_wh_per_m", self.consumption_wh_per_m, positive=True))
        object.__setattr__(self, "reserve_wh", _finite("battery reserve_wh", self.reserve_wh))
        if self.reserve_wh > self.capacity_wh:
            raise ValueError(f"battery reserve_wh {self.reserve_wh:g} is more than the capacity "
                             f"{self.capacity_wh:g} Wh")

    @classmethod
    def with_reserve_fraction(cls, capacity_wh: float, consumption_wh_per_m: float,
                              reserve_fraction: float) -> BatteryModel:
        """The model with a reserve given as a fraction of the full pack (autopilots' way)."""
        f = _finite("battery reserve_fraction", reserve_fraction)
        if f > 1:
            raise ValueError(f"battery reserve_fraction must be in [0, 1], got {reserve_fraction!r}")
        return cls(capacity_wh, consumption_wh_per_m, f * _finite("battery capacity_wh", capacity_wh))

    @property
    def reserve_fraction(self) -> float:
        return self.reserve_wh / self.capacity_wh

    def energy_for_m(self, distance_m: float) -> float:
        """Wh that flying `distance_m` at cruise costs."""
        return _finite("distance_m", distance_m) * self.consumption_wh_per_m


@dataclass(frozen=True)
class BatteryState:
    """The energy left, in Wh (a telemetry percentage converts with `from_fraction`)."""

    remaining_wh: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "remaining_wh", _finite("battery remaining_wh", self.remaining_wh))

    @classmethod
    def from_fraction(cls, fraction: float, model: BatteryModel) -> BatteryState:
        """From a remaining fraction of the pack (BATTERY_STATUS.battery_remaining / 100)."""
        f = _finite("battery remaining fraction", fraction)
        if f > 1:
            raise ValueError(f"battery remaining fraction must be in [0, 1], got {fraction!r}")
        return cls(f * model.capacity_wh)

    def fraction(self, model: BatteryModel) -> float:
        return self.remaining_wh / model.capacity_wh

    def after(self, distance_m: float, model: BatteryModel) -> BatteryState:
        """What is left after flying `distance_m` at cruise (never below 0: the pack is empty)."""
        return BatteryState(max(0.0, self.remaining_wh - model.energy_for_m(distance_m)))


def usable_range_m(battery: BatteryState, model: BatteryModel) -> float:
    """Metres the vehicle can still fly at cruise without touching the reserve (>= 0)."""
    return max(0.0, battery.remaining_wh - model.reserve_wh) / model.consumption_wh_per_m


# --- where to go ---------------------------------------------------------------------------

class RefugeKind(Enum):
    """Where the emergency procedure sends the vehicle; the value is the report's word."""

    HOME = "home"            # return to launch
    RALLY = "rally"          # the rally point `Refuge.rally_index`
    LAND_HERE = "land-here"  # nothing reachable: land at the current position


# The MAVLink command that carries each choice out (advice for the mission computer:
# RTL goes home; a rally point is a reposition, then a landing; the last resort lands now).
COMMAND_FOR = {
    RefugeKind.HOME: "MAV_CMD_NAV_RETURN_TO_LAUNCH",
    RefugeKind.RALLY: "MAV_CMD_DO_REPOSITION",
    RefugeKind.LAND_HERE: "MAV_CMD_NAV_LAND",
}


@dataclass(frozen=True)
class Refuge:
    """The decision: where, how far, what it costs, and why, in one sentence for the report."""

    kind: RefugeKind
    point: GeoPoint              # the refuge; the vehicle's own position for LAND_HERE
    distance_m: float            # 0 for LAND_HERE
    usable_range_m: float        # at the time of the decision
    rally_index: int | None      # index in the rally list for RALLY, else None
    reason: str

    @property
    def reachable(self) -> bool:
        """True unless this is the last resort (nothing was in range)."""
        return self.kind is not RefugeKind.LAND_HERE

    @property
    def margin_m(self) -> float:
        """Range left on arrival (before the reserve); 0 for LAND_HERE."""
        return self.usable_range_m - self.distance_m if self.reachable else 0.0

    @property
    def command(self) -> str:
        return COMMAND_FOR[self.kind]


def _check_point(name: str, value: object) -> GeoPoint:
    if not isinstance(value, GeoPoint):
        raise TypeError(f"{name} must be a GeoPoint, got {value!r}")
    return value


def choose_refuge(position: GeoPoint, home: GeoPoint, rally: Sequence[GeoPoint],
                  battery: BatteryState, model: BatteryModel) -> Refuge:
    """The nearest refuge (home or a rally point) in range, else land here; see the module doc.

    Ties go to home, then to the rally point listed first, so the choice is a function of
    the inputs alone (never of float noise in a sort).
    """
    _check_point("position", position)
    _check_point("home", home)
    rally = tuple(_check_point(f"rally[{i}]", p) for i, p in enumerate(rally))
    reach = usable_range_m(battery, model)
    # (distance, rank) with home ranked before every rally point; min() keeps the first of equals.
    candidates = [(haversine_m(position, home), -1)]
    candidates += [(haversine_m(position, p), i) for i, p in enumerate(rally)]
    distance, index = min(candidates)
    if distance > reach:
        which = "home" if index < 0 else f"rally point {index}"
        return Refuge(RefugeKind.LAND_HERE, position, 0.0, reach, None,
                      f"land here: the nearest refuge ({which}, {_km(distance)}) is beyond the usable "
                      f"range of {_km(reach)} (remaining {battery.remaining_wh:.1f} Wh, reserve "
                      f"{model.reserve_wh:.1f} Wh)")
    others = len(rally) + 1 - sum(1 for d, _ in candidates if d <= reach)
    beyond = f"; {others} farther refuge{'s' if others != 1 else ''} out of range" if others else ""
    if index < 0:
        if rally:
            nearest_rally = min(d for d, i in candidates if i >= 0)
            why = (f"home is nearer than every rally point (nearest {_km(nearest_rally)})"
                   if nearest_rally > distance else "home ties with the nearest rally point and is preferred")
        else:
            why = "no rally points"
        return Refuge(RefugeKind.HOME, home, distance, reach, None,
                      f"return to launch: home is {_km(distance)} away, within the usable range of "
                      f"{_km(reach)}; {why}{beyond}")
    return Refuge(RefugeKind.RALLY, rally[index], distance, reach, index,
                  f"rally point {index}: the nearest refuge in range, {_km(distance)} away (home "
                  f"{_km(candidates[0][0])}), usable range {_km(reach)}{beyond}")


def _km(metres: float) -> str:
    return f"{metres:.0f} m" if metres < 1000 else f"{metres / 1000:.2f} km"


# --- when ----------------------------------------------------------------------------------

class TriggerKind(Enum):
    """Why the emergency procedure starts (seed 003, 4.7)."""

    COMMANDER_LOST = "commander-lost"      # the commanding GCS silent for loss_timeout_s
    OUTSIDE_COVERAGE = "outside-coverage"  # outside every GCS's coverage for outside_grace_s


@dataclass(frozen=True)
class TriggerPolicy:
    """The scenario's thresholds, as data. `outside_grace_s` 0: the first sample outside fires."""

    loss_timeout_s: float
    outside_grace_s: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "loss_timeout_s", _finite("loss_timeout_s", self.loss_timeout_s, positive=True))
        object.__setattr__(self, "outside_grace_s", _finite("outside_grace_s", self.outside_grace_s))


@dataclass(frozen=True)
class Trigger:
    """A trigger that has fired: which, the time it became due, and a sentence for the report."""

    kind: TriggerKind
    due_at: float
    reason: str


def due_triggers(now: float, *, commander_last_heard: float | None, outside_since: float | None,
                 policy: TriggerPolicy) -> tuple[Trigger, ...]:
    """The triggers that have fired by `now`, earliest first (COMMANDER_LOST first on a tie).

    `commander_last_heard`: when the commander was last heard (None: there is no commander
    to lose, e.g. before the mission starts). `outside_since`: since when the vehicle has been
    outside every coverage without a break (None: inside one, or the region method is not
    geographic). Both are times on the caller's clock, as `now` is.
    """
    _time("now", now)
    fired: list[Trigger] = []
    if commander_last_heard is not None:
        _time("commander_last_heard", commander_last_heard)
        due = commander_last_heard + policy.loss_timeout_s
        if now >= due:
            fired.append(Trigger(TriggerKind.COMMANDER_LOST, due,
                                 f"commander silent for {now - commander_last_heard:.1f} s "
                                 f"(loss timeout {policy.loss_timeout_s:g} s)"))
    if outside_since is not None:
        _time("outside_since", outside_since)
        due = outside_since + policy.outside_grace_s
        if now >= due:
            fired.append(Trigger(TriggerKind.OUTSIDE_COVERAGE, due,
                                 f"outside every GCS's coverage for {now - outside_since:.1f} s "
                                 f"(grace {policy.outside_grace_s:g} s)"))
    order = list(TriggerKind)
    return tuple(sorted(fired, key=lambda t: (t.due_at, order.index(t.kind))))


def _time(name: str, value: object) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite time in seconds, got {value!r}")
