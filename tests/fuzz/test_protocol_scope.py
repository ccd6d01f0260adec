"""The protocol fuzzer keeps to what a profile says the vehicle has (fuzz/protocol/scope.py).

INAV 9.1 has no fence or rally plans (mission_type is ignored), no _INT forms, no
set-current, no empty upload and no way back to idle from an abandoned upload. Fuzzing
those only rediscovers the profile (before the scope: an "idle" finding on builtin:inav in
the first example); what is left must still be judged, and a planted bug still found.
"""

from __future__ import annotations

import pytest

from mavconform.fuzz.case import Case
from mavconform.fuzz.protocol import replay, search
from mavconform.fuzz.protocol.scope import Scope
from mavconform.fuzz.protocol.world import profile_from
from mavconform.reference_impl.mission.store import MissionStore

from .test_protocol import ABANDONED_UPLOAD, WAYPOINT, upload


@pytest.fixture(scope="module")
def inav() -> Scope:
    return profile_from("inav", "profile inav").scope


def test_the_spec_profile_fuzzes_everything():
    scope = profile_from("spec", "profile spec").scope
    step = {"op": "upload", "type": 1, "items": []}
    assert scope.whole and scope.adapt(step) is step and scope.describe() == "the whole protocol"


def test_inav_is_fuzzed_on_its_mission_in_the_float_forms(inav):
    assert not inav.whole and "as profile inav documents" in inav.describe()
    assert inav.adapt(upload(2, t=1)) is None                       # a fence upload would replace the mission
    assert inav.adapt({"op": "upload", "type": 0, "items": []}) is None   # COUNT 0 opens an upload
    assert inav.adapt({"op": "set_current", "seq": 1, "command": False}) is None
    assert inav.adapt({"op": "download", "type": 2}) is None
    assert inav.adapt({"op": "clear", "type": 255}) == {"op": "clear", "type": 255}
    step = upload(2)
    step["items"][1]["mission_type"] = 1
    adapted = inav.adapt(step)
    assert adapted["float"] is True and "mission_type" not in adapted["items"][1]
    assert step["items"][1]["mission_type"] == 1 and "float" not in step   # the drawn step is kept as drawn
    cancel = {"op": "cancel", "of": upload(3), "after": 0.1}
    assert inav.adapt(cancel)["of"]["float"] is True
    assert inav.adapt({"op": "second_gcs", "first": upload(3), "second": upload(1, t=2), "after": 0.1}) is None
    stray = {"op": "stray", "during": None, "after": 0.0, "messages": [
        {"msg": "MISSION_ITEM_INT", "fields": dict(WAYPOINT, seq=0, mission_type=0), "to": "target"},
        {"msg": "MISSION_COUNT", "fields": {"count": 0, "mission_type": 0, "opaque_id": 0}, "to": "target"},
        {"msg": "MISSION_COUNT", "fields": {"count": 2, "mission_type": 1, "opaque_id": 0}, "to": "target"}]}
    assert inav.adapt(stray) is None
    stray["messages"].append({"msg": "MISSION_CLEAR_ALL", "fields": {"mission_type": 0}, "to": "broadcast"})
    assert [r["msg"] for r in inav.adapt(stray)["messages"]] == ["MISSION_CLEAR_ALL"]


def test_a_campaign_against_builtin_inav_finds_nothing_it_documents():
    assert search("builtin:inav", seed=1, max_examples=60) == []


def test_an_upload_inav_is_left_with_is_not_an_idle_finding_but_is_on_the_spec_vehicle():
    """A GCS that sends MISSION_COUNT and falls silent: INAV has no upload timer and keeps
    the upload open (documented); a vehicle of the spec profile must give up."""
    steps = ABANDONED_UPLOAD
    assert replay(Case("protocol", "builtin:inav", 0, steps)) is None
    v = replay(Case("protocol", "mutant:never-gives-up", 0, steps))
    assert v is not None and v.invariant == "idle" and "RECEIVING" in v.detail


def test_inside_the_scope_a_planted_bug_is_still_found(monkeypatch):
    """A vehicle of the inav profile that loses the last item of what it stores."""
    kept = MissionStore.items
    monkeypatch.setattr(MissionStore, "items", lambda self, t: kept(self, t)[:-1] if len(kept(self, t)) > 1 else kept(self, t))
    v = replay(Case("protocol", "builtin:inav", 0, (upload(3), {"op": "download", "type": 0})))
    assert v is not None and v.invariant in ("atomic-upload", "download-matches-upload"), v
