"""The GCS checks: one function per MIS.G clause, registered by the clause id it decides.

A check gets the `GcsHarness` (its `run` has the GCS do one operation against a scripted
vehicle) and returns a short text when the GCS met the clause; it raises `ClauseFailed` saying
what the GCS did instead, or `PreconditionFailed` when the GCS never led the vehicle to the
move the clause is about (another clause judges that). Modules are grouped like the clauses;
common.py holds the plans, the shared operations and the judging helpers. Importing this
package registers them all.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Callable

from ...registry import checks_by_clause, import_submodules

if TYPE_CHECKING:
    from ..harness import GcsHarness

Check = Callable[["GcsHarness"], "str | None"]
GCS_CHECKS: dict[str, Check] = {}


check = checks_by_clause(GCS_CHECKS)
import_submodules(__path__, __name__)
