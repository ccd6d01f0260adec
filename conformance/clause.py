"""What a clause is: one requirement sentence of the spec, as data a test can decide.

h2spec prints the requirement beside the verdict so a reader never needs the source; a
clause carries its sentence and where it came from for the same reason.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum

SEED_000 = "seeds/000_e382b17b02933558.txt"   # the Mission Protocol text (second half)
SEED_001 = "seeds/001_8a174eac43c4bfd2.txt"   # MAVLink framing, routing and signing
UPSTREAM = "mavlink-upstream/common.xml"       # upstream message definitions

# HO: handover (operator control); MIS.G.*: the GCS's side of the Mission Protocol; MSP.*:
# an MSP flight controller's waypoint store (seed 004, INAV)
_ID = re.compile(r"(MIS|HO)(\.G)?\.[A-Z]{2,4}\.\d{2}|MSP\.[A-Z]{2,4}\.\d{2}")


class Level(str, Enum):
    """RFC 2119 strength. MUST failures always gate; SHOULD failures gate with --strict;
    MAY clauses check that an optional behaviour, when present, is done right."""

    MUST = "MUST"
    SHOULD = "SHOULD"
    MAY = "MAY"


class Role(str, Enum):
    VEHICLE = "vehicle"
    GCS = "gcs"
    MSP = "msp"          # an MSP flight controller (conformance/msp)


@dataclass(frozen=True)
class Clause:
    id: str            # stable: MIS|HO[.G].<group>.<nn> or MSP.<group>.<nn>; never renumbered, retired ids are not reused
    level: Level
    role: Role
    title: str         # one line in our words
    source: str        # file:line under ../shared (seeds/… or mavlink-upstream/…)
    requirement: str   # the sentence, quoted from the source

    def __post_init__(self) -> None:
        if not _ID.fullmatch(self.id):
            raise ValueError(f"bad clause id {self.id!r}")

    @property
    def group(self) -> str:
        return self.id.split(".", 1)[1].rsplit(".", 1)[0]   # "UP"; a GCS clause's "G.UP"
