"""Helpers of the vectors tests."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def load_crosscheck():
    """tools/vectors_crosscheck.py as a module (tools/ is not a package)."""
    name = "vectors_crosscheck"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / "vectors_crosscheck.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]
