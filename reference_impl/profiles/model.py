"""A vehicle profile: the knob settings that make the reference vehicle spec-exact,
PX4-like or ArduPilot-like, each with the VARIANTS.md row it reproduces and its source."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Sequence

from ..mission.behaviour import ServerBehaviour
from ..mission.items import MissionItem, MissionType
from ..mission.store import STORAGE_FORMS
from ..vehicle import VehicleConfig, VehicleNode


@dataclass(frozen=True)
class Alternative:
    """The same knob the other way, where sources disagree (P1/P1', P2/P2')."""
    value: Any
    variant: str
    source: str
    why: str


@dataclass(frozen=True)
class KnobSetting:
    knob: str
    value: Any                 # as written in the profile file (TOML value)
    variant: str               # VARIANTS.md row, e.g. "A2"; "HB" for the HEARTBEAT identity
    source: str
    why: str
    alternative: Alternative | None = None
    seen_on: str = ""          # the real autopilot version it was observed on, if any


@dataclass(frozen=True)
class Documented:
    """A VARIANTS.md row the profile covers without a knob: the spec behaviour already is
    the autopilot's (`kind="same-as-spec"`), or it is not reproduced (`"not-reproduced"`)."""
    variant: str
    kind: str
    why: str
    source: str = ""


@dataclass(frozen=True)
class Profile:
    name: str
    description: str
    behaviour: ServerBehaviour
    config: VehicleConfig
    settings: tuple[KnobSetting, ...]
    documented: tuple[Documented, ...] = ()
    path: str = ""             # the file it was read from

    def vehicle(self, **config_overrides: Any) -> VehicleNode:
        """A fresh reference vehicle with this profile (config fields may be overridden)."""
        config = dataclasses.replace(self.config, **config_overrides) if config_overrides else self.config
        return VehicleNode(config)

    def stored_items(self, items: Sequence[MissionItem], mission_type: MissionType) -> tuple[MissionItem, ...]:
        """What a download returns after `items` were uploaded as the `mission_type` plan
        (without a home item at seq 0): the profile's storage transform (A13). Identity for spec."""
        keep = STORAGE_FORMS[self.behaviour.item_storage]
        return tuple(keep(it if it.mission_type is mission_type else dataclasses.replace(it, mission_type=mission_type))
                     for it in items)

    def variants(self) -> set[str]:
        """Every VARIANTS.md row this profile accounts for (by a knob, its alternative, or
        a documented reason)."""
        out = {s.variant for s in self.settings} | {d.variant for d in self.documented}
        out |= {s.alternative.variant for s in self.settings if s.alternative is not None}
        return out

    @property
    def int_messages_ignored(self) -> bool:
        """The vehicle drops MISSION_ITEM_INT / MISSION_REQUEST_INT unread (INAV 9.1): a GCS must
        use MISSION_ITEM / MISSION_REQUEST. The conformance tester falls back to them
        (conformance/harness/float_forms.py), the frame fuzzer's GCS downloads with them and the
        protocol fuzzer's GCSs use them (fuzz/protocol/scope.py); the knob matrix, the fault
        table and the round trips do not yet, so they leave such a profile out."""
        return self.config.int_forms_ignored

    def setting(self, knob: str) -> KnobSetting | None:
        return next((s for s in self.settings if s.knob == knob), None)
