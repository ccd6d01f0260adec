"""Scripted cases for the GCS-side engine: the vehicle is played by hand."""

from __future__ import annotations

from dataclasses import replace

import pytest

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.adaptations import ARDUPILOT, NONE, PX4
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.results import Operation, Outcome
from mavconform.reference_impl.mission.transitions import CLIENT_TRANSITIONS, ClientState
from mavconform.reference_impl.wire.dialect import mavlink as d

from .conftest import plan
from .script import GCS, VEHICLE, Script, names, only


def client(**kw) -> Script:
    return Script(MissionClient(*GCS, VEHICLE, **kw))


def req(seq, t=T.MISSION, as_int=True):
    return m.request_message(seq, t, GCS, as_int=as_int)


def vack(result, t=T.MISSION, opaque_id=0):
    return m.ack_message(result, t, GCS, opaque_id)


def result(s: Script):
    assert len(s.results) == 1, s.results
    return s.results[0]


# --- upload --------------------------------------------------------------------------------
def test_upload_answers_requests_and_succeeds_on_accept():
    s = client()
    items = plan(3)
    out = s.call(s.engine.upload(T.MISSION, items, s.now))
    assert names(out) == ["MISSION_COUNT"] and out[0].count == 3
    for i in range(3):
        out = s.feed(req(i), VEHICLE)
        assert names(out) == ["MISSION_ITEM_INT"] and m.item_from_message(out[0]) == items[i]
    out = s.feed(vack(R.ACCEPTED, opaque_id=77), VEHICLE)
    r = result(s)
    assert r.ok and r.opaque_id == 77 and r.operation is Operation.UPLOAD
    assert not s.engine.busy


def test_upload_answers_mission_request_with_mission_item():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(1), s.now))
    assert names(s.feed(req(0, as_int=False), VEHICLE)) == ["MISSION_ITEM"]


def test_upload_resends_count_then_times_out_after_five_retries():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(2), s.now))
    s.advance(30)
    counts = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_COUNT"]
    assert counts == pytest.approx([0.0, 1.5, 3.0, 4.5, 6.0, 7.5])
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and r.retries == 5 and r.max_consecutive_retries == 5
    assert r.finished == pytest.approx(9.0) and not r.outcome_unknown


def test_upload_nack_ends_with_the_code():
    s = client()
    s.call(s.engine.upload(T.FENCE, plan(2, T.FENCE), s.now))
    s.feed(vack(R.NO_SPACE, T.FENCE), VEHICLE)
    r = result(s)
    assert (r.outcome, r.nack) == (Outcome.NACK, R.NO_SPACE)


def test_upload_ack_of_another_type_is_not_ours():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(1), s.now))
    s.feed(vack(R.ACCEPTED, T.FENCE), VEHICLE)
    s.feed(vack(R.ERROR, T.RALLY), VEHICLE)
    assert s.results == [] and s.engine.busy


def test_an_ack_addressed_to_another_system_or_component_is_not_ours():
    # seed 001's routing: another GCS's reply on a shared link is not about our operation
    for target in [(GCS[0] - 1, GCS[1]), (GCS[0], GCS[1] + 1)]:
        s = client()
        s.call(s.engine.upload(T.MISSION, plan(1), s.now))
        s.feed(req(0), VEHICLE)
        s.feed(m.ack_message(R.DENIED, T.MISSION, target), VEHICLE)
        assert s.results == [] and s.engine.busy, target
        s.feed(m.ack_message(R.ACCEPTED, T.MISSION, (GCS[0], 0)), VEHICLE)   # broadcast component: ours
        assert result(s).ok


def test_upload_early_accept_is_a_protocol_error():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(vack(R.ACCEPTED), VEHICLE)
    assert result(s).outcome is Outcome.PROTOCOL_ERROR


def test_upload_request_beyond_count_is_a_protocol_error_and_nacked():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(2), s.now))
    out = s.feed(req(5), VEHICLE)
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.INVALID_SEQUENCE]
    assert result(s).outcome is Outcome.PROTOCOL_ERROR


def test_lost_final_ack_resends_last_item_and_reports_outcome_unknown():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(2), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(req(1), VEHICLE)
    out = s.advance(30)
    resent = only(out, "MISSION_ITEM_INT")
    assert len(resent) == 5 and {x.seq for x in resent} == {1}
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and r.outcome_unknown


def test_timeout_before_last_item_is_a_known_outcome():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    s.feed(req(0), VEHICLE)
    s.advance(30)
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and not r.outcome_unknown


def test_empty_upload_is_count_zero_then_accept():
    s = client()
    out = s.call(s.engine.upload(T.RALLY, [], s.now))
    assert out[0].count == 0
    s.feed(vack(R.ACCEPTED, T.RALLY), VEHICLE)
    assert result(s).ok


# --- download ------------------------------------------------------------------------------
def _download_reply(items, seq, as_int=True):
    return m.item_message(items[seq], GCS, as_int=as_int)


def test_download_requests_each_item_and_acks():
    s = client()
    items = plan(3)
    out = s.call(s.engine.download(T.MISSION, s.now))
    assert names(out) == ["MISSION_REQUEST_LIST"]
    out = s.feed(m.count_message(3, T.MISSION, GCS, 42), VEHICLE)
    for i in range(3):
        assert names(out) == ["MISSION_REQUEST_INT"] and out[0].seq == i
        out = s.feed(_download_reply(items, i), VEHICLE)
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.ACCEPTED]
    r = result(s)
    assert r.ok and r.items == tuple(items) and r.opaque_id == 42


def test_download_drops_out_of_sequence_items_and_rerequests():
    s = client()
    items = plan(3)
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(3, T.MISSION, GCS), VEHICLE)
    out = s.feed(_download_reply(items, 2), VEHICLE)
    assert names(out) == ["MISSION_REQUEST_INT"] and out[0].seq == 0
    for i in range(3):
        s.feed(_download_reply(items, i), VEHICLE)
    assert result(s).items == tuple(items)


def test_download_accepts_float_items():
    s = client(download_int=False)
    items = plan(1)
    out = s.call(s.engine.download(T.MISSION, s.now))
    out = s.feed(m.count_message(1, T.MISSION, GCS), VEHICLE)
    assert names(out) == ["MISSION_REQUEST"]
    s.feed(_download_reply(items, 0, as_int=False), VEHICLE)
    got = result(s).items[0]
    assert abs(got.x - items[0].x) <= 64


def test_download_retries_item_requests_every_250ms_then_times_out():
    s = client()
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    s.advance(5)
    times = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_REQUEST_INT"]
    assert times == pytest.approx([0.0, 0.25, 0.5, 0.75, 1.0, 1.25])
    assert result(s).outcome is Outcome.TIMEOUT


def test_download_resends_request_list():
    s = client()
    s.call(s.engine.download(T.MISSION, s.now))
    s.advance(2.0)
    assert len(only([msg for _, msg in s.sent_at], "MISSION_REQUEST_LIST")) == 2


def test_download_of_empty_plan_acks_and_succeeds_with_no_items():
    s = client()
    s.call(s.engine.download(T.FENCE, s.now))
    out = s.feed(m.count_message(0, T.FENCE, GCS), VEHICLE)
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.ACCEPTED]
    assert result(s).items == ()


def test_download_nack_and_wrong_type_item():
    s = client()
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    s.feed(vack(R.INVALID_SEQUENCE), VEHICLE)
    assert result(s).nack == R.INVALID_SEQUENCE
    s2 = client()
    s2.call(s2.engine.download(T.MISSION, s2.now))
    s2.feed(m.count_message(1, T.MISSION, GCS), VEHICLE)
    s2.feed(_download_reply(plan(1, T.FENCE), 0), VEHICLE)
    assert result(s2).outcome is Outcome.PROTOCOL_ERROR


# --- clear, set current --------------------------------------------------------------------
def test_clear_resends_and_succeeds_on_ack():
    s = client()
    s.call(s.engine.clear(T.ALL, s.now))
    s.advance(1.6)
    assert len(only([msg for _, msg in s.sent_at], "MISSION_CLEAR_ALL")) == 2
    s.feed(vack(R.ACCEPTED, T.ALL), VEHICLE)
    assert result(s).ok


def test_clear_timeout_is_outcome_unknown_and_nack_is_known():
    s = client()
    s.call(s.engine.clear(T.MISSION, s.now))
    s.advance(20)
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and r.outcome_unknown
    s2 = client()
    s2.call(s2.engine.clear(T.MISSION, s2.now))
    s2.feed(vack(R.DENIED), VEHICLE)
    assert result(s2).nack == R.DENIED and not result(s2).outcome_unknown


def test_set_current_waits_for_matching_mission_current():
    s = client()
    s.call(s.engine.set_current(4, s.now))
    s.feed(m.current_message(2, 9, 2, 2, (0, 0, 0)), VEHICLE)   # the old current: keep waiting
    assert s.results == []
    s.feed(m.current_message(4, 9, 2, 2, (0, 0, 0)), VEHICLE)
    assert result(s).ok


def test_set_current_rejected_by_statustext_or_command_ack():
    s = client()
    s.call(s.engine.set_current(9, s.now))
    s.feed(m.statustext_message(4, "Set current failed"), VEHICLE)
    assert result(s).outcome is Outcome.REJECTED
    s2 = client()
    out = s2.call(s2.engine.set_current(9, s2.now, via_command=True))
    assert names(out) == ["COMMAND_LONG"] and out[0].command == 224 and out[0].param1 == 9
    s2.feed(m.command_ack_message(224, 4, GCS), VEHICLE)
    assert result(s2).outcome is Outcome.REJECTED


# --- cancel, concurrency, addressing -------------------------------------------------------
@pytest.mark.parametrize("start", ["upload", "download"])
def test_cancel_sends_operation_cancelled_and_finishes_once(start):
    s = client()
    op = getattr(s.engine, start)
    s.call(op(T.MISSION, plan(2), s.now) if start == "upload" else op(T.MISSION, s.now))
    out = s.call(s.engine.cancel(s.now))
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.OPERATION_CANCELLED]
    assert result(s).outcome is Outcome.CANCELLED
    assert s.advance(30) == [] and len(s.results) == 1


def test_idle_client_answers_a_stray_request_with_cancelled():
    s = client()
    out = s.feed(req(3), VEHICLE)
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.OPERATION_CANCELLED]
    assert s.feed(vack(R.ACCEPTED), VEHICLE) == []


def test_second_operation_while_busy_is_the_callers_bug():
    s = client()
    s.call(s.engine.download(T.MISSION, s.now))
    with pytest.raises(LocalProtocolError):
        s.engine.upload(T.MISSION, plan(1), s.now)


def test_messages_from_other_systems_are_ignored():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(1), s.now))
    assert s.feed(req(0), (9, 1)) == []
    assert s.feed(m.request_message(0, T.MISSION, (77, 1)), VEHICLE) == []


def test_every_operation_ends_with_exactly_one_finished_action():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(1), s.now))
    s.feed(req(0), VEHICLE)
    s.feed(vack(R.ACCEPTED), VEHICLE)
    s.feed(vack(R.ACCEPTED), VEHICLE)      # a duplicate ACK after the end
    s.advance(30)
    assert len(s.results) == 1


def test_client_transition_table_is_covered():
    seen = set()
    # walk one engine per operation through its retries and its success
    engines = []
    for op in ("upload", "download", "clear", "set_current", "silent_upload", "silent_download",
               "clear_types_separately", "restarted_download"):
        adapt = {"clear_types_separately": ARDUPILOT, "restarted_download": PX4}.get(op, NONE)
        e = Script(MissionClient(*GCS, VEHICLE, adaptations=adapt))
        engines.append(e)
        if op == "upload":
            e.call(e.engine.upload(T.MISSION, plan(2), e.now))
            e.advance(2)
            e.feed(req(0), VEHICLE)
            e.advance(2)
            e.feed(req(1), VEHICLE)
            e.feed(vack(R.ACCEPTED), VEHICLE)
        elif op == "download":
            e.call(e.engine.download(T.MISSION, e.now))
            e.advance(2)
            e.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
            e.feed(_download_reply(plan(2), 1), VEHICLE)
            e.advance(0.3)
            e.feed(_download_reply(plan(2), 0), VEHICLE)
            e.feed(_download_reply(plan(2), 1), VEHICLE)
        elif op == "clear":
            e.call(e.engine.clear(T.MISSION, e.now))
            e.advance(2)
            e.feed(vack(R.ACCEPTED), VEHICLE)
        elif op == "set_current":
            e.call(e.engine.set_current(1, e.now))
            e.advance(2)
            e.feed(m.current_message(1, 2, 2, 2, (0, 0, 0)), VEHICLE)
        elif op == "silent_upload":
            e.call(e.engine.upload(T.MISSION, plan(1), e.now))
            e.advance(30)
        elif op == "restarted_download":
            e.call(e.engine.download(T.MISSION, e.now))
            e.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
            e.feed(vack(R.ERROR), VEHICLE)          # restart from DOWNLOAD_REQUESTING
            e.feed(vack(R.ERROR), VEHICLE)          # and again before the COUNT came back
            e.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
            e.feed(_download_reply(plan(2), 0), VEHICLE)
            e.feed(_download_reply(plan(2), 1), VEHICLE)
        elif op == "clear_types_separately":
            e.call(e.engine.clear(T.ALL, e.now))
            for t in (T.MISSION, T.FENCE, T.RALLY):
                e.feed(vack(R.ACCEPTED, t), VEHICLE)
        else:
            e.call(e.engine.download(T.MISSION, e.now))
            e.advance(30)
        seen |= {(before, event) for before, event, _ in e.engine.history}
    assert seen == set(CLIENT_TRANSITIONS), set(CLIENT_TRANSITIONS) - seen
    assert all(e.engine.state is ClientState.IDLE for e in engines)


def test_cancelled_or_unanswered_empty_upload_is_an_unknown_outcome():
    """MISSION_COUNT 0 is the whole upload: once sent, the vehicle may already have cleared
    (found by the property test: count 0 then an immediate cancel was reported as 'known')."""
    s = client()
    s.call(s.engine.upload(T.MISSION, [], s.now))
    s.call(s.engine.cancel(s.now))
    assert result(s).outcome is Outcome.CANCELLED and result(s).outcome_unknown
    s2 = client()
    s2.call(s2.engine.upload(T.MISSION, [], s2.now))
    s2.advance(30)
    assert result(s2).outcome is Outcome.TIMEOUT and result(s2).outcome_unknown


def test_a_vehicle_stuck_on_one_request_cannot_hold_the_upload():
    """Review finding: repeated requests for the same item answered but not counted as
    progress; the upload ends by timeout in bounded time."""
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(3), s.now))
    for _ in range(200):
        s.feed(req(0), VEHICLE)
        s.advance(0.2)
        if s.results:
            break
    r = result(s)
    assert r.outcome is Outcome.TIMEOUT and s.now < 12


def test_a_vehicle_alternating_requests_is_a_protocol_error_not_a_loop():
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(2), s.now))
    for i in range(1000):
        s.feed(req(i % 2), VEHICLE)
        if s.results:
            break
    r = result(s)
    assert r.outcome is Outcome.PROTOCOL_ERROR and "requested items" in r.detail


def test_stale_messages_from_an_earlier_operation_are_ignored():
    """Review finding: a late ACCEPTED before any request, or a late item of another type
    with the wrong seq, must not end the next operation."""
    s = client()
    s.call(s.engine.upload(T.MISSION, plan(2), s.now))
    s.feed(vack(R.ACCEPTED), VEHICLE)                # a late copy from before
    assert s.results == [] and s.engine.busy
    s2 = client()
    s2.call(s2.engine.download(T.FENCE, s2.now))
    s2.feed(m.count_message(2, T.FENCE, GCS), VEHICLE)
    s2.feed(vack(R.ACCEPTED, T.FENCE), VEHICLE)
    s2.feed(_download_reply(plan(3), 2), VEHICLE)     # a stale mission item, seq 2
    assert s2.results == []
    for i in range(2):
        s2.feed(_download_reply(plan(2, T.FENCE), i), VEHICLE)
    assert result(s2).ok


def test_download_duplicates_do_not_multiply_requests():
    s = client()
    items = plan(10)
    out = s.call(s.engine.download(T.MISSION, s.now))
    out = s.feed(m.count_message(10, T.MISSION, GCS), VEHICLE)
    for _ in range(10):
        seq = out[-1].seq
        out = s.feed(_download_reply(items, seq), VEHICLE)
        s.feed(_download_reply(items, seq), VEHICLE)
    assert result(s).items == tuple(items)
    assert len(only([msg for _, msg in s.sent_at], "MISSION_REQUEST_INT")) == 10


def test_cancelled_clear_is_an_unknown_outcome():
    s = client()
    s.call(s.engine.clear(T.MISSION, s.now))
    s.call(s.engine.cancel(s.now))
    assert result(s).outcome_unknown


def test_set_current_by_command_is_not_rejected_by_an_unrelated_statustext():
    s = client()
    s.call(s.engine.set_current(2, s.now, via_command=True))
    s.feed(m.statustext_message(4, "Low battery"), VEHICLE)
    assert s.results == []
    s.feed(m.command_ack_message(224, 0, GCS), VEHICLE)
    s.feed(m.current_message(2, 5, 2, 2, (0, 0, 0)), VEHICLE)
    assert result(s).ok


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
        s.feed(_download_reply(stored, i), VEHICLE)
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
    s.feed(_download_reply(items, 0), VEHICLE)
    out = s.feed(vack(R.ERROR), VEHICLE)      # P6: a stale duplicate request ended it
    assert names(out) == ["MISSION_REQUEST_LIST"] and s.results == []
    s.feed(m.count_message(2, T.MISSION, GCS), VEHICLE)
    s.feed(_download_reply(items, 0), VEHICLE)
    s.feed(_download_reply(items, 1), VEHICLE)
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
