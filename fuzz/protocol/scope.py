"""What of the mission protocol a target's profile says it implements, and the fuzzer keeps to.

A profile documents deviations that are not bugs to find again on every example: INAV 9.1
(VARIANTS I2, I4, I5; I11 in docs/real-targets.md) reads only MISSION_ITEM / MISSION_REQUEST, ignores mission_type
(a fence upload replaces the mission), answers MISSION_COUNT 0 with a request for item 0,
drops a GCS's MISSION_ACK and MISSION_SET_CURRENT unread, and has no upload timers (an
upload a GCS abandons stays open until the next MISSION_COUNT). Fuzzing those would only
rediscover the profile; what is left to fuzz is everything else: loss, duplication,
reordering, cancels (which such a vehicle ignores), a second GCS, stray messages.

`Scope.adapt` maps each drawn step onto that part of the protocol, the same way when a
saved case is replayed: a step about a plan type, message or operation the profile says the
vehicle does not have is left out (None) or narrowed (float forms, no empty upload). The
spec profile's scope is everything, and `adapt` returns every step unchanged.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from mavconform.reference_impl.mission.items import MissionType

MISSION = int(MissionType.MISSION)


@dataclass(frozen=True)
class Scope:
    plan_types: frozenset[int] = frozenset(int(t) for t in MissionType if t is not MissionType.ALL)
    float_only: bool = False        # MISSION_ITEM_INT / MISSION_REQUEST_INT unread (I2)
    set_current: bool = True        # MISSION_SET_CURRENT read (I2: dropped unread)
    empty_upload: bool = True       # MISSION_COUNT 0 clears (I5: it opens an upload instead)
    returns_to_idle: bool = True    # an abandoned upload ends by a timer or a GCS's cancel (I11: neither)
    basis: str = "the spec"

    @classmethod
    def of(cls, config: Any, basis: str) -> Scope:
        """The scope a vehicle's profile (its VehicleConfig: knobs and unread messages) implies."""
        behaviour = config.behaviour
        types = frozenset({MISSION}) if behaviour.mission_type_ignored else cls().plan_types
        return cls(plan_types=types,
                   float_only=config.int_forms_ignored,
                   set_current="MISSION_SET_CURRENT" not in config.ignored_messages,
                   empty_upload=not behaviour.count0_opens_upload,
                   returns_to_idle=config.abandoned_upload_ends,
                   basis=basis)

    @property
    def whole(self) -> bool:
        return self == Scope(basis=self.basis)

    def describe(self) -> str:
        """One line for the campaign's header: what is left out, and on whose word."""
        if self.whole:
            return "the whole protocol"
        out = []
        if self.plan_types != Scope().plan_types:
            out.append("mission plans only (mission_type ignored)")
        if self.float_only:
            out.append("MISSION_ITEM / MISSION_REQUEST only")
        if not self.set_current:
            out.append("no set-current")
        if not self.empty_upload:
            out.append("no empty uploads (MISSION_COUNT 0 opens one)")
        if not self.returns_to_idle:
            out.append("the vehicle's own idleness not judged (no upload timers, cancels unread)")
        return f"{'; '.join(out)}: as {self.basis} documents"

    def adapt(self, step: dict[str, Any]) -> dict[str, Any] | None:
        """The step as this target is fuzzed, or None if the profile says it has no such thing."""
        if self.whole:
            return step
        kind = step.get("op")
        if kind in ("upload", "download", "clear", "set_current"):
            return self._operation(step)
        if kind == "cancel":
            of = self._operation(step["of"])
            return None if of is None else {**step, "of": of}
        if kind == "second_gcs":
            first, second = self._operation(step["first"]), self._operation(step["second"])
            if first is None or second is None:
                return None
            return {**step, "first": first, "second": second}
        if kind == "stray":
            messages = [raw for raw in step["messages"] if self._raw_in_scope(raw)]
            during = step.get("during")
            during = self._operation(during) if during else None
            if not messages:
                return None
            return {**step, "messages": messages, "during": during}
        return step

    def _operation(self, op: dict[str, Any]) -> dict[str, Any] | None:
        kind = op["op"]
        if kind == "set_current":
            return op if self.set_current else None
        kind_type = op.get("type")
        if kind == "clear" and kind_type == int(MissionType.ALL):
            return op
        if kind_type not in self.plan_types:
            return None
        if kind == "upload":
            if not op["items"] and not self.empty_upload:
                return None
            # with mission_type ignored, an item's own (wrong) mission_type is read as the mission's
            retyped = self.plan_types == {MISSION} and any("mission_type" in i for i in op["items"])
            if retyped or (self.float_only and not op.get("float")):
                op = copy.deepcopy(op)
                op["float"] = bool(op.get("float")) or self.float_only
                for item in op["items"] if retyped else ():
                    item.pop("mission_type", None)
        return op

    def _raw_in_scope(self, raw: dict[str, Any]) -> bool:
        name, fields = raw["msg"], raw["fields"]
        if self.float_only and name in ("MISSION_ITEM_INT", "MISSION_REQUEST_INT"):
            return False
        if not self.set_current and name == "MISSION_SET_CURRENT":
            return False
        if not self.empty_upload and name == "MISSION_COUNT" and fields.get("count") == 0:
            return False
        kind_type = fields.get("mission_type")
        return kind_type is None or kind_type in self.plan_types or (
            name == "MISSION_CLEAR_ALL" and kind_type == int(MissionType.ALL))
