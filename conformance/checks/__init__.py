"""The checks: one function per clause, registered by the clause id it decides.

A check gets the `Session` (its `t` is the scripted GCS) and returns normally when the
target met the clause (a string it returns is a remark kept with the pass, e.g. a race seen); it raises `ClauseFailed` with what it expected and what came,
`NotApplicable` when the clause is about an optional behaviour the target lacks, or
`Skipped` when the user has not allowed what it needs. Modules are grouped like the
catalogue; importing this package registers them all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from ..session import Session

Check = Callable[["Session"], "str | None"]
CHECKS: dict[str, Check] = {}


def check(clause_id: str) -> Callable[[Check], Check]:
    def register(fn: Check) -> Check:
        if clause_id in CHECKS:
            raise ValueError(f"two checks for {clause_id}: {CHECKS[clause_id].__name__}, {fn.__name__}")
        CHECKS[clause_id] = fn
        fn.clause_id = clause_id  # type: ignore[attr-defined]
        return fn
    return register


def _load() -> None:
    import importlib
    import pkgutil
    for info in pkgutil.iter_modules(__path__):
        importlib.import_module(f"{__name__}.{info.name}")


_load()
