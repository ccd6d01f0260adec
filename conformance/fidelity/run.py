"""One fidelity survey from options to run.json: `mavconform fidelity` (issue 26).

The target is reached as the conformance run reaches it (conformance/session.py: builtin
targets in this process over UDP loopback, or virtual time in the tool's tests; external ones
over their link). Its plans are read first and put back after, as a run does. Each cell is
judged twice: by the rules (`class`: classify.py) and against what the profile's declared
rules predict (`predicted`, predict.py), for a profile whose rules say everything about a
cell (not INAV's). The run document is the conformance run's (no clauses) with the matrix
under `fidelity`:

    fidelity  {format: "mavconform-fidelity/1", scope: "frames" | "commands" | "all", profile: NAME,
               basis: TEXT, uploads: N, cells: [{plan_type: mission|fence|rally, frame: int,
                 command: int, probe: "nominal" | "p<i>:<kind>" (command matrix only),
                 sent: [{frame, command, param1..param4, x, y, z, autocontinue}, ...],
                 back: [...] or null (not accepted), class: refused:<MAV_MISSION result> |
                 exact | int_twin | changed:<field from->to, ...>[ (rule: ...)] | unanswered |
                 unread, precision: {field: |sent - back|} where a float came back as another
                 number, predicted: the same vocabulary or null, as_predicted: bool or null,
                 exchange: index into `exchanges`}],
               exchanges: [[event, ...], ...]: each upload's and download's messages (the
                 report's sequence-diagram events), one list per upload; a batch's cells share one}

`sent` and `back` are lists: a fence polygon cell is three vertices.
"""

from __future__ import annotations

import datetime as dt
import time
from dataclasses import dataclass
from typing import Any, Callable

from mavconform.reference_impl.profiles import load_profile

from .. import document, readiness
from ..outcome import TargetUnresponsive
from ..runner import RunOutcome, _restore, _snapshot
from ..session import Session
from ..target_uri import TargetUri
from .cells import Cell, entry_key, frame_cells
from .predict import agrees, predict, predictable
from .probes import command_cells
from .survey import run_survey

FORMAT = "mavconform-fidelity/1"
SCOPES = ("frames", "commands", "all")


def scope_cells(scope: str) -> list[Cell]:
    """frames: every MAV_FRAME × plan-type item kind; commands: every mission command × its
    params' probes (probes.py); all: both."""
    if scope not in SCOPES:
        raise ValueError(f"unknown matrix scope {scope!r} (one of {', '.join(SCOPES)})")
    return (frame_cells() if scope in ("frames", "all") else []) + (command_cells() if scope != "frames" else [])


@dataclass
class FidelityRun:
    doc: dict[str, Any]
    unresponsive: str | None = None


def profile_name(uri: TargetUri, identity: dict | None) -> str:
    """The profile that predicts the target: --profile, a builtin's own, or the HEARTBEAT's autopilot's."""
    if uri.profile is not None:
        return uri.profile
    if uri.kind == "builtin":
        return uri.name
    from ..harness.stored_form import profile_for_target
    found = profile_for_target(identity.get("autopilot") if identity else None,
                               identity.get("type") if identity else None)
    return found or "spec"


def survey(uri: TargetUri, *, scope: str = "frames", virtual: bool = False, seed: int = 0,
           on_cell: Callable[[dict[str, Any]], None] | None = None) -> FidelityRun:
    started = dt.datetime.now(dt.timezone.utc)
    begun = time.monotonic()
    cells = scope_cells(scope)
    options = document.RunOptions(target=str(uri), clauses="", seed=seed, profile=uri.profile)
    with Session(uri, virtual=virtual, seed=seed) as session:
        try:
            identity = session.discover()
        except TargetUnresponsive as exc:
            run = RunOutcome([], None, {"status": "skipped", "detail": "the target never answered"},
                             time.monotonic() - begun, 0.0, unresponsive=str(exc))
            doc = _document(options, run, started, scope, "spec", None, [], 0)
            return FidelityRun(doc, unresponsive=str(exc))
        snapshot = _snapshot(session)
        identity["prepared"] = readiness.prepare(session.t).line()   # streams asked for, boot waited out
        name = profile_name(uri, identity)
        profile = load_profile(name)
        form = session.t.form
        result = run_survey(session.t, cells, on_cell)
        by_key = {c.key: c for c in cells}
        can_predict = predictable(profile.behaviour)
        for entry in result.cells:
            cell = by_key[entry_key(entry)]
            guess = predict(cell, profile.behaviour, form) if can_predict else None
            entry["predicted"] = guess
            entry["as_predicted"] = None if guess is None else agrees(entry["class"], guess)
        restore = _restore(session, snapshot) if snapshot is not None else {
            "status": "failed", "detail": "could not read the target's plans before the survey"}
        run = RunOutcome([], identity, restore, time.monotonic() - begun, 0.0, link=session.link_facts)
        doc = _document(options, run, started, scope, name, form.describe(), result.cells, result.uploads)
        doc["fidelity"]["exchanges"] = result.exchanges
    return FidelityRun(doc)


def _document(options: document.RunOptions, run: RunOutcome, started: dt.datetime, scope: str, profile: str,
              basis: str | None, cells: list[dict[str, Any]], uploads: int) -> dict[str, Any]:
    doc = document.build(options, run, started=started, gating_flags={}, gating={"mode": "default",
                                                                                   "regressions": [], "fixed": []},
                         capture=None)
    doc["fidelity"] = {"format": FORMAT, "scope": scope, "profile": profile, "basis": basis, "uploads": uploads,
                       "cells": cells}
    return doc
