"""Hypothesis strategies shared by the tool's own tests: valid plans and fault models.

They live in `fuzz.valid_plans` (the fuzzer draws from the same ones); this module keeps
the names the tests import.
"""

from mavconform.fuzz.valid_plans import (
    GLOBAL, alt, f32, fault_models, lat, lon, mission_item, partition, plan_items,
)

__all__ = ["GLOBAL", "alt", "f32", "fault_models", "lat", "lon", "mission_item", "partition",
           "plan_items"]
