"""Hypothesis made to draw the same examples from the same seed, whatever else the process did.

A seeded campaign must find the same cases finding for finding (`--seed` reproduces it). A CI
run showed it did not always: in one xdist worker a search of the same seed, run after other
tests, found another case than the same search run first. Hypothesis lets a process's history
into a seeded run in the ways below; `seeded_hypothesis()` shuts out the first three while a
campaign's Hypothesis runs, and our strategies avoid the fourth:

- Local constants: Hypothesis draws now and then from the literal constants of every "local"
  module loaded in the process (hypothesis.internal.conjecture.providers), a pool that grows
  as modules are imported (ours import lazily) and changes with every edit of a loaded
  module. Here the pool is empty: only Hypothesis's own global constants remain.
- Shared strategy objects: `st.integers(0, 2)` and the like return one cached object per
  process, and which draws share an object decides which parts of an example Hypothesis's
  mutator splices into each other. A second same-seed search in one process was seen to run
  other programs, and to run the first one's again once that cache was emptied. So at the
  start of every run the module-level strategies are resolved, then Hypothesis's cache and our
  `cached_strategy_builder`s are emptied: every run builds and shares its strategies alike.
- The wall clock (virtual-time targets only): with report_multiple_bugs, Hypothesis stops
  looking for more bugs 10 s of wall time after the first (engine.should_generate_more); on
  a loaded machine a campaign then ran fewer examples. Its monotonic clock is held still.
  (Its shrink limit uses perf_counter, five minutes, and stays real.)
- Labels that hang on memory: the mutator splices the parts of an example whose strategies
  share a label, and Hypothesis labels `just(x)` and `sampled_from(xs)` by hash(x). A NaN's
  hash is its identity, so a `just(float("nan"))` made per draw got a label that depended on
  where the NaN was allocated: moving unrelated code between modules, or importing one more
  module first, changed what seed 1 explored (1133 examples or 1165). No strategy may hold such
  a value made per draw (tests/fuzz/test_seeded_labels.py is the tripwire).

These are the causes found, not all there are: an xdist worker that had run many other tests
was still once seen to explore other examples in a second same-seed search (before the fourth
was found, which may have been it). What holds is the same seed in a fresh process, as
`mavconform fuzz` runs a campaign (tests/fuzz/test_protocol.py checks it so); a finding replays
from its saved case in any process. A Hypothesis without one of these module attributes is left
as it is there.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from functools import lru_cache
from typing import Any, Callable, Iterator, TypeVar

_PROVIDERS = "hypothesis.internal.conjecture.providers"
_ENGINE = "hypothesis.internal.conjecture.engine"
_STRATEGY_UTILS = "hypothesis.strategies._internal.utils"


Builder = TypeVar("Builder", bound=Callable[..., Any])
_BUILDERS: list[Any] = []


def cached_strategy_builder(build: Builder) -> Builder:
    """`lru_cache` for a function that builds strategies (each built once per campaign run),
    emptied with Hypothesis's own cache when a run starts."""
    cached = lru_cache(maxsize=None)(build)
    _BUILDERS.append(cached)
    return cached  # type: ignore[return-value]


def _resolve_module_strategies() -> None:
    """Resolve every strategy our modules hold at module level, now: a lazy one resolved for
    the first time inside a run would put its parts in the strategy cache, to be shared by
    that run's draws only."""
    from hypothesis.strategies import SearchStrategy
    for name, module in list(sys.modules.items()):
        if name.startswith("mavconform.") and module is not None:
            for value in list(vars(module).values()):
                if isinstance(value, SearchStrategy):
                    try:
                        value.validate()
                    except Exception:   # noqa: BLE001 - an invalid one fails where it is drawn
                        pass


class _FrozenMonotonic:
    """`time` as Hypothesis's engine sees it, but with a monotonic clock that stands still."""

    def __getattr__(self, name: str) -> Any:
        return getattr(time, name)

    @staticmethod
    def monotonic() -> float:
        return 0.0


@contextmanager
def seeded_hypothesis(*, virtual_time: bool) -> Iterator[None]:
    """While it is open, Hypothesis's draws depend on the seed alone (see the module doc)."""
    providers = sys.modules.get(_PROVIDERS)
    engine = sys.modules.get(_ENGINE)
    constants = getattr(providers, "_get_local_constants", None)
    cache = getattr(getattr(providers, "CONSTANTS_CACHE", None), "cache", None)
    freeze = virtual_time and engine is not None and getattr(engine, "time", None) is time
    clear_strategies = getattr(sys.modules.get(_STRATEGY_UTILS), "clear_strategy_cache", None)
    if clear_strategies is not None:
        _resolve_module_strategies()
        clear_strategies()
    for builder in _BUILDERS:
        builder.cache_clear()
    if constants is not None and cache is not None:
        empty = providers.Constants()
        providers._get_local_constants = lambda: empty
        cache.clear()   # permitted values cached with the local constants of earlier runs
    if freeze:
        engine.time = _FrozenMonotonic()
    try:
        yield
    finally:
        if freeze:
            engine.time = time
        if constants is not None and cache is not None:
            providers._get_local_constants = constants
            cache.clear()
