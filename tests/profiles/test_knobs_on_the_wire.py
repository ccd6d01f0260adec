"""Each profile knob, seen on the wire: the sans-IO server fed real frames (virtual time)."""

from __future__ import annotations

from dataclasses import replace

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.commands import by_name
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.progress import REACHED_SLOT_DELAY
from mavconform.reference_impl.mission.server import MissionServer
from mavconform.reference_impl.mission.transitions import PROFILE_TRANSITIONS
from mavconform.reference_impl.profiles import load_profile
from mavconform.reference_impl.wire.dialect import mavlink as d

from ..mission.conftest import plan, waypoint
from ..mission.script import (
    GCS, OTHER_GCS, VEHICLE, Script, ack, clear_all, count, names, only, request_float,
    request_int, request_list,
)


def server(profile: str, **knobs) -> Script:
    behaviour = load_profile(profile).behaviour
    if knobs:
        behaviour = replace(behaviour, **knobs)
    return Script(MissionServer(*VEHICLE, behaviour, record_history=True))


def cmd(name: str) -> int:
    """A MAV_CMD value from the upstream XML facts (our dialect carries only a few)."""
    return by_name(name).value


def item(it, as_int=True):
    return m.item_message(it, VEHICLE, as_int=as_int)


def acks(msgs):
    return [(a.type, a.mission_type) for a in only(msgs, "MISSION_ACK")]


def texts(msgs):
    return [bytes(t.text).rstrip(b"\0").decode() if isinstance(t.text, (bytes, bytearray)) else t.text.rstrip("\0")
            for t in only(msgs, "STATUSTEXT")]


def upload(s: Script, items, src=GCS):
    out = s.feed(count(len(items), items[0].mission_type), src)
    for it in items:
        out = s.feed(item(it), src)
    return out


# --- ArduPilot-like ------------------------------------------------------------------------
def test_non_atomic_upload_leaves_a_mix_of_old_and_new():        # A2
    s = server("ardupilot")
    old, new = plan(4), plan(4, z=99.0)
    upload(s, old)
    s.feed(count(3))
    assert s.engine.store.count(T.MISSION) == 3                   # truncated at once
    s.feed(item(new[0])); s.feed(item(new[1]))
    s.feed(ack(R.OPERATION_CANCELLED))                           # ignored (A4)
    s.advance(10)                                                # the vehicle gives up by itself
    stored = s.engine.store.items(T.MISSION)
    assert list(stored) == [new[0], new[1], old[2]]


def test_a_sequence_nack_does_not_end_the_upload_but_a_refused_item_does():   # A3 (master)
    """ArduPilot master, MissionItemProtocol::handle_mission_item: INVALID_SEQUENCE (and
    DENIED) are sent and the upload goes on; an item replace/append refuses ends it."""
    s = server("ardupilot")
    items = plan(3)
    s.feed(count(3)); s.feed(item(items[0]))
    out = s.feed(item(items[2]))                                 # out of sequence
    assert acks(out) == [(R.INVALID_SEQUENCE, T.MISSION)] and not only(out, "MISSION_REQUEST")
    assert [r.seq for r in only(s.advance(1.0), "MISSION_REQUEST")] == [1]   # still asking for 1
    out = s.feed(item(items[1])) + s.feed(item(items[2]))
    assert acks(out) == [(R.ACCEPTED, T.MISSION)]
    s.feed(count(3)); s.feed(item(items[0]))
    out = s.feed(item(replace(items[1], x=1_000_000_000)))       # latitude 100 degrees
    assert acks(out) == [(R.INVALID_PARAM5_X, T.MISSION)]
    assert not only(s.advance(2.0), "MISSION_REQUEST")           # that ended it
    assert only(s.feed(item(items[1]), OTHER_GCS), "MISSION_ACK")[0].type != R.ACCEPTED


def test_a_refused_item_mid_upload_leaves_the_items_written_before_it():   # A2 with A3 (master)
    """What MIS.UP.17 sees on ArduPilot: MISSION_COUNT cut the plan, items 0-1 were written,
    item 2 is refused; nothing is restored."""
    s = server("ardupilot")
    old, new = plan(4), plan(3, z=99.0)
    upload(s, old)
    s.feed(count(3)); s.feed(item(new[0])); s.feed(item(new[1]))
    out = s.feed(item(replace(new[2], command=31999)))          # no such command
    assert acks(out) == [(R.UNSUPPORTED, T.MISSION)]
    assert not only(s.advance(2.0), "MISSION_REQUEST") and s.engine.is_idle()
    assert list(s.engine.store.items(T.MISSION)) == [new[0], new[1], old[2]]


def test_cancel_is_ignored_then_the_vehicle_times_out_with_ack_and_statustext():   # A4, A5
    s = server("ardupilot")
    s.feed(count(3))
    s.feed(ack(R.OPERATION_CANCELLED))
    out = s.advance(9)
    times = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_REQUEST"]
    assert [round(b - a, 3) for a, b in zip(times, times[1:])] == [1.0] * 7     # every 1 s, uncapped
    assert acks(out) == [(R.OPERATION_CANCELLED, T.MISSION)]
    assert "Mission upload timeout" in texts(out)
    given_up = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_ACK"][0]
    assert given_up == 8.0 and s.engine.is_idle()


def test_home_is_item_0_of_a_download_and_current_total_is_count_minus_1():   # A1
    s = server("ardupilot")
    s.engine.home = waypoint(0, frame=0, x=1, y=2, z=3.0)
    items = plan(3)
    upload(s, items)
    assert only(s.feed(request_list()), "MISSION_COUNT")[0].count == 3
    got = [m.item_from_message(only(s.feed(request_int(i)), "MISSION_ITEM_INT")[0]) for i in range(3)]
    assert (got[0].x, got[0].y, got[0].z) == (1, 2, 3.0) and got[1:] == items[1:]
    current = s.engine.progress.current_message()
    assert (current.total, current.seq, current.mission_id) == (2, 1, 0)   # starts after home; no ids (A19)


def test_float_requests_and_one_warning_per_transfer():           # A6, A7
    s = server("ardupilot")
    out = s.feed(count(2))
    assert names(out) == ["MISSION_REQUEST"]
    out = s.feed(item(waypoint(0), as_int=False))
    assert texts(out) == ["got MISSION_ITEM; GCS should send MISSION_ITEM_INT"]
    out = s.feed(item(waypoint(1), as_int=False))
    assert texts(out) == [] and acks(out) == [(R.ACCEPTED, T.MISSION)]
    s.feed(request_list())
    first, second = s.feed(request_float(0)), s.feed(request_float(1))
    assert texts(first) == ["got MISSION_REQUEST; use MISSION_REQUEST_INT!"] and texts(second) == []


def test_reads_are_denied_while_an_upload_runs_but_its_gcs_may_restart():   # A8
    s = server("ardupilot")
    s.feed(count(3))
    for msg, src in ((request_list(), GCS), (request_int(0), GCS), (count(2), OTHER_GCS),
                     (request_list(), OTHER_GCS)):
        assert acks(s.feed(msg, src)) == [(R.DENIED, T.MISSION)]
    assert [r.seq for r in only(s.feed(count(2)), "MISSION_REQUEST")] == [0]


def test_partial_write_rewrites_a_range_and_refuses_one_out_of_range():   # A9
    s = server("ardupilot")
    items = plan(4)
    upload(s, items)
    out = s.feed(d.MAVLink_mission_write_partial_list_message(1, 1, 9, 12, 0))
    assert acks(out) == [(R.ERROR, T.MISSION)] and texts(out) == ["Flight plan update rejected"]
    out = s.feed(d.MAVLink_mission_write_partial_list_message(1, 1, 1, 2, 0))
    assert [r.seq for r in only(out, "MISSION_REQUEST")] == [1]
    new = [replace(items[1], z=7.0), replace(items[2], z=8.0)]
    s.feed(item(new[0]))
    assert acks(s.feed(item(new[1]))) == [(R.ACCEPTED, T.MISSION)]
    assert list(s.engine.store.items(T.MISSION)) == [items[0], *new, items[3]]
    assert s.feed(d.MAVLink_mission_write_partial_list_message(1, 1, 0, 0, 0)) and \
        server("spec").feed(d.MAVLink_mission_write_partial_list_message(1, 1, 0, 0, 0)) == []


def test_clear_all_types_is_unsupported_and_a_flown_mission_is_not_cleared():   # A10, A12
    s = server("ardupilot")
    upload(s, plan(2))
    assert acks(s.feed(clear_all(T.ALL))) == [(R.UNSUPPORTED, T.ALL)]
    s.engine.progress.running = True
    assert acks(s.feed(clear_all())) == [(R.ERROR, T.MISSION)]
    assert acks(s.feed(count(0))) == [(R.ACCEPTED, T.MISSION)]     # a new (empty) upload is allowed


def _v1_with_extensions(msg):
    """A MAVLink 1 frame that still carries the extension fields (pymavlink's own v1 pack
    does this), so a MAVLink 1 link can name a fence transfer at all."""
    from mavconform.reference_impl.wire import FrameDecoder
    (frame,) = FrameDecoder().feed(bytes(msg.pack(d.MAVLink(None, *GCS), force_mavlink1=True)))
    assert frame.version == 1 and frame.msg.mission_type == msg.mission_type
    return frame


def test_fence_and_rally_need_mavlink2():                          # A11
    s = server("ardupilot")
    out = s.call(s.engine.handle(_v1_with_extensions(count(2, T.FENCE)), s.now))
    assert acks(out) == [(R.UNSUPPORTED, T.FENCE)] and texts(out) == ["Need mavlink2 for item transfer"]
    assert names(s.feed(count(2, T.FENCE))) == ["MISSION_REQUEST"]
    assert names(s.feed(count(2), version=1)) == ["MISSION_REQUEST"]   # missions are fine over v1
    spec = server("spec")
    assert names(spec.call(spec.engine.handle(_v1_with_extensions(count(2, T.FENCE)), 0.0))) == ["MISSION_REQUEST_INT"]


def test_the_older_dialect_is_byte_identical_to_frames_without_plan_ids():   # A19
    from mavconform.reference_impl.wire import FrameEncoder
    s = server("ardupilot")
    final = only(upload(s, plan(2)), "MISSION_ACK")[0]
    assert final.opaque_id == 0
    wire = FrameEncoder(1, 1).encode(final)
    legacy = d.MAVLink_mission_ack_message(GCS[0], GCS[1], R.ACCEPTED, 0)   # no opaque_id given
    assert wire == FrameEncoder(1, 1).encode(legacy)                      # trailing zeros cut
    with_id = FrameEncoder(1, 1).encode(d.MAVLink_mission_ack_message(GCS[0], GCS[1], R.ACCEPTED, 0, 7))
    assert len(with_id) > len(wire)


def test_downloads_hold_no_state():                               # A14
    s = server("ardupilot")
    items = plan(2)
    upload(s, items)
    assert m.item_from_message(only(s.feed(request_int(1)), "MISSION_ITEM_INT")[0]) == items[1]
    assert acks(s.feed(request_int(5))) == [(R.INVALID_SEQUENCE, T.MISSION)]
    s.feed(request_list())
    assert s.engine.is_idle() and s.feed(ack(R.ACCEPTED)) == []


def test_commands_of_other_vehicle_types_are_accepted_and_compact_storage_rounds():   # A17, A13
    """AP_Mission stores a plane's or a VTOL's commands on any vehicle (A17); a command it has
    no storage form for is refused (AP_Mission::mavlink_int_to_mission_cmd's default)."""
    s = server("ardupilot")
    odd = [waypoint(0, command=cmd("NAV_VTOL_TAKEOFF")), waypoint(1, param1=2.6, param4=45.0, z=12.345)]
    assert acks(upload(s, odd)) == [(R.ACCEPTED, T.MISSION)]
    kept = s.engine.store.items(T.MISSION)[1]
    assert (kept.param1, kept.param4) == (2.0, 0.0) and abs(kept.z - 12.34) < 1e-5
    for name in ("ardupilot", "spec"):
        other = server(name)
        other.feed(count(1))
        assert acks(other.feed(item(waypoint(0, command=31999)))) == [(R.UNSUPPORTED, T.MISSION)], name


def test_px4_stores_only_the_commands_its_parser_knows():          # P19
    """ROI, camera and gimbal items go in (issue 13); DO_SET_SERVO is not in PX4's list."""
    accepted = [waypoint(0, command=cmd("DO_SET_ROI_LOCATION")),
                waypoint(1, frame=2, command=cmd("IMAGE_START_CAPTURE")),
                waypoint(2, frame=2, command=cmd("DO_GIMBAL_MANAGER_PITCHYAW")),
                waypoint(3, frame=2, command=cmd("DO_SET_CAM_TRIGG_DIST"))]
    assert acks(upload(server("px4"), accepted)) == [(R.ACCEPTED, T.MISSION)]
    s = server("px4")
    s.feed(count(1))
    assert acks(s.feed(item(waypoint(0, frame=2, command=d.MAV_CMD_DO_SET_SERVO)))) == [(R.UNSUPPORTED, T.MISSION)]


def test_px4_takes_any_latitude_but_refuses_an_unknown_command_or_a_local_frame():   # P20, P19, P14
    """parse_mavlink_mission_item copies lat/lon unchecked; the spec vehicle refuses latitude 100."""
    far = waypoint(0, x=1_000_000_000)
    assert acks(upload(server("px4"), [far])) == [(R.ACCEPTED, T.MISSION)]
    assert acks(upload(server("spec"), [far])) == [(R.INVALID_PARAM5_X, T.MISSION)]
    for bad, code in ((waypoint(0, command=31999), R.UNSUPPORTED),
                      (waypoint(0, frame=d.MAV_FRAME_LOCAL_NED), R.UNSUPPORTED_FRAME)):
        s = server("px4")
        s.feed(count(1))
        assert acks(s.feed(item(bad))) == [(code, T.MISSION)], bad


# --- PX4-like ------------------------------------------------------------------------------
def test_px4_resends_every_250ms_uncapped_until_5s_without_a_message():   # P3
    s = server("px4")
    s.feed(count(2))
    out = s.advance(6)
    times = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_REQUEST_INT"]
    assert len(times) == 20 and times[-1] == 4.75                 # 1 + 19 resends, > the spec's 5
    assert acks(out) == [] and s.engine.is_idle()                  # idle without a word
    s2 = server("px4")
    s2.feed(count(2)); s2.advance(3); s2.feed(item(waypoint(0)))   # a message restarts the 5 s
    s2.advance(4.9)
    assert not s2.engine.is_idle()


def test_px4_drops_an_out_of_sequence_item_silently():            # P5
    s = server("px4")
    s.feed(count(3))
    assert s.feed(item(waypoint(2))) == []
    assert [r.seq for r in only(s.advance(0.25), "MISSION_REQUEST_INT")] == [0]


def test_px4_downloads_must_be_in_order():                         # P6
    s = server("px4")
    upload(s, plan(3))
    s.feed(request_list())
    assert names(s.feed(request_int(0)) + s.feed(request_int(0)) + s.feed(request_int(1))) == ["MISSION_ITEM_INT"] * 3
    assert acks(s.feed(request_int(0))) == [(R.ERROR, T.MISSION)] and s.engine.is_idle()


def test_px4_answers_an_item_of_another_type_with_error_and_goes_on():   # P7
    s = server("px4")
    s.feed(count(2))
    out = s.feed(item(waypoint(0, T.FENCE)))
    assert acks(out) == [(R.ERROR, T.MISSION)] and not s.engine.is_idle()


def test_px4_follows_the_gcs_float_mode_and_flips_on_unsupported():   # P8
    s = server("px4")
    s.feed(count(3))
    assert names(s.feed(item(waypoint(0), as_int=False))) == ["MISSION_REQUEST"]
    assert names(s.feed(ack(R.UNSUPPORTED))) == ["MISSION_REQUEST_INT"]
    assert names(s.feed(item(waypoint(1)))) == ["MISSION_REQUEST_INT"]


def test_px4_refuses_set_current_during_a_transfer():             # P12
    s = server("px4")
    upload(s, plan(3))
    s.feed(count(2))
    out = s.feed(d.MAVLink_mission_set_current_message(1, 1, 2))
    assert texts(out) and not only(out, "MISSION_CURRENT")
    s.feed(ack(R.OPERATION_CANCELLED))                            # P2': the cancel is honoured
    assert only(s.feed(d.MAVLink_mission_set_current_message(1, 1, 2)), "MISSION_CURRENT")[0].seq == 2


def test_px4_repeats_item_reached_ten_times_at_1hz():             # P13
    s = server("px4")
    upload(s, plan(3))
    s.call(s.engine.progress.reached(0, s.now))
    s.advance(12)
    reached = [t for t, msg in s.sent_at if msg.get_type() == "MISSION_ITEM_REACHED"]
    assert reached == [REACHED_SLOT_DELAY + i for i in range(10)]   # from its one slot's send (P21) on


def test_every_profile_transition_is_reachable():
    # nack_ends_upload=False: older ArduPilot (seed 000), the knob's documented alternative
    s = server("ardupilot", follow_gcs_int_mode=True, nack_ends_upload=False)
    upload(s, plan(3))
    s.feed(d.MAVLink_mission_write_partial_list_message(1, 1, 0, 0, 0))   # PARTIAL_WRITE
    s.feed(item(replace(waypoint(0), x=1_000_000_000)))                  # ITEM_REFUSED_GOES_ON
    s.feed(ack(R.UNSUPPORTED))                                            # FORM_FLIPPED
    s.advance(9)
    s.feed(request_list()); s.feed(request_int(0))                        # *_UNTRACKED
    seen = {(before, event) for _t, before, event, _after in s.engine.stats.history}
    assert set(PROFILE_TRANSITIONS) <= seen, set(PROFILE_TRANSITIONS) - seen
