"""Scripted cases for the GCS-side engine's adaptations to PX4 and ArduPilot (VARIANTS.md;
adaptations.py), and the stale ACKs a clear must not take for its answer: the vehicle is
played by hand."""

from __future__ import annotations

from dataclasses import replace

import pytest

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.adaptations import ARDUPILOT, NONE, PX4
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.results import Outcome
from mavconform.reference_impl.wire.dialect import mavlink as d

from .client_script import client, download_reply, req, result, vack
from .conftest import plan
from .script import GCS, VEHICLE, Script, names, only


# --- adaptations (VARIANTS.md; adaptations.py) ---------------------------------------------
def test_home_at_seq0_upload_sends_a_placeholder_and_count_plus_one():
    s = client(adaptations=ARDUPILOT)
    items = plan(3)
    out = s.call(s.engine.upload(T.MISSION, items, s.now))
    assert out[0].count == 4
    sent = [m.item_from_message(only(s.feed(req(i, as_int=False), VEHICLE), "MISSION_ITEM_INT")[0])
            for i in range(4)]
    assert sent[0].command == 16 and sent[0].seq == 0
    assert [i.seq for i in sent[1:]] == [1, 2, 3]
    assert [(i.x, i.y, i.z) for i in sent[1:]] == [(i.x, i.y, i.z) for i in items]
    s.feed(vack(R.ACCEPTED), VEHICLE)
    r = result(s)
    assert r.ok and r.adaptations == ("home-at-seq0", "item-int-for-request")   # no wait was stretched


def test_home_at_seq0_applies_to_missions_only_and_not_to_an_empty_upload():
    s = client(adaptations=ARDUPILOT)
    assert s.call(s.engine.upload(T.FENCE, plan(2, T.FENCE), s.now))[0].count == 2
    s2 = client(adaptations=ARDUPILOT)
    assert s2.call(s2.engine.upload(T.MISSION, [], s2.now))[0].count == 0


def test_home_at_seq0_download_drops_item_0():
    s = client(adaptations=ARDUPILOT)
    stored = plan(3)            # as the vehicle holds it: [home, a, b]
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(3, T.MISSION, GCS), VEHICLE)
    for i in range(3):
        s.feed(download_reply(stored, i), VEHICLE)
    r = result(s)
    assert r.ok and r.items == (replace(stored[1], seq=0), replace(stored[2], seq=1))
    assert r.adaptations == ("home-at-seq0",)


def test_home_at_seq0_set_current_adds_one():
    s = client(adaptations=ARDUPILOT)
    out = s.call(s.engine.set_current(2, s.now))
    assert out[0].seq == 3
    s.feed(m.current_message(2, 4, 2, 2, (0, 0, 0)), VEHICLE)   # not ours yet
    assert s.results == []
    s.feed(m.current_message(3, 4, 2, 2, (0, 0, 0)), VEHICLE)
    assert result(s).ok and result(s).adaptations == ("home-at-seq0",)


def test_mission_request_is_answered_with_item_int_only_when_adapted():
    for adapt, expected, used in ((NONE, "MISSION_ITEM", ()), (PX4, "MISSION_ITEM_INT", ("item-int-for-request",))):
        s = client(adaptations=adapt)
        s.call(s.engine.upload(T.MISSION, plan(1), s.now))
        assert names(s.feed(req(0, as_int=False), VEHICLE)) == [expected]
        s.feed(vack(R.ACCEPTED), VEHICLE)
        assert result(s).adaptations == used


def test_nonterminating_invalid_sequence_nack_is_ignored_mid_upload():
    s = client(adaptations=ARDUPILOT)
    items = plan(2)
    s.call(s.engine.upload(T.MISSION, items, s.now))
    s.feed(req(0), VEHICLE)
    s.feed(req(1), VEHICLE)
    assert s.feed(vack(R.INVALID_SEQUENCE), VEHICLE) == [] and s.results == []   # A3
    assert s.feed(vack(R.DENIED), VEHICLE) == [] and s.results == []
    s.feed(req(2), VEHICLE)
    s.feed(vack(R.ACCEPTED), VEHICLE)
    r = result(s)
    assert r.ok and "ignore-nonterminating-nack" in r.adaptations
    spec = client()
    spec.call(spec.engine.upload(T.MISSION, items, spec.now))
    spec.feed(req(0), VEHICLE)
    spec.feed(vack(R.INVALID_SEQUENCE), VEHICLE)
    assert result(spec).outcome is Outcome.NACK and not result(spec).adaptations


def test_failed_upload_to_a_non_atomic_vehicle_is_an_unknown_outcome():
    s = client(adaptations=ARDUPILOT)
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(vack(R.ERROR), VEHICLE)     # not ignored: only INVALID_SEQUENCE / DENIED are
    r = result(s)
    assert r.outcome is Outcome.NACK and r.outcome_unknown and "non-atomic-upload" in r.adaptations
    refused = client(adaptations=ARDUPILOT)   # a refused MISSION_COUNT changed nothing
    refused.call(refused.engine.upload(T.MISSION, plan(3), refused.now))
    refused.feed(vack(R.NO_SPACE), VEHICLE)
    assert not result(refused).outcome_unknown


def test_denied_opening_message_is_retried_while_the_vehicle_may_hold_an_old_transfer():
    s = client(adaptations=ARDUPILOT)
    s.call(s.engine.download(T.FENCE, s.now))
    s.feed(vack(R.DENIED, T.FENCE), VEHICLE)
    assert s.results == []
    s.advance(1.5)
    assert s.sent_at[-1][0] == 1.5 and names([s.sent_at[-1][1]]) == ["MISSION_REQUEST_LIST"]
    s.feed(m.count_message(0, T.FENCE, GCS), VEHICLE)
    assert result(s).ok and result(s).adaptations == ("long-vehicle-timeout",)
    # denied for longer than the vehicle's timeout: the NACK is the result
    s2 = client(adaptations=ARDUPILOT)
    s2.call(s2.engine.download(T.FENCE, s2.now))
    for _ in range(12):
        s2.feed(vack(R.DENIED, T.FENCE), VEHICLE)
        s2.advance(1.5)
    r = result(s2)
    assert (r.outcome, r.nack) == (Outcome.NACK, R.DENIED) and r.finished <= 9.5 + 1.5


def test_clear_all_types_one_by_one():
    s = client(adaptations=ARDUPILOT)
    out = s.call(s.engine.clear(T.ALL, s.now))
    assert [o.mission_type for o in out] == [T.MISSION]
    assert [o.mission_type for o in s.feed(vack(R.ACCEPTED, T.MISSION), VEHICLE)] == [T.FENCE]
    s.feed(vack(R.ACCEPTED, T.MISSION), VEHICLE)          # a duplicate: not about the fence
    assert s.results == []
    s.feed(vack(R.ACCEPTED, T.FENCE), VEHICLE)
    s.feed(vack(R.ACCEPTED, T.RALLY), VEHICLE)
    r = result(s)
    assert r.ok and r.mission_type is T.ALL and r.adaptations == ("clear-types-separately",)
    s2 = client(adaptations=ARDUPILOT)
    s2.call(s2.engine.clear(T.ALL, s2.now))
    s2.feed(vack(R.ACCEPTED, T.MISSION), VEHICLE)
    s2.feed(vack(R.ERROR, T.FENCE), VEHICLE)
    r2 = result(s2)
    assert r2.outcome is Outcome.NACK and r2.outcome_unknown and "mission" in r2.detail


def test_long_vehicle_timeout_waits_out_the_vehicle_before_giving_up():
    s = client(adaptations=ARDUPILOT)     # vehicle re-requests every ~1 s, gives up after 8 s
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(req(1), VEHICLE)               # progress at t=0, then silence
    s.advance(60)
    resends = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_ITEM_INT" and t > 0]
    assert resends == pytest.approx([2.0, 4.0, 6.0, 8.0, 10.0])   # 2 x the vehicle's interval
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and r.max_consecutive_retries == 5
    assert r.finished == pytest.approx(12.0) and r.finished >= 8.0 + 1.5
    px4 = client(adaptations=PX4)          # 250 ms re-requests, 5 s: our own waits cover it
    px4.call(px4.engine.upload(T.MISSION, plan(3), px4.now))
    px4.feed(req(0), VEHICLE)
    px4.advance(60)
    r = result(px4)
    assert r.finished == pytest.approx(9.0) and "long-vehicle-timeout" not in r.adaptations


def test_long_vehicle_timeout_outlasts_fast_gcs_timings():
    from mavconform.reference_impl.mission.timing import Timings
    s = Script(MissionClient(*GCS, VEHICLE, Timings(default_timeout=0.5), adaptations=ARDUPILOT))
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.advance(60)
    r = result(s)   # own retries end at 6 x 2 s = 12 s > 8 s anyway; wait-out not needed
    assert r.finished == pytest.approx(12.0)
    s = Script(MissionClient(*GCS, VEHICLE, Timings(default_timeout=0.5), adaptations=PX4))
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.advance(60)
    r = result(s)   # own retries would end at 3 s; the vehicle's 5 s timeout is waited out
    assert r.finished == pytest.approx(5.5) and "long-vehicle-timeout" in r.adaptations
    assert r.max_consecutive_retries == 5


def test_download_answered_with_the_wrong_item_ends_without_a_request_storm():
    s = client()
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(3, T.MISSION, GCS), VEHICLE)
    wrong = plan(3)[1]
    for _ in range(40):   # the vehicle answers every request for 0 with item 1
        s.feed(m.item_message(wrong, GCS), VEHICLE)
        s.advance(0.05)
    s.advance(30)
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and "seq 0 with seq 1" in r.detail
    requests = only([msg for _, msg in s.sent_at], "MISSION_REQUEST_INT")
    assert len(requests) <= 2 * (1 + 5)   # one timer request and one gap re-request per period


def test_download_restarts_after_a_vehicle_error_when_adapted():
    s = client(adaptations=PX4)
    items = plan(2)
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    s.feed(download_reply(items, 0), VEHICLE)
    out = s.feed(vack(R.ERROR), VEHICLE)      # P6: a stale duplicate request ended it
    assert names(out) == ["MISSION_REQUEST_LIST"] and s.results == []
    s.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    s.feed(download_reply(items, 0), VEHICLE)
    s.feed(download_reply(items, 1), VEHICLE)
    r = result(s)
    assert r.ok and r.items == tuple(items) and r.adaptations == ("restart-download-on-error",)
    s2 = client(adaptations=PX4)              # bounded: the sixth error is the result
    s2.call(s2.engine.download(T.MISSION, s2.now))
    for _ in range(6):
        s2.feed(vack(R.ERROR), VEHICLE)
    assert result(s2).outcome is Outcome.NACK
    spec = client()
    spec.call(spec.engine.download(T.MISSION, spec.now))
    spec.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    spec.feed(vack(R.ERROR), VEHICLE)
    assert result(spec).outcome is Outcome.NACK


def test_a_cancel_before_any_reply_is_about_an_earlier_transfer():
    s = client()
    s.call(s.engine.download(T.FENCE, s.now))
    s.feed(vack(R.OPERATION_CANCELLED, T.FENCE), VEHICLE)   # late reply to a stray copy
    assert s.results == []
    s.feed(m.count_message(0, T.FENCE, GCS), VEHICLE)
    assert result(s).ok
    s2 = client()          # a vehicle that only ever cancels: reported after the retries
    s2.call(s2.engine.upload(T.MISSION, plan(1), s2.now))
    for _ in range(8):
        s2.feed(vack(R.OPERATION_CANCELLED), VEHICLE)
        s2.advance(1.5)
    r = result(s2)
    assert (r.outcome, r.nack) == (Outcome.NACK, R.OPERATION_CANCELLED) and r.finished == pytest.approx(9.0)


def test_refused_set_current_is_retried_after_cancelling_stale_transfers():
    s = client(adaptations=PX4)
    s.call(s.engine.set_current(1, s.now))
    out = s.feed(d.MAVLink_statustext_message(4, b"Set current refused: a transfer is in progress", 0, 0), VEHICLE)
    assert names(out) == ["MISSION_ACK"] * 3 and {o.type for o in out} == {R.OPERATION_CANCELLED}
    assert s.results == []
    s.advance(1.5)
    assert names([s.sent_at[-1][1]]) == ["MISSION_SET_CURRENT"]
    s.feed(m.current_message(1, 2, 2, 2, (0, 0, 0)), VEHICLE)
    assert result(s).ok and result(s).adaptations == ("retry-refused-set-current",)
    s2 = client(adaptations=PX4)      # busy every time: REJECTED after the retries
    s2.call(s2.engine.set_current(1, s2.now))
    for _ in range(7):
        s2.feed(d.MAVLink_statustext_message(4, b"WPM: IGN WP CURR CMD: Busy", 0, 0), VEHICLE)
        s2.advance(1.5)
    r = result(s2)
    assert r.outcome is Outcome.REJECTED and "Busy" in r.detail and r.retries == 5
    spec = client()
    spec.call(spec.engine.set_current(1, spec.now))
    spec.feed(d.MAVLink_statustext_message(4, b"Set current failed", 0, 0), VEHICLE)
    assert result(spec).outcome is Outcome.REJECTED and not result(spec).outcome_unknown


def test_requests_after_a_successful_upload_are_served_from_it_when_adapted():
    s = client(adaptations=ARDUPILOT)
    items = plan(2)
    s.call(s.engine.upload(T.MISSION, items, s.now))
    for i in range(3):
        s.feed(req(i, as_int=False), VEHICLE)
    s.feed(vack(R.ACCEPTED), VEHICLE)
    assert result(s).ok
    # a late duplicate MISSION_COUNT restarted the upload on the vehicle (A2, A4)
    out = s.feed(req(2, as_int=False), VEHICLE)
    assert names(out) == ["MISSION_ITEM_INT"] and m.item_from_message(out[0]) == replace(items[1], seq=2)
    assert "finish-restarted-upload" in s.engine.used
    assert names(s.feed(req(3, as_int=False), VEHICLE)) == ["MISSION_ACK"]   # beyond it: cancel
    s.call(s.engine.clear(T.MISSION, s.now))     # a clear forgets it
    s.feed(vack(R.ACCEPTED), VEHICLE)
    assert names(s.feed(req(1), VEHICLE)) == ["MISSION_ACK"]
    spec = client()
    spec.call(spec.engine.upload(T.MISSION, items, spec.now))
    spec.feed(req(0), VEHICLE)
    spec.feed(req(1), VEHICLE)
    spec.feed(vack(R.ACCEPTED), VEHICLE)
    assert names(spec.feed(req(0), VEHICLE)) == ["MISSION_ACK"]


def test_a_generic_nack_after_the_last_item_waits_for_a_late_accept_when_adapted():
    s = client(adaptations=ARDUPILOT)
    s.call(s.engine.upload(T.MISSION, plan(1), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(req(1), VEHICLE)                 # home placeholder + 1 item: the last one is out
    s.feed(vack(R.ERROR), VEHICLE)          # its reply to a late duplicate, ahead of ...
    assert s.results == []
    s.feed(vack(R.ACCEPTED), VEHICLE)       # ... the ACCEPTED
    assert result(s).ok and "await-accept-after-nack" in result(s).adaptations
    s2 = client(adaptations=ARDUPILOT)      # no ACCEPTED follows: an unknown outcome, 1.5 s on
    s2.call(s2.engine.upload(T.MISSION, plan(1), s2.now))
    s2.feed(req(0), VEHICLE)
    s2.feed(req(1), VEHICLE)
    s2.advance(0.5)
    s2.feed(vack(R.ERROR), VEHICLE)
    s2.advance(30)
    r = result(s2)
    assert (r.outcome, r.nack, r.outcome_unknown) == (Outcome.NACK, R.ERROR, True)
    assert r.finished == pytest.approx(2.0)
    s3 = client(adaptations=ARDUPILOT)      # a NACK about the item itself is final at once
    s3.call(s3.engine.upload(T.MISSION, plan(1), s3.now))
    s3.feed(req(0), VEHICLE)
    s3.feed(req(1), VEHICLE)
    s3.feed(vack(R.INVALID_PARAM1), VEHICLE)
    assert result(s3).nack is R.INVALID_PARAM1


# --- stale ACKs during a clear (found by the protocol fuzzer) -------------------------------
# MISSION_ACK carries no operation id; a late copy of an earlier operation's ACK must not be
# taken as the answer to MISSION_CLEAR_ALL when it can be told apart.

def _clear_session(up, down):
    from ..rigs import vehicle_and_gcs
    r = vehicle_and_gcs(seed=0, up=up, down=down, discovery=10)
    return r.net, r.vehicle, r.session


def test_a_late_upload_accept_does_not_answer_a_lost_clear():
    from mavconform.reference_impl.net import DropMessage, FaultModel

    net, vehicle, s = _clear_session(FaultModel(rules=(DropMessage("MISSION_CLEAR_ALL", 1),)),
                                     FaultModel(duplicate=1.0, reorder=1.0, reorder_delay=0.5))
    rally = [MissionItem(0, 0, 5100, x=473977420, y=85455940, z=10.0, mission_type=MissionType.RALLY)]
    assert s.upload(MissionType.RALLY, rally).ok
    result = s.clear(MissionType.RALLY)
    assert result.ok and vehicle.store.count(MissionType.RALLY) == 0   # the resent clear did it


def test_a_late_item_nack_does_not_answer_a_clear():
    from mavconform.reference_impl.net import DropWhere, FaultModel

    clear_ack = DropWhere(lambda m: m.get_type() == "MISSION_ACK" and m.type == 0 and m.opaque_id == 0, limit=1)
    net, vehicle, s = _clear_session(None, FaultModel(duplicate=1.0, reorder=1.0, reorder_delay=0.5,
                                                      rules=(clear_ack,)))
    assert s.upload(MissionType.MISSION, [MissionItem(0, 3, 16, x=473977420, y=85455940, z=10.0)]).ok
    net.run_for(2.0)
    bad = [MissionItem(0, 3, 16, param2=float("inf"), x=473977420, y=85455940, z=10.0)]
    assert not s.upload(MissionType.MISSION, bad).ok                   # refused: INVALID_PARAM2
    result = s.clear(MissionType.MISSION)
    assert vehicle.store.count(MissionType.MISSION) == 0
    assert result.ok or result.outcome_unknown, result.summary()
