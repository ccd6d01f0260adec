"""Registries a package fills by importing its modules: the checks of each role, the mutants.

A check registers itself under the clause id it decides (`checks_by_clause`); the package's
`__init__` imports every module beside it (`import_submodules`), so adding a module is
enough to add its checks.
"""

from __future__ import annotations

import importlib
import pkgutil
from typing import Callable, Iterable, TypeVar

F = TypeVar("F", bound=Callable[..., object])


def checks_by_clause(registry: dict[str, F]) -> Callable[[str], Callable[[F], F]]:
    """The `@check(clause_id)` decorator that fills `registry`; two checks for one clause are
    a bug in the suite."""
    def check(clause_id: str) -> Callable[[F], F]:
        def register(fn: F) -> F:
            if clause_id in registry:
                raise ValueError(f"two checks for {clause_id}: {registry[clause_id].__name__}, {fn.__name__}")
            registry[clause_id] = fn
            fn.clause_id = clause_id  # type: ignore[attr-defined]
            return fn
        return register
    return check


def import_submodules(path: Iterable[str], package: str) -> None:
    """Import every module of the package at `path` (its `__path__`), for what they register."""
    for info in pkgutil.iter_modules(path):
        importlib.import_module(f"{package}.{info.name}")
