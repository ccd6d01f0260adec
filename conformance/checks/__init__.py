"""The checks: one function per clause, registered by the clause id it decides.

A check gets the `Session` (its `t` is the scripted GCS) and returns normally when the
target met the clause (a string it returns is a remark kept with the pass, e.g. a race seen); it raises `ClauseFailed` with what it expected and what came,
`NotApplicable` when the clause is about an optional behaviour the target lacks, or
`Skipped` when the user has not allowed what it needs. Modules are grouped like the
catalogue; importing this package registers them all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

from ..registry import checks_by_clause, import_submodules

if TYPE_CHECKING:
    from ..session import Session

Check = Callable[["Session"], "str | None"]
CHECKS: dict[str, Check] = {}


check = checks_by_clause(CHECKS)
import_submodules(__path__, __name__)
