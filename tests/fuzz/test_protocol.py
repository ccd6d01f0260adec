"""The protocol fuzzer, in virtual time: passes on the spec vehicle, finds planted bugs.

- a bounded campaign against builtin:spec finds nothing (every invariant holds);
- against `mutant:non-atomic-upload` it finds the broken atomicity, shrinks the program to
  a few steps, and the saved case (JSON) loads and replays to the same invariant, with a
  capture of every frame;
- the same seed gives the same examples and the same findings;
- a vehicle that raises, one that never gives up, the non-atomic profile hook, and a bad
  step in a hand-edited case.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from mavconform.fuzz.case import Case, load_case, save_case
from mavconform.fuzz.protocol import INVARIANTS, Knobs, replay, search
from mavconform.fuzz.protocol import machine as machine_module
from mavconform.fuzz.protocol.steps import Runner
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.server import MissionServer

WAYPOINT = {"frame": 3, "command": 16, "current": 0, "autocontinue": 1, "param1": 0.0,
            "param2": 0.0, "param3": 0.0, "param4": float("nan"), "x": 473977420,
            "y": 85455940, "z": 50.0}


def upload(n: int, t: int = 0) -> dict:
    return {"op": "upload", "type": t, "items": [dict(WAYPOINT, x=WAYPOINT["x"] + i) for i in range(n)]}


def test_a_bounded_campaign_passes_on_the_spec_vehicle():
    units: list[int] = []
    assert search("builtin:spec", seed=5, max_examples=40, on_example=units.append) == []
    assert len(units) >= 40 and sum(units) > 40 * 3   # examples ran, each with several steps


SEARCH = dict(seed=4, max_examples=200)   # finds and shrinks it in a few hundred examples


def _same(a, b) -> bool:
    """Equal as JSON: a NaN param equals a NaN (`==` says a NaN equals nothing, itself
    included, unless it is the very same object)."""
    return json.dumps(a, sort_keys=True, default=repr) == json.dumps(b, sort_keys=True, default=repr)


@pytest.fixture(scope="module")
def non_atomic_findings() -> list[Case]:
    return search("mutant:non-atomic-upload", **SEARCH)


@pytest.fixture(scope="module")
def non_atomic_finding(non_atomic_findings) -> Case:
    found = [c for c in non_atomic_findings if c.violation.invariant == "atomic-upload"]
    assert found, non_atomic_findings
    return found[0]


def test_the_planted_non_atomic_upload_is_found_and_shrunk(non_atomic_finding):
    case = non_atomic_finding
    assert case.mode == "protocol" and case.target == "mutant:non-atomic-upload"
    assert case.violation.invariant == "atomic-upload"
    assert case.violation.invariant in INVARIANTS
    assert "none of the versions it accepted" in case.violation.detail
    assert 1 <= len(case.steps) <= 5, case.steps          # shrunk to a short program
    assert case.violation.step == len(case.steps) - 1     # it broke on the last step


def test_the_saved_case_loads_and_replays_to_the_same_failure(non_atomic_finding, tmp_path):
    path = save_case(non_atomic_finding, tmp_path)
    loaded = load_case(path)
    assert _same(loaded.steps, non_atomic_finding.steps)  # NaN params survive the JSON
    frames = []
    violation = replay(loaded, capture=frames.append)
    assert violation == non_atomic_finding.violation       # same invariant, detail and step
    assert any(r.kind == "rx" and r.dst == "vehicle" for r in frames)
    # the same program against the spec vehicle breaks nothing
    spec = Case(loaded.mode, "builtin:spec", loaded.seed, loaded.steps)
    assert replay(spec) is None


# A same-seed search in a fresh process each time, as `mavconform fuzz --seed` runs one: a
# process that has already run other searches (an xdist worker) was seen to explore other
# examples (fuzz/seeded.py shuts out the causes found; see the note there).
_FRESH_SEARCH = """
import json, sys, time
from mavconform.fuzz.protocol import search
if sys.argv[1] == "slow":   # wall time jumping 30 s at every look
    real, jumps = time.monotonic, [0.0]
    def slow():
        jumps[0] += 30.0
        return real() + jumps[0]
    time.monotonic = slow
found = search("mutant:non-atomic-upload", seed=%(seed)d, max_examples=%(max_examples)d)
print(json.dumps([(c.seed, c.steps, c.violation.__dict__) for c in found], sort_keys=True, default=repr))
""" % SEARCH


def _fresh_search(mode: str = "plain") -> str:
    done = subprocess.run([sys.executable, "-c", _FRESH_SEARCH, mode], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def test_the_same_seed_gives_the_same_examples_and_findings(monkeypatch):
    first = _fresh_search()
    assert first == _fresh_search()
    assert json.loads(first)   # it found the planted bug

    def programs(seed: int) -> list[str]:
        """Every step every example ran, in order."""
        ran: list[str] = []

        class Recording(Runner):
            def apply(self, step):
                ran.append(json.dumps(step, sort_keys=True))
                return super().apply(step)

        monkeypatch.setattr(machine_module, "Runner", Recording)
        assert search("builtin:spec", seed=seed, max_examples=10) == []
        return ran

    assert programs(8) == programs(8)
    assert programs(8) != programs(9)   # another seed explores other programs


def test_the_non_atomic_profile_hook_judges_only_confirmed_outcomes(non_atomic_finding):
    """builtin:ardupilot is non-atomic (VARIANTS A2): a mix after a failed upload is
    allowed there, so the same program passes when atomicity is not required."""
    relaxed = Case("protocol", non_atomic_finding.target, non_atomic_finding.seed,
                   non_atomic_finding.steps, found_by={"atomic": False})
    assert replay(relaxed) is None
    # ... while a confirmed upload must still be stored whole
    runner = Runner("mutant:non-atomic-upload", 0, atomic=False)
    assert runner.apply(upload(3)) is None and runner.check() is None
    assert runner.world.stored(0) and len(runner.world.stored(0)) == 3


def test_every_step_kind_runs_clean_on_the_spec_vehicle():
    steps = [
        {"op": "faults", "up": {"loss": 0.2, "duplicate": 0.1, "reorder": 0.1, "delay": 0.01,
                                "bursts": [[0.5, 2.0]]},
         "down": {"loss": 0.2, "delay": 0.01, "drops": [{"name": "MISSION_ACK", "nth": 1, "onwards": False}],
                  "cut": {"name": "MISSION_REQUEST_INT", "nth": 3, "span": 4}}},
        upload(30), {"op": "download", "type": 0},
        {"op": "cancel", "of": upload(10, t=2), "after": 0.05},
        {"op": "second_gcs", "first": upload(20), "second": upload(5), "after": 0.01},
        {"op": "stray", "during": upload(20), "after": 0.01, "messages": [
            {"msg": "MISSION_COUNT", "fields": {"count": 65535, "mission_type": 0, "opaque_id": 0},
             "to": "target", "from": "a"},
            {"msg": "MISSION_CLEAR_ALL", "fields": {"mission_type": 255}, "to": "other-system", "from": "b"},
            {"msg": "MISSION_COUNT", "fields": {"count": 3, "mission_type": 1, "opaque_id": 0},
             "to": "target", "from": "mute"}]},
        {"op": "set_current", "seq": 2, "command": True},
        {"op": "faults", "up": None, "down": None},
        {"op": "wait", "seconds": 12.0}, {"op": "download", "type": 0}, {"op": "clear", "type": 255},
    ]
    runner = Runner("builtin:spec", 4)
    for i, step in enumerate(steps):
        assert runner.apply(step) is None, (i, step)
        assert runner.check() is None, (i, step)
    results = [r.outcome.value for r in runner.world.a.results]
    assert "success" in results and "cancelled" in results
    assert runner.world.b.results[-1].nack is not None   # B was DENIED or refused mid-transfer
    assert all(runner.world.stored(t) == () for t in (0, 1, 2))


def test_a_vehicle_that_raises_is_a_crash_finding(monkeypatch):
    def boom(self, msg, src, now):
        raise ZeroDivisionError("planted")
    monkeypatch.setattr(MissionServer, "_on_clear_all", boom)
    case = Case("protocol", "builtin:spec", 0, ({"op": "clear", "type": 1}, {"op": "download", "type": 0}))
    v = replay(case)
    assert v is not None and v.invariant == "target-crash" and "ZeroDivisionError: planted" in v.detail


# A GCS that sends a MISSION_COUNT and then never answers (the mute one)
ABANDONED_UPLOAD = ({"op": "stray", "during": None, "after": 0.0, "messages": [
    {"msg": "MISSION_COUNT", "fields": {"count": 2, "mission_type": 0, "opaque_id": 0},
     "to": "target", "from": "mute"}]},)


def test_a_vehicle_that_never_gives_up_is_not_idle():
    """A GCS that sends a MISSION_COUNT and then never answers: the spec vehicle gives up
    after its retries; `mutant:never-gives-up` requests forever."""
    steps = ABANDONED_UPLOAD
    assert replay(Case("protocol", "builtin:spec", 0, steps)) is None
    v = replay(Case("protocol", "mutant:never-gives-up", 0, steps))
    assert v is not None and v.invariant == "idle" and "RECEIVING" in v.detail


def test_a_mutant_with_too_many_retries_breaks_the_retry_limit():
    # from A's first item on, its next 20 messages are lost: the vehicle re-requests to its limit
    steps = ({"op": "faults", "up": {"cut": {"name": "MISSION_ITEM_INT", "nth": 1, "span": 20}}}, upload(2))
    assert replay(Case("protocol", "builtin:spec", 0, steps)) is None
    v = replay(Case("protocol", "mutant:too-many-retries", 0, steps))
    assert v is not None and v.invariant == "retry-limit" and "limit is 5" in v.detail


def test_a_bad_step_in_a_case_is_a_usage_error():
    with pytest.raises(UsageError, match="step 1: upload step lacks items"):
        replay(Case("protocol", "builtin:spec", 0, ({"op": "wait", "seconds": 1}, {"op": "upload", "type": 0})))
    with pytest.raises(UsageError, match="step 0"):
        replay(Case("protocol", "builtin:spec", 0, ({"op": "fly"},)))


def test_knobs_shape_the_campaign():
    units: list[int] = []
    knobs = Knobs(max_items=50, steps=3, faults=False)
    assert search("builtin:spec", seed=2, max_examples=5, on_example=units.append, knobs=knobs) == []
    assert max(units) <= 3


def test_a_wall_time_budget_stops_the_search():
    units: list[int] = []
    assert search("builtin:spec", seed=1, stop_after=0.5, on_example=units.append) == []
    assert 0 < len(units) < 2000


def test_a_float_item_may_be_stored_truncated_as_a_c_vehicle_does():
    """Learned on ArduCopter SITL: a rally point sent by MISSION_ITEM with x = -1940 degE7
    (float -0.000194) was stored as -1939 (`x = packet.x * 1.0e7f`, a cast that truncates).
    Both conversions are versions the vehicle may hold; nothing else is."""
    from mavconform.fuzz.protocol.wire_plans import float_variant
    from mavconform.reference_impl.mission.items import MissionItem, MissionType
    plan = (MissionItem(0, 6, 5100, x=-1940, y=-5160, z=10.0, mission_type=MissionType.RALLY),)
    rounded, truncated = float_variant(plan), float_variant(plan, truncate=True)
    assert (rounded[0].x, rounded[0].y) == (-1940, -5160)
    assert (truncated[0].x, truncated[0].y) == (-1939, -5159)
    out_of_range = (MissionItem(0, 6, 5100, x=2_000_000_000, y=0, mission_type=MissionType.RALLY),)
    assert float_variant(out_of_range, {0: {"fx": 215.0}}, truncate=True) is None


def test_the_fuzzer_finds_the_crash_arducopter_sitl_had():
    """Learned on ArduCopter SITL (issue 11): a float MISSION_ITEM with param1 1.4e37 killed
    it (`cmd.p1 = packet.param1` into a uint16_t, floating-point exceptions on). The
    mutant dies the same way; the edge floats of the strategies must reach it."""
    # A seed's programs depend on the test selection (Hypothesis also draws constants from
    # the modules loaded), so seeds are tried until one finds it: alone, 10 of seeds 1-12 do
    # within 150 examples; in a full run fewer (5 seeds once missed it in 1 of 5 runs).
    crash: list[Case] = []
    for seed in range(1, 21):
        cases = search("mutant:dies-on-out-of-range-param", seed=seed, max_examples=150)
        crash = [c for c in cases if c.violation.invariant == "target-crash"]
        if crash:
            break
    assert crash and "param1" in crash[0].violation.detail
    assert replay(crash[0]).invariant == "target-crash"


def test_a_slow_machine_finds_the_same_cases_for_the_same_seed():
    """Hypothesis stops hunting for more bugs 10 s of wall time after the first; a loaded CI
    machine used to cross that and find other cases. Wall time jumping 30 s at every look
    must change nothing in virtual time."""
    assert _fresh_search("slow") == _fresh_search()