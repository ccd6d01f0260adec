"""While a campaign's Hypothesis runs, what the process did before cannot reach its draws.

fuzz/seeded.py (its doc says why) keeps Hypothesis's local constants, its strategy cache and
its clock out of a campaign's runs, for all three fuzzers. This checks that each is really
shut out inside, and let back after. That the same seed then finds the same cases, in fresh
processes as `mavconform fuzz --seed` runs them, is tests/fuzz/test_protocol.py's.
"""

from __future__ import annotations

import time

from hypothesis import strategies as st

from mavconform.fuzz.seeded import seeded_hypothesis


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
