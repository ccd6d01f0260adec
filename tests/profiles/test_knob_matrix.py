"""The negative-control matrix: builtin profiles x the knobs each sets x the clauses that
judge them, so no clause can go blind to a deviation a profile models (issue 23). The table
and what (a), (b) and (c) mean are in conformance/knob_judges.py. Every builtin profile
takes part (BUILTIN_PROFILES: a profile added later joins by itself); each vehicle runs in
virtual time, once (runs are cached), so the whole matrix takes seconds."""

from __future__ import annotations

import json
from functools import lru_cache
from typing import Any

import pytest

from mavconform.conformance.catalogue import CLAUSES
from mavconform.conformance.knob_judges import JUDGES, dependents, listers
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_clauses
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, KNOBS, KnobSetting, build_config, load_profile
from mavconform.reference_impl.profiles.loader import spec_default
from mavconform.reference_impl.profiles.model import Profile

# A profile whose vehicle ignores the _INT mission messages (inav) leaves the suite's transfers
# unanswered (ERROR) until its tester falls back to MISSION_ITEM / MISSION_REQUEST: not run here yet.
PROFILES: dict[str, Profile] = {name: p for name in BUILTIN_PROFILES
                                if not (p := load_profile(name)).int_messages_ignored}
CLAUSE_IDS = {c.id for c in CLAUSES}
Verdicts = dict[str, tuple[Outcome, str]]
Applied = tuple[tuple[str, str], ...]   # (knob, its TOML value as JSON): hashable, for the cache


def _is_default(knob: str, value: Any) -> bool:
    return KNOBS[knob].parse(value) == spec_default(knob)


def _on(profile: Profile) -> frozenset[str]:
    """The knobs a profile sets to something other than the spec default."""
    return frozenset(s.knob for s in profile.settings if not _is_default(s.knob, s.value))


def _applied(pairs: list[tuple[str, Any]]) -> Applied:
    return tuple((knob, json.dumps(value, sort_keys=True)) for knob, value in pairs)


def _without(profile: Profile, removed: set[str]) -> Applied:
    return _applied([(s.knob, s.value) for s in profile.settings if s.knob not in removed])


@lru_cache(maxsize=None)
def _verdicts(target: str, applied: Applied, clauses: tuple[str, ...] | None = None) -> Verdicts:
    """Every clause's (or the named ones') verdict on builtin `target` built from just the
    `applied` knob settings (builtin:spec keeps the suite's own overrides)."""
    settings = [KnobSetting(knob, json.loads(value), "", "", "") for knob, value in applied]
    config = build_config(settings, where=f"the knob matrix ({target})")
    selected = [c for c in CLAUSES if clauses is None or c.id in clauses]
    with Session(parse_target(f"builtin:{target}"), virtual=True, config=config) as session:
        return {r.clause_id: (r.outcome, r.detail) for r in run_clauses(session, selected).results}


def _changed(applied: Applied) -> Verdicts:
    """The clauses whose verdict on the spec vehicle these knob settings change."""
    base, got = _verdicts("spec", ()), _verdicts("spec", applied)
    return {c: v for c, v in got.items() if v[0] is not base[c][0]}


def _show(verdicts: Verdicts) -> str:
    return "; ".join(f"{c} {o.value}: {d}" for c, (o, d) in sorted(verdicts.items())) or "none"


def _alone(knob: str, value: Any, needs: list[tuple[str, Any]], where: str) -> None:
    """(a): the spec vehicle with the knob (and what it needs) changes exactly its rows' verdicts."""
    want = dict(JUDGES[knob].clauses)
    for other, _ in needs:
        want.update(JUDGES[other].clauses)
    changed = _changed(_applied([(knob, value), *needs]))
    got = {c: o for c, (o, _) in changed.items()}
    assert got == want, (f"{where}: the spec vehicle with {knob} = {value!r} alone changes "
                         f"{_show(changed)}; the table says {sorted((c, o.value) for c, o in want.items())}")


# --- the table ------------------------------------------------------------------------------
def test_every_knob_has_a_row() -> None:
    assert set(JUDGES) == set(KNOBS), (f"knobs without a row in conformance/knob_judges.py: "
                                       f"{sorted(set(KNOBS) - set(JUDGES))}; rows for no knob: "
                                       f"{sorted(set(JUDGES) - set(KNOBS))}")


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_every_knob_a_profile_sets_is_in_the_table(name: str) -> None:
    missing = [s.knob for s in load_profile(name).settings if s.knob not in JUDGES]
    assert not missing, f"{name} sets knobs the matrix table does not mention: {missing}"


@pytest.mark.parametrize("knob", sorted(JUDGES))
def test_every_row_says_what_judges_it_or_why_nothing_does(knob: str) -> None:
    row = JUDGES[knob]
    assert row.why.strip(), knob
    assert set(row.clauses) <= CLAUSE_IDS, sorted(set(row.clauses) - CLAUSE_IDS)
    assert all(o in (Outcome.FAIL, Outcome.NOT_APPLICABLE) for o in row.clauses.values()), row.clauses
    assert all(n in JUDGES and n != knob for n in row.needs), row.needs
    assert all(n in JUDGES for n in row.side), row.side
    if row.example is not None:
        KNOBS[knob].parse(row.example)
        assert not _is_default(knob, row.example), f"{knob}: the example is the spec default"


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_a_profile_sets_what_its_knobs_need(name: str) -> None:
    profile = load_profile(name)
    for knob in _on(profile):
        lacking = [n for n in JUDGES[knob].needs if profile.setting(n) is None]
        assert not lacking, f"{name} sets {knob} without {lacking}, which it needs"


def test_every_judging_row_is_run() -> None:
    """A row's clauses are a claim only a run can check: by a profile's value, or the example."""
    run = {s.knob for p in PROFILES.values() for s in p.settings if not _is_default(s.knob, s.value)}
    run |= {s.knob for p in PROFILES.values() for s in p.settings if s.alternative is not None
            and not _is_default(s.knob, s.alternative.value)}
    idle = [k for k, row in JUDGES.items() if row.clauses and k not in run and row.example is None]
    assert not idle, f"rows whose clauses no profile value or example exercises: {idle}"


# --- (a) alone ------------------------------------------------------------------------------
ALONE = [(name, s.knob, which) for name, p in PROFILES.items() for s in p.settings
         for which, v in (("value", s.value), ("alternative", s.alternative and s.alternative.value))
         if v is not None and not _is_default(s.knob, v)]


@pytest.mark.parametrize("name,knob,which", ALONE, ids=[f"{n}-{k}-{w}" for n, k, w in ALONE])
def test_alone_a_knob_changes_exactly_its_rows_verdicts(name: str, knob: str, which: str) -> None:
    profile = PROFILES[name]
    setting = profile.setting(knob)
    value = setting.value if which == "value" else setting.alternative.value
    needs = [(n, profile.setting(n).value) for n in JUDGES[knob].together if profile.setting(n) is not None]
    _alone(knob, value, needs, f"{name} ({which})")


EXAMPLES = sorted(k for k, row in JUDGES.items() if row.example is not None)


@pytest.mark.parametrize("knob", EXAMPLES)
def test_alone_a_knob_changes_exactly_its_rows_verdicts_with_its_example(knob: str) -> None:
    needs = [(n, JUDGES[n].example) for n in JUDGES[knob].needs]
    assert all(v is not None for _, v in needs), f"{knob}'s example needs examples of {JUDGES[knob].needs}"
    _alone(knob, JUDGES[knob].example, needs, "the row's example")


# --- (b) needed, (c) not masked ---------------------------------------------------------------
JUDGED = [(name, knob) for name, p in PROFILES.items() for knob in sorted(_on(p)) if JUDGES[knob].clauses]


@pytest.mark.parametrize("name,knob", JUDGED, ids=[f"{n}-{k}" for n, k in JUDGED])
def test_the_profile_without_the_knob_passes_its_clauses(name: str, knob: str) -> None:
    profile, on = PROFILES[name], _on(PROFILES[name])
    removed = dependents(knob, on)
    kept = on - removed
    mine = tuple(c for c in JUDGES[knob].clauses if not listers(c, kept))
    if not mine:
        pytest.skip(f"every clause {knob} judges is judged by another knob {name} sets too")
    got = _verdicts(name, _without(profile, removed), mine)
    failed = {c: v for c, v in got.items() if v[0] is not Outcome.PASS}
    assert not failed, (f"{name} with {sorted(removed)} back at the spec default still does not pass "
                        f"{_show(failed)}: another knob changes it, and the table does not say so")


@pytest.mark.parametrize("name,knob", JUDGED, ids=[f"{n}-{k}" for n, k in JUDGED])
def test_the_profiles_other_knobs_do_not_hide_it(name: str, knob: str) -> None:
    profile, on = PROFILES[name], _on(PROFILES[name])
    row = JUDGES[knob]
    blind = []
    for clause, outcome in row.clauses.items():
        others = listers(clause, on) - {knob} - set(row.needs)
        removed = set().union(*(dependents(o, on) for o in others))
        assert knob not in removed, f"{knob} needs a knob that judges {clause} too: {sorted(removed)}"
        got = _verdicts(name, _without(profile, removed), (clause,))[clause]
        if got[0] is not outcome:
            blind.append(f"{clause} is {got[0].value}, not {outcome.value} (with {sorted(removed) or 'nothing'} "
                         f"back at the spec default){': ' + got[1] if got[1] else ''}")
    assert not blind, f"{name} sets {knob}, yet its probes are blind to it there: " + "; ".join(blind)
