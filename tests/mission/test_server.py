"""Scripted cases for the vehicle-side engine, one behaviour each (seed 000, second half)."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.behaviour import ServerBehaviour
from mavconform.reference_impl.mission.constants import CommandResult, MissionResult as R, MissionState
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.mission.transitions import SERVER_TRANSITIONS, SlotState
from mavconform.reference_impl.wire.dialect import mavlink as d

from .conftest import plan, waypoint
from .script import (
    GCS, OTHER_GCS, VEHICLE, Script, ack, clear_all, count, names, only, request_float,
    request_int, request_list,
)


def server(**behaviour) -> Script:
    return Script(MissionServer(*VEHICLE, ServerBehaviour(**behaviour), record_history=True))


def item_int(it, target=VEHICLE):
    return m.item_message(it, target, as_int=True)


def item_float(it, target=VEHICLE):
    return m.item_message(it, target, as_int=False)


def upload(s: Script, items, src=GCS, as_int=True) -> list:
    """A clean upload, answering each request in turn; returns the final replies."""
    t = items[0].mission_type if items else T.MISSION
    out = s.feed(count(len(items), t), src)
    for it in items:
        assert names(out)[-1] in ("MISSION_REQUEST_INT", "MISSION_REQUEST"), names(out)
        assert out[-1].seq == it.seq
        out = s.feed(item_int(it) if as_int else item_float(it), src)
    return out


def acks(msgs):
    return [(a.type, a.mission_type) for a in only(msgs, "MISSION_ACK")]


# --- upload --------------------------------------------------------------------------------
def test_upload_requests_each_item_in_order_and_accepts_with_opaque_id():
    s = server()
    items = plan(3)
    out = upload(s, items)
    final = only(out, "MISSION_ACK")[0]
    assert final.type == R.ACCEPTED and final.opaque_id != 0
    assert final.opaque_id == s.engine.store.opaque_id(T.MISSION)
    assert list(s.engine.store.items(T.MISSION)) == items
    assert s.engine.is_idle()
    # the accepted plan becomes the current one: MISSION_CURRENT announces it
    current = only(out, "MISSION_CURRENT")[0]
    assert (current.seq, current.total, current.mission_id) == (0, 3, final.opaque_id)


def test_upload_accepts_float_items_and_requests_float_when_configured():
    s = server(request_int=False)
    out = s.feed(count(2))
    assert names(out) == ["MISSION_REQUEST"]
    items = plan(2)
    upload_out = s.feed(item_float(items[0]))
    assert names(upload_out) == ["MISSION_REQUEST"]
    s.feed(item_float(items[1]))
    stored = s.engine.store.items(T.MISSION)
    # MISSION_ITEM carries lat/lon as float32: within float32 precision of the original
    for got, want in zip(stored, items):
        assert abs(got.x - want.x) <= 64 and abs(got.y - want.y) <= 16


def test_out_of_sequence_item_is_dropped_and_expected_item_rerequested():
    s = server()
    items = plan(3)
    s.feed(count(3))
    s.feed(item_int(items[0]))
    out = s.feed(item_int(items[2]))          # skips seq 1
    assert names(out) == ["MISSION_REQUEST_INT"] and out[0].seq == 1
    out = s.feed(item_int(items[0]))          # a stale duplicate of seq 0: dropped, no new request
    assert out == []
    s.feed(item_int(items[1]))
    s.feed(item_int(items[2]))
    assert list(s.engine.store.items(T.MISSION)) == items
    assert s.engine.stats.rerequests == 1


def test_duplicated_items_do_not_multiply_traffic():
    """Review finding: re-requesting on every stale duplicate started one more request/item
    stream per duplicate. Every item arriving twice must cost one request per item."""
    s = server()
    items = plan(20)
    out = s.feed(count(20))
    for _ in range(20):
        seq = out[-1].seq
        out = s.feed(item_int(items[seq]))
        s.feed(item_int(items[seq]))          # the network duplicates every item
    assert list(s.engine.store.items(T.MISSION)) == items
    requests = [msg for _, msg in s.sent_at if msg.get_type() == "MISSION_REQUEST_INT"]
    assert len(requests) == 20


def test_a_gcs_sending_the_wrong_item_forever_cannot_hold_the_transfer():
    """Out-of-sequence items neither move the deadline nor reset the retries: the upload
    ends after the usual retries, and another GCS is served afterwards."""
    s = server()
    s.feed(count(3))
    for _ in range(100):
        s.feed(item_int(waypoint(2)))        # always the wrong item, every 100 ms
        s.advance(0.1)
        if s.engine.is_idle():
            break
    assert s.engine.is_idle() and s.now < 2.0
    assert acks(s.feed(count(1), OTHER_GCS)) == []   # a plain request: served, not DENIED


def test_item_timeout_retries_five_times_at_250ms_then_cancels_and_keeps_old_plan():
    s = server()
    old = plan(2)
    upload(s, old)
    s.feed(count(4))
    out = s.advance(10.0)
    requests = only(out, "MISSION_REQUEST_INT")
    assert len(requests) == 5 and all(r.seq == 0 for r in requests)
    assert acks(out) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert s.engine.is_idle()
    assert list(s.engine.store.items(T.MISSION)) == old


def test_retry_interval_is_the_item_timeout():
    s = server(timings=Timings(item_timeout=0.4))
    s.feed(count(2))
    s.advance(10.0)
    times = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_REQUEST_INT"]
    assert times == pytest.approx([0.0, 0.4, 0.8, 1.2, 1.6, 2.0])
    give_up = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_ACK"]
    assert give_up == pytest.approx([2.4])


def test_count_zero_clears_the_plan():
    s = server()
    upload(s, plan(3))
    out = s.feed(count(0))
    assert acks(out) == [(R.ACCEPTED, T.MISSION)]
    assert s.engine.store.count(T.MISSION) == 0
    assert s.engine.store.opaque_id(T.MISSION) == 0


def test_no_space_when_count_exceeds_capacity_and_old_plan_stays():
    s = server(capacity={T.MISSION: 5, T.FENCE: 5, T.RALLY: 5})
    old = plan(2)
    upload(s, old)
    out = s.feed(count(6))
    assert acks(out) == [(R.NO_SPACE, T.MISSION)]
    assert list(s.engine.store.items(T.MISSION)) == old and s.engine.is_idle()


@pytest.mark.parametrize("raw_type", [3, 7, 230, 255])
def test_unknown_mission_type_is_unsupported(raw_type):
    s = server()
    for msg in (count(2, raw_type), request_list(raw_type)):
        assert acks(s.feed(msg)) == [(R.UNSUPPORTED, raw_type)]


def test_unsupported_plan_type_of_a_profile():
    s = server(supported_types=frozenset({T.MISSION, T.FENCE}))
    assert acks(s.feed(count(1, T.RALLY))) == [(R.UNSUPPORTED, T.RALLY)]


@pytest.mark.parametrize("change, code", [
    (dict(command=9999), R.UNSUPPORTED),
    (dict(command=5100), R.UNSUPPORTED),                       # rally command in a mission
    (dict(frame=77), R.UNSUPPORTED_FRAME),
    (dict(frame=1), R.UNSUPPORTED_FRAME),                       # local frame for a waypoint
    (dict(param1=-1.0), R.INVALID_PARAM1),                      # negative hold time
    (dict(param2=math.inf), R.INVALID_PARAM2),
    (dict(param3=-math.inf), R.INVALID_PARAM3),
    (dict(param4=math.inf), R.INVALID_PARAM4),
    (dict(x=910_000_000), R.INVALID_PARAM5_X),
    (dict(y=-1_810_000_000), R.INVALID_PARAM6_Y),
    (dict(z=math.nan), R.INVALID_PARAM7),
    (dict(autocontinue=2), R.INVALID),
])
def test_invalid_item_is_refused_with_its_code_and_old_plan_stays(change, code):
    s = server()
    old = plan(2)
    upload(s, old)
    bad = replace(waypoint(1), **change)
    s.feed(count(3))
    s.feed(item_int(waypoint(0)))
    out = s.feed(item_int(bad))
    assert acks(out) == [(code, T.MISSION)]
    assert s.engine.is_idle() and list(s.engine.store.items(T.MISSION)) == old


def test_float_item_whose_position_cannot_be_an_int32_is_refused():
    s = server()
    s.feed(count(1))
    msg = d.MAVLink_mission_item_message(1, 1, 0, 3, 16, 0, 1, 0, 0, 0, 0, math.nan, 8.5, 50, 0)
    assert acks(s.feed(msg)) == [(R.INVALID_PARAM5_X, T.MISSION)]


def test_nan_params_mean_default_and_are_accepted():
    s = server()
    it = waypoint(0, param4=math.nan)     # yaw: NaN = keep current heading
    out = upload(s, [it])
    assert acks(out) == [(R.ACCEPTED, T.MISSION)]
    assert s.engine.store.items(T.MISSION)[0] == it


def test_fence_rules():
    s = server()
    bad_vertex = waypoint(0, T.FENCE, command=5001, param1=2.0)
    s.feed(count(1, T.FENCE))
    assert acks(s.feed(item_int(bad_vertex))) == [(R.INVALID_PARAM1, T.FENCE)]
    s.feed(count(1, T.FENCE))
    assert acks(s.feed(item_int(waypoint(0, T.FENCE, param1=0.0)))) == [(R.INVALID_PARAM1, T.FENCE)]


# --- several GCSs ---------------------------------------------------------------------------
def test_other_gcs_is_denied_while_a_transfer_runs_and_same_gcs_may_restart():
    s = server()
    s.feed(count(3))
    for msg in (count(2), request_list(), clear_all(), item_int(waypoint(0)), request_int(0)):
        assert acks(s.feed(msg, OTHER_GCS)) == [(R.DENIED, T.MISSION)], msg.get_type()
    assert s.engine.partner(T.MISSION) == GCS
    out = s.feed(count(2))                    # the same GCS restarts its upload
    assert only(out, "MISSION_REQUEST_INT")[0].seq == 0
    items = plan(2)
    s.feed(item_int(items[0]))
    s.feed(item_int(items[1]))
    assert list(s.engine.store.items(T.MISSION)) == items


def test_other_gcs_may_use_another_plan_type_meanwhile():
    s = server()
    s.feed(count(3))
    out = upload(s, plan(2, T.FENCE), src=OTHER_GCS)
    assert acks(out) == [(R.ACCEPTED, T.FENCE)]
    assert s.engine.state(T.MISSION) is SlotState.RECEIVING


def test_denied_during_a_download_too():
    s = server()
    upload(s, plan(2))
    s.feed(request_list())
    assert acks(s.feed(request_int(0), OTHER_GCS)) == [(R.DENIED, T.MISSION)]
    assert acks(s.feed(count(1), OTHER_GCS)) == [(R.DENIED, T.MISSION)]


# --- cancellation ---------------------------------------------------------------------------
def test_gcs_cancel_mid_upload_returns_vehicle_to_idle_with_old_plan():
    s = server()
    old = plan(2)
    upload(s, old)
    s.feed(count(3))
    s.feed(item_int(waypoint(0)))
    assert s.feed(ack(R.OPERATION_CANCELLED)) == []
    assert s.engine.is_idle() and list(s.engine.store.items(T.MISSION)) == old
    assert not only(s.advance(5.0), "MISSION_REQUEST_INT")    # no more requests after the cancel


def test_vehicle_cancel_tells_the_gcs_and_keeps_old_plan():
    s = server()
    old = plan(1)
    upload(s, old)
    s.feed(count(3))
    out = s.call(s.engine.cancel(T.MISSION, s.now))
    assert acks(out) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert s.engine.is_idle() and list(s.engine.store.items(T.MISSION)) == old


def test_gcs_cancel_of_a_download_returns_vehicle_to_idle():
    s = server()
    upload(s, plan(2))
    s.feed(request_list())
    assert s.engine.state(T.MISSION) is SlotState.SENDING
    s.feed(ack(R.OPERATION_CANCELLED))
    assert s.engine.is_idle()


# --- download --------------------------------------------------------------------------------
def test_download_serves_count_with_opaque_id_and_items_in_both_encodings():
    s = server()
    items = plan(3)
    upload(s, items)
    out = s.feed(request_list())
    c = only(out, "MISSION_COUNT")[0]
    assert (c.count, c.opaque_id) == (3, s.engine.store.opaque_id(T.MISSION))
    got = only(s.feed(request_int(2)), "MISSION_ITEM_INT")[0]
    assert m.item_from_message(got) == items[2]
    got = only(s.feed(request_float(1)), "MISSION_ITEM")[0]
    assert abs(got.x - items[1].x / 1e7) < 1e-5
    assert s.feed(ack(R.ACCEPTED)) == [] and s.engine.is_idle()


def test_download_request_beyond_the_plan_is_invalid_sequence():
    s = server()
    upload(s, plan(2))
    s.feed(request_list())
    assert acks(s.feed(request_int(65))) == [(R.INVALID_SEQUENCE, T.MISSION)]
    assert s.engine.is_idle()


def test_download_of_empty_plan_is_count_zero_and_stays_idle():
    s = server()
    out = s.feed(request_list(T.RALLY))
    assert [(c.count, c.mission_type) for c in only(out, "MISSION_COUNT")] == [(0, T.RALLY)]
    assert s.engine.is_idle()


def test_silent_downloader_is_dropped_after_the_idle_timeout():
    s = server()
    upload(s, plan(2))
    s.feed(request_list())
    s.advance(ServerBehaviour().download_idle_timeout - 0.01)
    assert s.engine.state(T.MISSION) is SlotState.SENDING
    s.advance(0.02)
    assert s.engine.is_idle()


# --- types, clear ---------------------------------------------------------------------------
def test_plan_types_are_stored_independently():
    s = server()
    mission, fence, rally = plan(3), plan(2, T.FENCE), plan(1, T.RALLY)
    for p in (mission, fence, rally):
        upload(s, p)
    s.feed(count(0, T.FENCE))
    store = s.engine.store
    assert list(store.items(T.MISSION)) == mission and list(store.items(T.RALLY)) == rally
    assert store.count(T.FENCE) == 0


def test_clear_one_type_and_clear_all():
    s = server()
    for t in (T.MISSION, T.FENCE, T.RALLY):
        upload(s, plan(2, t))
    assert acks(s.feed(clear_all(T.FENCE))) == [(R.ACCEPTED, T.FENCE)]
    assert s.engine.store.count(T.FENCE) == 0 and s.engine.store.count(T.MISSION) == 2
    assert acks(s.feed(clear_all(T.ALL))) == [(R.ACCEPTED, T.ALL)]
    assert all(s.engine.store.count(t) == 0 for t in (T.MISSION, T.FENCE, T.RALLY))


def test_clear_all_is_denied_while_another_gcs_uploads_any_type():
    s = server()
    s.feed(count(3, T.RALLY), OTHER_GCS)
    assert acks(s.feed(clear_all(T.ALL))) == [(R.DENIED, T.ALL)]


# --- set current, progress ------------------------------------------------------------------
def test_set_current_broadcasts_mission_current_or_statustext_on_failure():
    s = server()
    upload(s, plan(4))
    out = s.feed(d.MAVLink_mission_set_current_message(1, 1, 2))
    assert [c.seq for c in only(out, "MISSION_CURRENT")] == [2]
    out = s.feed(d.MAVLink_mission_set_current_message(1, 1, 9))
    assert names(out) == ["STATUSTEXT"] and out[0].severity <= 4
    assert s.engine.progress.seq == 2


def test_set_current_command_acks_and_broadcasts():
    s = server()
    upload(s, plan(4))
    out = s.call(s.engine.command_set_current(3.0, GCS, s.now))
    assert [a.result for a in only(out, "COMMAND_ACK")] == [CommandResult.ACCEPTED]
    assert [c.seq for c in only(out, "MISSION_CURRENT")] == [3]
    out = s.call(s.engine.command_set_current(7.0, GCS, s.now))
    assert [a.result for a in only(out, "COMMAND_ACK")] == [CommandResult.FAILED]
    assert names(out)[-1] == "STATUSTEXT"


def test_mission_current_is_streamed_at_1hz_with_total_state_and_ids():
    s = server()
    upload(s, plan(3))
    upload(s, plan(2, T.FENCE))
    out = only(s.advance(3.05), "MISSION_CURRENT")
    assert len(out) == 3
    last = out[-1]
    store = s.engine.store
    assert (last.total, last.mission_state) == (3, MissionState.NOT_STARTED)
    assert (last.mission_id, last.fence_id, last.rally_points_id) == (
        store.opaque_id(T.MISSION), store.opaque_id(T.FENCE), 0)


def test_opaque_id_follows_plan_content():
    s = server()
    upload(s, plan(2))
    first = s.engine.store.opaque_id(T.MISSION)
    upload(s, plan(3))
    assert s.engine.store.opaque_id(T.MISSION) not in (0, first)
    upload(s, plan(2))
    assert s.engine.store.opaque_id(T.MISSION) == first


# --- idle-state replies ---------------------------------------------------------------------
def test_lost_final_ack_is_recovered_by_reacking_the_same_last_item():
    s = server()
    items = plan(2)
    upload(s, items)
    accepted = s.engine.store.opaque_id(T.MISSION)
    out = s.feed(item_int(items[-1]))
    assert [(a.type, a.opaque_id) for a in only(out, "MISSION_ACK")] == [(R.ACCEPTED, accepted)]
    # but not for another GCS, nor for an item that is not the accepted last one
    assert acks(s.feed(item_int(items[-1]), OTHER_GCS)) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert acks(s.feed(item_int(replace(items[-1], z=99.0)))) == [(R.OPERATION_CANCELLED, T.MISSION)]


def test_a_new_upload_ends_the_lost_ack_recovery_of_the_previous_one():
    """Review finding: after a new MISSION_COUNT, a late item equal to one of the previous
    plan's must not draw ACCEPTED (the GCS would report success for a plan not stored)."""
    s = server()
    first = plan(3)
    upload(s, first)
    s.feed(count(3))                             # the next upload starts, then is abandoned
    s.advance(5)
    assert acks(s.feed(item_int(first[2]))) == [(R.OPERATION_CANCELLED, T.MISSION)]


def test_stray_items_and_requests_in_idle_get_an_error_and_acks_get_silence():
    s = server()
    assert acks(s.feed(item_int(waypoint(0)))) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert acks(s.feed(request_int(0))) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert s.feed(ack(R.ACCEPTED)) == [] and s.feed(ack(R.ERROR)) == []
    quiet = server(idle_reply=None)
    assert quiet.feed(item_int(waypoint(0))) == []


def test_messages_for_another_system_or_component_are_ignored():
    s = server()
    assert s.feed(count(2, target=(7, 1))) == []
    assert s.feed(count(2, target=(1, 50))) == []
    assert s.engine.is_idle()
    assert names(s.feed(count(1, target=(1, 0)))) == ["MISSION_REQUEST_INT"]


def test_mavlink1_frames_work_and_mean_mission_type_mission():
    s = server()
    out = s.feed(count(1), version=1)
    assert names(out) == ["MISSION_REQUEST_INT"]
    s.feed(item_int(waypoint(0)), version=1)
    assert s.engine.store.count(T.MISSION) == 1


def test_every_transition_of_the_table_is_reachable():
    """A tour through the scripted behaviours covers the server's whole table."""
    s = server(capacity={T.MISSION: 4, T.FENCE: 4, T.RALLY: 4})
    e = s.engine
    upload(s, plan(2))                                  # COUNT, ITEM_NEXT, ITEM_LAST
    s.feed(count(3)); s.feed(item_int(waypoint(2)))     # ITEM_OUT_OF_SEQUENCE
    s.advance(0.3)                                       # TIMEOUT_RETRY
    s.feed(count(2))                                    # SUPERSEDED (restart)
    s.feed(item_int(replace(waypoint(0), command=1)))   # ITEM_REJECTED
    s.feed(count(2)); s.advance(5)                      # TIMEOUT_GIVE_UP (receiving)
    s.feed(count(2)); s.feed(ack(R.OPERATION_CANCELLED))  # ACK while receiving
    s.feed(count(2)); s.call(e.cancel(T.MISSION, s.now))  # CANCEL while receiving
    s.feed(count(9))                                    # COUNT_REJECTED
    s.feed(count(0))                                    # COUNT_ZERO
    s.feed(request_list())                              # REQUEST_LIST_EMPTY
    upload(s, plan(2))
    s.feed(request_list()); s.feed(request_int(0))      # REQUEST_LIST, REQUEST_VALID
    s.feed(ack(R.ACCEPTED))                             # ACK while sending
    s.feed(request_list()); s.feed(request_int(9))      # REQUEST_INVALID
    s.feed(request_list()); s.advance(20)               # TIMEOUT_GIVE_UP (sending)
    s.feed(request_list()); s.call(e.cancel(T.MISSION, s.now))  # CANCEL while sending
    s.feed(request_list()); s.feed(count(1))            # SUPERSEDED while sending
    s.feed(clear_all())                                 # CLEAR (also SUPERSEDED)
    s.feed(request_int(0))                              # STRAY
    seen = {(before, event) for _t, before, event, _after in e.stats.history}
    assert seen == set(SERVER_TRANSITIONS), set(SERVER_TRANSITIONS) - seen
