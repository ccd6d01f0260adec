"""Scripted cases for the GCS-side engine: the vehicle is played by hand."""

from __future__ import annotations

import pytest

from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.adaptations import ARDUPILOT, NONE, PX4
from mavconform.reference_impl.mission.client import MissionClient
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.results import Operation, Outcome
from mavconform.reference_impl.mission.transitions import CLIENT_TRANSITIONS, ClientState

from .client_script import client, download_reply, req, result, vack
from .conftest import plan
from .script import GCS, VEHICLE, Script, names, only


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
def test_download_requests_each_item_and_acks():
    s = client()
    items = plan(3)
    out = s.call(s.engine.download(T.MISSION, s.now))
    assert names(out) == ["MISSION_REQUEST_LIST"]
    out = s.feed(m.count_message(3, T.MISSION, GCS, 42), VEHICLE)
    for i in range(3):
        assert names(out) == ["MISSION_REQUEST_INT"] and out[0].seq == i
        out = s.feed(download_reply(items, i), VEHICLE)
    assert [a.type for a in only(out, "MISSION_ACK")] == [R.ACCEPTED]
    r = result(s)
    assert r.ok and r.items == tuple(items) and r.opaque_id == 42


def test_download_drops_out_of_sequence_items_and_rerequests():
    s = client()
    items = plan(3)
    s.call(s.engine.download(T.MISSION, s.now))
    s.feed(m.count_message(3, T.MISSION, GCS), VEHICLE)
    out = s.feed(download_reply(items, 2), VEHICLE)
    assert names(out) == ["MISSION_REQUEST_INT"] and out[0].seq == 0
    for i in range(3):
        s.feed(download_reply(items, i), VEHICLE)
    assert result(s).items == tuple(items)


def test_download_accepts_float_items():
    s = client(download_int=False)
    items = plan(1)
    out = s.call(s.engine.download(T.MISSION, s.now))
    out = s.feed(m.count_message(1, T.MISSION, GCS), VEHICLE)
    assert names(out) == ["MISSION_REQUEST"]
    s.feed(download_reply(items, 0, as_int=False), VEHICLE)
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
    s2.feed(download_reply(plan(1, T.FENCE), 0), VEHICLE)
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
            e.feed(download_reply(plan(2), 1), VEHICLE)
            e.advance(0.3)
            e.feed(download_reply(plan(2), 0), VEHICLE)
            e.feed(download_reply(plan(2), 1), VEHICLE)
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
            e.feed(download_reply(plan(2), 0), VEHICLE)
            e.feed(download_reply(plan(2), 1), VEHICLE)
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
    s2.feed(download_reply(plan(3), 2), VEHICLE)     # a stale mission item, seq 2
    assert s2.results == []
    for i in range(2):
        s2.feed(download_reply(plan(2, T.FENCE), i), VEHICLE)
    assert result(s2).ok


def test_download_duplicates_do_not_multiply_requests():
    s = client()
    items = plan(10)
    out = s.call(s.engine.download(T.MISSION, s.now))
    out = s.feed(m.count_message(10, T.MISSION, GCS), VEHICLE)
    for _ in range(10):
        seq = out[-1].seq
        out = s.feed(download_reply(items, seq), VEHICLE)
        s.feed(download_reply(items, seq), VEHICLE)
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
