"""How a target keeps plans: the equivalences every plan comparison allows.

A clause judges only its own behaviour. Two things a target may do to every plan must
therefore never decide an unrelated clause:
- documented equivalences: upstream common.xml supersedes the `*_INT` frames (5, 6, 11) as
  synonymous with the plain ones (0, 3, 10), and PX4 returns one for the other (VARIANTS.md
  L3); params upstream marks "Reserved" carry nothing (a fence vertex has no altitude, so
  neither has the altitude reference of its frame: PX4 keeps its own); `autocontinue` is a
  flight-sequence flag that fence and rally items do not have (PX4's fence record has no
  such field); a downloaded item's `current` flag is the vehicle's progress marker;
- the target's storage, chosen by autopilot *and* vehicle type (ArduPlane packs a
  waypoint's params unlike ArduCopter and ArduRover): ArduPilot keeps home in mission slot 0 (A1: an uploaded item 0 is
  not kept, `AP_Mission::replace_cmd(0)` returns without writing, and a read of index 0
  returns home) and stores items in a compact record that rounds or drops some params (A13).
MIS.UP.04 owns A1 and compares item 0 too (`strict()`); everywhere else a plan is compared
in the target's stored form, and a mismatch names every field that differs.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Sequence

from mavconform.reference_impl.mission.items import GLOBAL_FRAMES, PLAIN_FRAME, MissionItem, MissionType
from mavconform.reference_impl.mission.store import STORAGE_FORMS
from mavconform.reference_impl.vehicle_class import VehicleClass, type_name, vehicle_class

MAX_LISTED = 8          # differences listed in one verdict; the rest are counted
_FIELDS = ("frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z",
           "autocontinue", "mission_type")
# upstream common.xml: the params of each plan-type command marked "Reserved" (1-4; 7 is z)
RESERVED_PARAMS = {
    5001: (3, 4, 7),        # MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
    5002: (2, 3, 4, 7),     # MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
    5003: (3, 4, 7),        # MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
    5004: (2, 3, 4, 7),     # MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
    5100: (1, 2, 3, 4),     # MAV_CMD_NAV_RALLY_POINT
}
_PARAM_FIELD = {1: "param1", 2: "param2", 3: "param3", 4: "param4", 7: "z"}


@dataclass(frozen=True)
class StoredForm:
    home_at_seq0: bool = False     # mission slot 0 holds the vehicle's home, whatever was uploaded
    storage: str = "exact"         # reference_impl.mission.store.STORAGE_FORMS key
    basis: str = "the spec"        # where this came from, for the report

    def first_flown(self, mission_type: MissionType | int = MissionType.MISSION) -> int:
        """The first seq of a plan that is the GCS's own (1 where slot 0 is home)."""
        return 1 if self.home_slot_of(mission_type) else 0

    def home_slot_of(self, mission_type: MissionType | int) -> bool:
        return self.home_at_seq0 and int(mission_type) == int(MissionType.MISSION)

    def strict(self) -> "StoredForm":
        """The same form, but item 0 compared too (the clause that owns A1 uses it)."""
        return replace(self, home_at_seq0=False)

    # --- comparison -------------------------------------------------------------------------
    def _compared(self, item: MissionItem) -> bool:
        return not (item.seq == 0 and self.home_slot_of(item.mission_type))

    def canonical(self, item: MissionItem, *, stored: bool = False) -> MissionItem:
        """An item as any comparison sees it: stored form, plain frame, no `current` flag,
        reserved params and flags the item type does not have left out. `stored`: the item
        is in the stored form already (downloaded, or read from a store), and a storage
        form is not applied twice: it need not be idempotent (ArduPilot keeps altitude in
        truncated whole centimetres: 1.3125 m is stored as 131 cm, read back as the float
        1.30999994, and that, sent again, is stored as 130 cm)."""
        kept = item if stored else STORAGE_FORMS[self.storage](item)
        frame = PLAIN_FRAME.get(kept.frame, kept.frame)
        changes: dict[str, Any] = {"current": 0, "frame": frame}
        reserved = RESERVED_PARAMS.get(int(kept.command), ())
        for index in reserved:
            changes[_PARAM_FIELD[index]] = 0.0
        if 7 in reserved and frame in GLOBAL_FRAMES:
            changes["frame"] = 0    # no altitude: the altitude reference means nothing
        if int(kept.mission_type) != int(MissionType.MISSION):
            changes["autocontinue"] = 0
        return replace(kept, **changes)

    def stored_plan(self, plan: Sequence[MissionItem]) -> tuple[MissionItem, ...]:
        """What the target keeps of a plan it accepts as sent."""
        keep = STORAGE_FORMS[self.storage]
        return tuple(keep(item) for item in plan)

    def same(self, got: Sequence[MissionItem], want: Sequence[MissionItem], *,
             want_stored: bool = False) -> bool:
        """`got` (downloaded or read from the store: stored form) holds the plan `want`
        (as sent; `want_stored`: read back too)."""
        if len(got) != len(want):
            return False
        canonical, compared = self.canonical, self._compared
        # an item equal to the one sent has the same canonical form whenever both sides go
        # through the same storage (the fuzzers compare thousands of plans: most are equal)
        alike = want_stored or self.storage == "exact"
        return all((alike and g == w) or canonical(g, stored=True) == canonical(w, stored=want_stored)
                   for g, w in zip(got, want) if compared(w))

    def differences(self, got: Sequence[MissionItem], want: Sequence[MissionItem], *,
                    want_stored: bool = False) -> list[str]:
        """Every field that differs, item by item, in the stored form ("" items when equal)."""
        out = []
        for g, w in zip(got, want):
            if not self._compared(w):
                continue
            cg, cw = self.canonical(g, stored=True), self.canonical(w, stored=want_stored)
            if cg == cw:
                continue
            fields = [f for f in _FIELDS if _differs(getattr(cg, f), getattr(cw, f))]
            shown = ", ".join(f"{f} {_v(getattr(g, f))} (expected {_v(getattr(w, f))})" for f in fields)
            out.append(f"seq {w.seq}: {shown}")
        return out

    def describe(self) -> str:
        parts = []
        if self.home_at_seq0:
            parts.append("home in mission slot 0")
        if self.storage != "exact":
            parts.append(f"{self.storage} item storage")
        return (", ".join(parts) or "plans stored as sent") + f" ({self.basis})"


SPEC_FORM = StoredForm()


def form_of_behaviour(behaviour: Any, basis: str) -> StoredForm:
    return StoredForm(behaviour.home_at_seq0, behaviour.item_storage, basis)


GENERIC_AUTOPILOT = 0   # MAV_AUTOPILOT_GENERIC


def profile_for_target(autopilot: int | None, mav_type: int | None = None) -> str | None:
    """The builtin profile that models what a HEARTBEAT names (None: the spec): the one of
    that autopilot for that class of vehicle (a VTOL without one of its own: the fixed-wing
    one, whose stored form it shares), else the autopilot's first profile. The profiles'
    own `autopilot` and `vehicle_type` knobs say what each models: one place. A generic
    autopilot (0) names nothing: the spec, unless `--profile` says what it is (INAV says 0,
    and so do MAVSDK's server and most others)."""
    if autopilot is None or autopilot == GENERIC_AUTOPILOT:
        return None
    from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile
    wanted = vehicle_class(mav_type)
    ours = [(name, vehicle_class(_vehicle_type(load_profile(name).config)))
            for name in BUILTIN_PROFILES if load_profile(name).config.autopilot == autopilot]
    for cls in (wanted, VehicleClass.FIXED_WING if wanted is VehicleClass.VTOL else None):
        for name, modelled in ours:
            if modelled is cls:
                return name
    return ours[0][0] if ours else None


def modelling_profile(label: str, *, vehicle_config: Any = None, mutant: bool = False,
                      chosen: str | None = None, autopilot: int | None = None,
                      mav_type: int | None = None) -> tuple[Any, str] | None:
    """The vehicle profile a target is held to (a `VehicleConfig`) and why; None: the spec.
    One choice for every consumer (the suite's session, the frame fuzzer's rig, the protocol
    fuzzer's world): a mutant claims to be the spec vehicle; an in-process vehicle (`label`
    names it) is held to its own profile; an external one to the profile --profile names,
    else to the builtin profile of the autopilot and vehicle class its HEARTBEAT names, else
    to the spec."""
    if mutant:
        return None
    if vehicle_config is not None:
        return vehicle_config, f"the {label} profile"
    from mavconform.reference_impl.profiles import load_profile
    if chosen is not None:
        profile = load_profile(chosen)
        return profile.config, f"--profile {chosen}: the {profile.name} profile"
    name = profile_for_target(autopilot, mav_type)
    if name is None:
        return None
    return (load_profile(name).config,
            f"HEARTBEAT autopilot {autopilot}, {type_name(mav_type)}: the {name} profile")


def stored_form_of(model: tuple[Any, str] | None) -> StoredForm:
    """The stored form of a `modelling_profile` (the spec's for None)."""
    return SPEC_FORM if model is None else form_of_behaviour(model[0].behaviour, model[1])


def _vehicle_type(config: Any) -> int:
    return getattr(config, "vehicle_type", 2)   # MAV_TYPE_QUADROTOR, the reference vehicle's


def describe_differences(diffs: list[str]) -> str:
    listed = "; ".join(diffs[:MAX_LISTED])
    more = len(diffs) - MAX_LISTED
    return listed + (f"; and {more} more item(s)" if more > 0 else "")


def _differs(a: object, b: object) -> bool:
    return a != b and not (a != a and b != b)   # NaN equals NaN here, as in item equality


def _v(value: object) -> str:
    return str(int(value)) if isinstance(value, int) else repr(value)
