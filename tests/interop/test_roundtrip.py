"""Property: random plans round-trip through every vehicle profile under link faults.

The reference GCS, left to pick its adaptations from the vehicle's HEARTBEAT, uploads a
random plan of a random type over a link with loss, duplication, reordering, delay and
jitter (no partitions), downloads it back, sets the current item and clears it. A failed
operation may be retried by hand (`roundtrip.ATTEMPTS` times, as a user would); after that,
every operation must have succeeded, and:
- the vehicle holds, and the download returns, the plan modulo the profile's documented
  transforms (`Profile.stored_items`: home item, rounding, frame forms);
- every operation ended with exactly one result and both ends were idle again in bounded time.
"""

from __future__ import annotations

import dataclasses
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.interop.harness import IDLE_BOUND, build_pair, expected_plan
from mavconform.reference_impl.interop.roundtrip import attempt
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionItem, MissionType as T
from mavconform.reference_impl.mission.validation import ItemRule, first_defect
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile

from ..strategies import fault_models, plan_items

# (inav ignores the _INT mission messages, which the reference GCS does not fall back from yet)
PROFILES = {name: p for name in BUILTIN_PROFILES if not (p := load_profile(name)).int_messages_ignored}
NAN_PARAM_CODES = (R.INVALID_PARAM1, R.INVALID_PARAM2, R.INVALID_PARAM3, R.INVALID_PARAM4)


def link_faults():
    """The fuzz tests' loss, duplication and reordering, without partitions (a link that is
    down for 12 s is a failure the user sees, not one a retry by hand hides)."""
    return fault_models(max_loss=0.15).map(lambda f: dataclasses.replace(f, partitions=()))


def acceptable(item: MissionItem, rules: tuple[ItemRule, ...]) -> MissionItem:
    """`item` as the profile takes it: the round trip is about transfers, not about what is
    acceptable. A NaN param the profile refuses (ArduPilot, A23: INVALID_PARAMn) becomes 0,
    and an item still refused (PX4: terrain frames, UNSUPPORTED_FRAME) moves to the relative frame."""
    defect = first_defect(item, rules)
    if defect is not None and defect.code in NAN_PARAM_CODES:
        item = dataclasses.replace(item, **{f"param{n}": 0.0 for n in (1, 2, 3, 4)
                                            if math.isnan(getattr(item, f"param{n}"))})
    if first_defect(item, rules) is not None:
        item = dataclasses.replace(item, frame=3)
    assert first_defect(item, rules) is None, item
    return item


def typed_plan():
    return st.sampled_from(PLAN_TYPES).flatmap(lambda t: st.tuples(st.just(t), plan_items(t, max_size=10)))


@pytest.mark.parametrize("name", sorted(PROFILES))
@given(seed=st.integers(0, 2**32 - 1), up=link_faults(), down=link_faults(), plan=typed_plan(),
       current=st.integers(0, 9))
def test_round_trip_through_the_profile_equals_the_plan_modulo_its_transforms(name, seed, up, down, plan, current):
    profile = PROFILES[name]
    pair = build_pair(profile, seed=seed, up=up, down=down)
    t, items = plan
    items = [acceptable(it, profile.behaviour.item_rules) for it in items]
    wanted = expected_plan(profile, items, t)

    def done(what, start):
        n = len(pair.gcs.results)
        result, attempts = attempt(pair, start)
        assert result is not None, f"{what}: no result (the GCS hung)"
        assert result.ok, f"{what} failed {attempts} times; last: {result.summary()}"
        assert pair.settle() is not None, f"{what}: not idle {IDLE_BOUND:g} s after its result"
        assert len(pair.gcs.results) == n + attempts, f"{what}: not one result per attempt"
        return result

    done("upload", lambda: pair.upload(t, items))
    assert pair.held(t) == wanted, "the vehicle does not hold the uploaded plan (modulo transforms)"
    down_result = done("download", lambda: pair.download(t))
    assert down_result.items == wanted, "downloaded plan != uploaded plan (modulo transforms)"
    if t is T.MISSION and items:
        seq = current % len(items)
        done("set current", lambda: pair.set_current(seq))
        home = 1 if profile.behaviour.home_at_seq0 else 0
        assert pair.vehicle.server.progress.seq == seq + home
    done("clear", lambda: pair.clear(t))
    assert pair.held(t) == ()
