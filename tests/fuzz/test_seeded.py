"""A seeded campaign draws the same examples whatever the process did before it.

A CI run's determinism tests failed in an xdist worker that had run other tests between two
same-seed searches. fuzz/seeded.py (its doc says how) keeps Hypothesis's local constants, its
strategy cache and its clock out of a campaign's draws, for all three fuzzers (the frame and
handover fuzzers open the same context around their Hypothesis runs). The first test checks
that end to end; the second that each of the three is really shut out, and let back after.
"""

from __future__ import annotations

import importlib
import json
import time

import pytest
from hypothesis import strategies as st

from mavconform.fuzz.protocol import machine as machine_module
from mavconform.fuzz.protocol import search
from mavconform.fuzz.protocol.steps import Runner
from mavconform.fuzz.seeded import seeded_hypothesis


@pytest.fixture
def programs(monkeypatch):
    """Every step a protocol search of `seed` ran, in order."""
    ran: list[str] = []

    class Recording(Runner):
        def apply(self, step):
            ran.append(json.dumps(step, sort_keys=True))
            return super().apply(step)

    monkeypatch.setattr(machine_module, "Runner", Recording)

    def run(seed: int, examples: int = 30) -> list[str]:
        ran.clear()
        assert search("builtin:spec", seed=seed, max_examples=examples) == []
        return list(ran)
    return run


def test_a_search_runs_the_same_programs_after_other_searches_and_imports(programs) -> None:
    first = programs(8)
    programs(1, examples=5)
    importlib.import_module("mavconform.conformance.gcs.checks")   # more local modules, more constants
    importlib.import_module("mavconform.fuzz.handover.machine")
    assert programs(8) == first


def test_inside_a_campaign_hypothesis_has_no_local_constants_no_carried_strategies_no_clock() -> None:
    from hypothesis.internal.conjecture import engine, providers
    from hypothesis.strategies._internal import utils

    assert len(providers._get_local_constants()) > 0   # this test module's literals, at least
    st.integers(0, 7).validate()                        # puts strategies in Hypothesis's cache
    assert len(utils._STRATEGY_CACHE) > 0
    with seeded_hypothesis(virtual_time=True):
        assert len(providers._get_local_constants()) == 0
        assert len(utils._STRATEGY_CACHE) == 0
        assert engine.time.monotonic() == 0.0
    assert len(providers._get_local_constants()) > 0
    assert engine.time is time
    with seeded_hypothesis(virtual_time=False):         # over UDP the engine keeps the real clock
        assert engine.time is time
