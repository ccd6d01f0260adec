"""Vehicle profiles as data: how the reference vehicle departs from the spec to behave like
PX4 or ArduPilot (VARIANTS.md), one documented knob at a time.

The profiles themselves are the TOML files beside this module (`spec.toml`, `px4.toml`,
`ardupilot.toml`); a user's profile file starts from one (`base = "px4"`) and overrides
knobs. The engines read knobs and never a profile name.
"""

from __future__ import annotations

from .knobs import KNOBS, Knob
from .loader import BUILTIN_PROFILES, build_config, load_profile
from .model import Alternative, Documented, KnobSetting, Profile

__all__ = ["BUILTIN_PROFILES", "KNOBS", "Alternative", "Documented", "Knob", "KnobSetting",
           "Profile", "build_config", "load_profile"]
