"""What differs between two run documents: clause outcomes and fidelity cells (issue 26).

Meant for two runs of one target kind across versions (PX4 v1.15 against v1.16, a fork
against upstream): every clause whose outcome changed, and every fidelity cell whose class
changed or that only one run has. Details and timings are left out: they differ run to run
without anything having changed.
"""

from __future__ import annotations

from typing import Any

from mavconform.conformance.fidelity.cells import entry_key


def _cells(doc: dict[str, Any]) -> dict[tuple[str, int, int, str], str]:
    fid = doc.get("fidelity") or {}
    return {entry_key(c): c["class"] for c in fid.get("cells", [])}


def differences(a: dict[str, Any], b: dict[str, Any]) -> list[str]:
    """One line per difference, clauses first, then cells in a stable order."""
    out = []
    oa = {c["id"]: c["outcome"] for c in a["clauses"]}
    ob = {c["id"]: c["outcome"] for c in b["clauses"]}
    for cid in sorted(oa.keys() | ob.keys()):
        if oa.get(cid) != ob.get(cid):
            out.append(f"clause {cid}: {oa.get(cid, 'not run')} -> {ob.get(cid, 'not run')}")
    ca, cb = _cells(a), _cells(b)
    for key in sorted(ca.keys() | cb.keys()):
        if ca.get(key) != cb.get(key):
            plan_type, frame, command, probe = key
            out.append(f"cell {plan_type} frame {frame} command {command}{' ' + probe if probe else ''}: "
                       f"{ca.get(key, 'not surveyed')} -> "
                       f"{cb.get(key, 'not surveyed')}")
    return out
