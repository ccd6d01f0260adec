"""The inav profile answers as the real INAV 9.1.0 SITL (e7d5cceb) did, message by message
(virtual time). Each check is one observation of /work/sitl/inav-findings.md, driven over the
wire with the float mission messages; each knob it relies on is taken away in turn and the
check must then fail, so no answer here holds by accident."""

from __future__ import annotations

import math

import pytest

from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.mission.constants import Cmd, CommandResult
from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionType as T
from mavconform.reference_impl.mission.items import to_float32
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile
from mavconform.reference_impl.profiles.loader import spec_default
from mavconform.reference_impl.profiles.knobs import KNOBS

from .inav_probe import (
    LAT, LON, Probe, ack, one, clear_all, command_int, command_long, count, inav_config, only, request, request_list,
    set_current, summary, waypoints, wp,
)

SEEN_ON = "INAV 9.1.0 SITL (e7d5cceb)"
REQ, ACK, COUNT = "MISSION_REQUEST", "MISSION_ACK", "MISSION_COUNT"


def probe(without=(), **overrides) -> Probe:
    return Probe(inav_config(without, **overrides))


def with_plan(n: int, without=(), **overrides) -> Probe:
    p = probe(without, **overrides)
    assert summary(p.upload(waypoints(n)))[-1] == (ACK, R.ACCEPTED, 0)
    return p


# --- 1. messages without a handler -------------------------------------------------------------
def check_int_messages_get_no_reply(without=()):
    p = with_plan(2, without)
    assert p.send(request(0, as_int=True)) == []                       # MISSION_REQUEST_INT
    assert summary(p.send(count(1))) == [(REQ, 0, 0)]
    assert p.send(wp(0, 9, as_int=True)) == []                         # MISSION_ITEM_INT: nothing,
    assert summary(p.send(wp(0, 9))) == [(ACK, R.ACCEPTED, 0)]         # the upload still open


def check_gcs_ack_set_current_and_command_long_are_ignored(without=()):
    p = with_plan(2, without)
    assert summary(p.send(count(2))) == [(REQ, 0, 0)]
    assert summary(p.send(wp(0))) == [(REQ, 1, 0)]
    assert p.send(ack(R.OPERATION_CANCELLED)) == []                    # no cancel: the upload goes on
    assert summary(p.send(wp(1))) == [(ACK, R.ACCEPTED, 0)]
    assert p.send(set_current(1)) == [] and p.vehicle.server.progress.seq == 0
    assert p.send(set_current(7)) == []                                # no STATUSTEXT either
    assert p.send(command_long(Cmd.DO_SET_MISSION_CURRENT, 1)) == []
    assert p.send(command_long(Cmd.REQUEST_MESSAGE, 242)) == []


def check_command_int_set_current_is_unsupported(without=()):
    p = with_plan(2, without)
    assert summary(p.send(command_int(Cmd.DO_SET_MISSION_CURRENT, 1))) == [
        ("COMMAND_ACK", Cmd.DO_SET_MISSION_CURRENT, CommandResult.UNSUPPORTED)]


def check_requests_are_float(without=()):
    p = probe(without)
    assert summary(p.send(count(3))) == [(REQ, 0, 0)]


# --- 2. mission_type ignored --------------------------------------------------------------------
def check_fence_and_rally_reads_and_clears_act_on_the_mission(without=()):
    p = with_plan(3, without)
    for t in (T.FENCE, T.RALLY):
        assert summary(p.send(request_list(t))) == [(COUNT, 3, 0)]
    item = one(p.send(request(0, T.FENCE)), "MISSION_ITEM")
    assert (item.command, item.mission_type) == (Cmd.NAV_WAYPOINT, 0)
    assert summary(p.send(clear_all(T.FENCE))) == [(ACK, R.ACCEPTED, 0)] and p.stored() == 0
    p.upload(waypoints(2))
    assert summary(p.send(clear_all(T.ALL))) == [(ACK, R.ACCEPTED, 0)] and p.stored() == 0


def check_fence_and_rally_uploads_replace_the_mission(without=()):
    p = with_plan(3, without)
    fence = wp(0, frame=0, command=5001, mission_type=T.FENCE)         # NAV_FENCE_POLYGON_VERTEX_INCLUSION
    assert summary(p.send(count(2, T.FENCE))) == [(REQ, 0, 0)]
    assert summary(p.send(fence)) == [(ACK, R.UNSUPPORTED, 0)]
    assert p.stored() == 3
    assert summary(p.upload([wp(0, 5, mission_type=T.RALLY)], T.RALLY)) == [(REQ, 0, 0), (ACK, R.ACCEPTED, 0)]
    assert p.stored() == 1


# --- 3.-5. upload: count 0, item 0 clears, no timers --------------------------------------------
def check_count0_requests_item0_and_keeps_the_plan_until_it_comes(without=()):
    p = with_plan(2, without)
    assert summary(p.send(count(0))) == [(REQ, 0, 0)]
    assert p.stored() == 2
    p = with_plan(2, without)
    p.send(count(0))
    assert summary(p.send(wp(0, 7))) == [(ACK, R.ACCEPTED, 0)]
    assert p.stored() == 1


def check_item0_clears_the_plan_and_an_abandoned_upload_stays_partial(without=()):
    p = with_plan(3, without)
    store = p.vehicle.store
    assert summary(p.send(count(5))) == [(REQ, 0, 0)] and store.count(T.MISSION) == 3   # untouched at COUNT
    new = waypoints(2, start=50)
    assert summary(p.send(new[0])) == [(REQ, 1, 0)] and store.count(T.MISSION) == 1     # item 0 cleared it
    assert summary(p.send(new[1])) == [(REQ, 2, 0)]
    assert p.stored() == 2                                                               # abandoned: 2 of 5
    first = one(p.send(request(0)), "MISSION_ITEM")
    assert first.x == to_float32(LAT + 50e-4)


def check_a_stalled_upload_is_never_rerequested_nor_ended(without=()):
    p = with_plan(1, without)
    assert summary(p.send(count(2))) == [(REQ, 0, 0)]
    assert p.run(30.0) == []
    assert summary(p.send(wp(0))) == [(REQ, 1, 0)]
    assert p.run(30.0) == []
    assert summary(p.send(wp(1))) == [(ACK, R.ACCEPTED, 0)]


def check_a_second_gcs_takes_an_upload_over(without=()):
    """No owner (mavlink.c:1036-1051): another GCS's MISSION_COUNT restarts the upload for it,
    no DENIED, and the first GCS's next item is out of sequence; replies go to the sender."""
    from mavconform.reference_impl.wire.frame import Frame
    server = probe(without).vehicle.server

    def from_gcs(system: int, message) -> list[tuple]:
        sends = server.handle(Frame(message, b"\xfd", system, 190), 0.0)   # a MAVLink 2 frame
        return [(x.msg.get_type(), getattr(x.msg, "seq", getattr(x.msg, "type", None)), x.to) for x in sends]
    items = waypoints(3)
    assert from_gcs(255, count(3)) == [(REQ, 0, (255, 190))]
    assert from_gcs(42, count(3)) == [(REQ, 0, (42, 190))]
    assert from_gcs(42, items[0]) == [(REQ, 1, (42, 190))]
    assert from_gcs(255, items[0]) == [(ACK, R.INVALID_SEQUENCE, (255, 190))]


# --- 6. sequence errors -------------------------------------------------------------------------
def check_out_of_sequence_and_duplicate_items_get_invalid_sequence(without=()):
    p = probe(without)
    items = waypoints(3)
    assert summary(p.send(count(3))) == [(REQ, 0, 0)]
    assert summary(p.send(items[1])) == [(ACK, R.INVALID_SEQUENCE, 0)]     # a gap: no re-request
    assert summary(p.send(items[0])) == [(REQ, 1, 0)]
    assert summary(p.send(items[0])) == [(ACK, R.INVALID_SEQUENCE, 0)]     # a duplicate
    assert summary(p.send(items[2])) == [(ACK, R.INVALID_SEQUENCE, 0)]
    assert summary(p.send(items[1])) == [(REQ, 2, 0)]
    assert summary(p.send(items[2])) == [(ACK, R.ACCEPTED, 0)]


def check_a_stray_item_continues_the_last_upload(without=()):
    """Probed on the SITL: after 3 items, a stray item 3 was appended (ACCEPTED, then 4 listed);
    a stray item 0 then drew INVALID_SEQUENCE and changed nothing."""
    p = with_plan(3, without)
    assert summary(p.send(waypoints(4)[3])) == [(ACK, R.ACCEPTED, 0)]
    assert summary(p.send(request_list(0))) == [(COUNT, 4, 0)]
    assert summary(p.send(waypoints(1)[0])) == [(ACK, R.INVALID_SEQUENCE, 0)]
    assert summary(p.send(request_list(0))) == [(COUNT, 4, 0)]
    p = probe(without)                               # read in source (mavlink.c:1035-1036, 1121-1141):
    assert summary(p.send(waypoints(1)[0])) == [(ACK, R.ACCEPTED, 0)]   # the counters start at 0: a plan
    assert summary(p.send(count(2))) == [(REQ, 0, 0)]
    assert summary(p.send(waypoints(2)[0])) == [(REQ, 1, 0)]
    assert summary(p.send(clear_all(0))) == [(ACK, R.ACCEPTED, 0)]
    assert summary(p.send(waypoints(2)[1])) == [(ACK, R.INVALID, 0)]   # number 2 of none stored: dropped


def check_items_after_a_finished_upload_get_invalid_sequence(without=()):
    p = with_plan(2, without)
    assert summary(p.send(waypoints(2)[1])) == [(ACK, R.INVALID_SEQUENCE, 0)]   # a late copy of the last
    assert summary(p.send(waypoints(1)[0])) == [(ACK, R.INVALID_SEQUENCE, 0)]   # item 0, no MISSION_COUNT


# --- 7. commands, frames, autocontinue ------------------------------------------------------------
ITEM_ANSWERS = [   # (command, frame, autocontinue) -> ACK, as the SITL answered COUNT 1 + the item
    *[((Cmd.NAV_WAYPOINT, 3, 1), R.ACCEPTED), ((Cmd.NAV_RETURN_TO_LAUNCH, 3, 1), R.ACCEPTED),
      ((Cmd.NAV_RETURN_TO_LAUNCH, 2, 1), R.ACCEPTED), ((Cmd.NAV_RETURN_TO_LAUNCH, 0, 1), R.UNSUPPORTED_FRAME),
      ((Cmd.NAV_LAND, 0, 1), R.UNSUPPORTED), ((Cmd.NAV_WAYPOINT, 3, 0), R.UNSUPPORTED)],
    *[((c, 3, 1), R.UNSUPPORTED) for c in (17, 18, 19, 21, 22, 31, 82, 93, 112, 177, 178, 183, 195, 201, 206,
                                           5001, 5100)],
    *[((Cmd.NAV_WAYPOINT, f, 1), R.UNSUPPORTED_FRAME) for f in (0, 1, 2, 5, 6, 10, 11)],
]


def check_commands_frames_and_autocontinue(without=()):
    p = probe(without)
    for (command, frame, autocontinue), code in ITEM_ANSWERS:
        p.send(count(1))
        got = summary(p.send(wp(0, command=command, frame=frame, autocontinue=autocontinue)))
        assert got == [(ACK, code, 0)], (command, frame, autocontinue, got)


def check_a_refused_item_can_be_sent_again_corrected(without=()):
    p = probe(without)
    assert summary(p.send(count(1))) == [(REQ, 0, 0)]
    assert summary(p.send(wp(0, frame=0))) == [(ACK, R.UNSUPPORTED_FRAME, 0)]
    assert summary(p.send(wp(0))) == [(ACK, R.ACCEPTED, 0)]


def check_latitude_is_not_range_checked(without=()):
    p = probe(without)
    p.send(count(1))
    assert summary(p.send(wp(0, x=100.0))) == [(ACK, R.ACCEPTED, 0)]


# --- 8. addressing ----------------------------------------------------------------------------
def check_broadcast_is_ignored_and_target_component_never_checked(without=()):
    p = with_plan(2, without)
    for msg in (request_list(0, (0, 0)), count(1, 0, (0, 0)), clear_all(0, (0, 0)), request_list(0, (2, 1))):
        assert p.send(msg) == [], msg
    assert summary(p.send(request_list(0, (1, 99)))) == [(COUNT, 2, 0)]
    assert summary(p.send(request_list(0, (1, 0)))) == [(COUNT, 2, 0)]


# --- 9.-10. download --------------------------------------------------------------------------
def check_download_fields(without=()):
    p = probe(without)
    sent = [wp(0, current=1, params=(1.5, 2.5, 3.5, 4.5), z=10.129),
            wp(1, command=Cmd.NAV_RETURN_TO_LAUNCH, x=0.0, y=0.0, z=0.0), wp(2, z=21474836.0)]
    assert summary(p.upload(sent))[-1] == (ACK, R.ACCEPTED, 0)
    first, rtl, high = [one(p.send(request(seq)), "MISSION_ITEM") for seq in range(3)]
    assert (first.frame, first.command, first.current, first.autocontinue) == (3, Cmd.NAV_WAYPOINT, 0, 1)
    assert (first.param1, first.param2, first.param3, first.param4) == (0, 0, 0, 0)
    assert (first.x, first.y) == (47.397743225097656, 8.545594215393066) == (to_float32(LAT), to_float32(LON))
    assert first.z == to_float32(10.12)                                 # truncated to whole cm
    assert (rtl.frame, rtl.command) == (2, Cmd.NAV_RETURN_TO_LAUNCH)
    assert high.z == -21474836.0                                        # the int32 cm wrapped


def check_no_plan_ids(without=()):
    p = probe(without)
    final = one(only(p.upload(waypoints(2)), ACK), ACK)
    c = one(p.send(request_list()), COUNT)
    assert (final.opaque_id, c.opaque_id) == (0, 0)


def check_requests_need_no_list_and_beyond_the_plan_are_invalid_sequence(without=()):
    p = with_plan(2, without)
    item = one(p.send(request(1)), "MISSION_ITEM")                      # no MISSION_REQUEST_LIST first
    assert item.seq == 1
    assert summary(p.send(request(2))) == [(ACK, R.INVALID_SEQUENCE, 0)]
    assert summary(p.send(request(0))) == [("MISSION_ITEM",)]


# --- 11.-12. identity, progress, capacity -------------------------------------------------------
def check_heartbeat_and_no_mission_current(without=()):
    p = with_plan(2, without)
    out = p.run(5.0)
    beats = [x for x in p.gcs.received if x.get_type() == "HEARTBEAT"]
    assert {(b.autopilot, b.type) for b in beats} == {(0, 2)}
    assert not {"MISSION_CURRENT", "CONTROL_STATUS"} & {x.get_type() for x in p.gcs.received}, out


def check_no_item_reached_while_flown(without=()):
    p = probe(without, autostart=True)
    p.upload(waypoints(3))
    p.run(60.0)
    assert p.vehicle.server.progress.complete                           # it did fly the plan
    assert not only(p.gcs.received, "MISSION_ITEM_REACHED")


def check_capacity_is_120(without=()):
    p = probe(without)
    assert summary(p.send(count(121))) == [(ACK, R.NO_SPACE, 0)]
    assert summary(p.send(count(65535, T.FENCE))) == [(ACK, R.NO_SPACE, 0)]
    assert summary(p.send(count(120))) == [(REQ, 0, 0)]


# knob -> the checks that rely on it (each must fail without it)
CHECKS = {
    "autopilot": [check_heartbeat_and_no_mission_current],
    "ignored_messages": [check_int_messages_get_no_reply, check_gcs_ack_set_current_and_command_long_are_ignored],
    "request_int": [check_requests_are_float],
    "target_system_only": [check_broadcast_is_ignored_and_target_component_never_checked],
    "mission_type_ignored": [check_fence_and_rally_reads_and_clears_act_on_the_mission,
                             check_fence_and_rally_uploads_replace_the_mission],
    "capacity": [check_capacity_is_120],
    "count0_opens_upload": [check_count0_requests_item0_and_keeps_the_plan_until_it_comes],
    "atomic_upload": [check_item0_clears_the_plan_and_an_abandoned_upload_stays_partial],
    "item0_clears_plan": [check_item0_clears_the_plan_and_an_abandoned_upload_stays_partial],
    "upload_counters_persist": [check_a_stray_item_continues_the_last_upload],
    "upload_timers": [check_a_stalled_upload_is_never_rerequested_nor_ended],
    "transfer_owner": [check_a_second_gcs_takes_an_upload_over],
    "out_of_sequence_reply": [check_out_of_sequence_and_duplicate_items_get_invalid_sequence],
    "rerequest_gap": [check_out_of_sequence_and_duplicate_items_get_invalid_sequence],
    "nack_ends_upload": [check_a_refused_item_can_be_sent_again_corrected],
    "reack_last_item": [check_items_after_a_finished_upload_get_invalid_sequence],
    "idle_reply": [check_items_after_a_finished_upload_get_invalid_sequence],
    "mission_commands": [check_commands_frames_and_autocontinue],
    "autocontinue_required": [check_commands_frames_and_autocontinue],
    "command_frames": [check_commands_frames_and_autocontinue],
    "lat_lon_range_check": [check_latitude_is_not_range_checked],
    "item_storage": [check_download_fields],
    "stateful_download": [check_requests_need_no_list_and_beyond_the_plan_are_invalid_sequence],
    "download_current_flag": [check_download_fields],
    "opaque_id_fields": [check_no_plan_ids],
    "set_current_command": [check_command_int_set_current_is_unsupported],
    "current_period": [check_heartbeat_and_no_mission_current],
    "item_reached_unreported": [check_no_item_reached_while_flown],
}
# taking a knob away takes with it what only works with it, and what would give its answer anyway:
# INAV's upload counters (upload_counters_persist) answer a stray item, a late copy and a corrected
# item after a refusal as the SITL did, whatever the slot-based knobs say
NEEDS = {"atomic_upload": ("item0_clears_plan", "upload_counters_persist"),
         "nack_ends_upload": ("upload_counters_persist",),
         "reack_last_item": ("upload_counters_persist",),
         "idle_reply": ("upload_counters_persist",)}
ALL_CHECKS = sorted({c for cs in CHECKS.values() for c in cs}, key=lambda c: c.__name__)
PAIRS = [(k, c) for k, cs in CHECKS.items() for c in cs]


@pytest.mark.parametrize("check", ALL_CHECKS, ids=lambda c: c.__name__.removeprefix("check_"))
def test_the_inav_vehicle_answers_as_the_sitl_did(check) -> None:
    check()


@pytest.mark.parametrize("knob,check", PAIRS, ids=[f"{k}-{c.__name__.removeprefix('check_')}" for k, c in PAIRS])
def test_without_the_knob_the_answer_differs(knob, check) -> None:
    with pytest.raises(AssertionError):
        check((knob, *NEEDS.get(knob, ())))


def test_every_knob_the_profile_changes_has_a_check_and_its_sources() -> None:
    profile = load_profile("inav")
    changed = {s.knob for s in profile.settings if KNOBS[s.knob].parse(s.value) != spec_default(s.knob)}
    assert changed == set(CHECKS), (sorted(changed - set(CHECKS)), sorted(set(CHECKS) - changed))
    for s in profile.settings:
        assert "INAV 9.1" in s.source and (".c:" in s.source or ".h:" in s.source), (s.knob, s.source)
        assert s.why, s.knob
        assert s.seen_on in ("", SEEN_ON), (s.knob, s.seen_on)
    assert sum(s.seen_on == SEEN_ON for s in profile.settings) >= len(profile.settings) - 1


def test_inav_is_a_builtin_target() -> None:
    assert "inav" in BUILTIN_PROFILES
    assert parse_target("builtin:inav").name == "inav"


def test_item0_clears_plan_needs_a_non_atomic_upload(tmp_path) -> None:
    path = tmp_path / "mine.toml"
    path.write_text('name = "mine"\n[[knob]]\nknob = "item0_clears_plan"\nvalue = true\n')
    with pytest.raises(UsageError, match="atomic_upload"):
        load_profile(str(path))


def test_the_float32_storage_matches_the_sitls_numbers() -> None:
    """x = 47.3977419 was stored as 473977440 (float32 x * 1e7f) and downloaded bit-identical to
    the float32 sent; z = 10.129 as 1012 cm."""
    assert to_float32(to_float32(LAT) * 1e7) == 473977440.0
    assert math.trunc(to_float32(to_float32(10.129) * 100.0)) == 1012


def test_a_generic_autopilot_is_not_taken_for_inav():
    """INAV's HEARTBEAT says MAV_AUTOPILOT_GENERIC, as MAVSDK's server and most others do: the
    profile is named with --profile, never guessed from autopilot 0 (it gave MAVSDK INAV's
    float32 stored form and eight false failures)."""
    from mavconform.conformance.harness.stored_form import (SPEC_FORM, modelling_profile, profile_for_target,
                                                           stored_form_of)
    assert load_profile("inav").config.autopilot == 0
    assert profile_for_target(0, 2) is None
    assert stored_form_of(modelling_profile("udp:127.0.0.1:14550", autopilot=0, mav_type=2)) == SPEC_FORM
    chosen = modelling_profile("udp:127.0.0.1:14550", chosen="inav", autopilot=0, mav_type=2)
    assert chosen is not None and stored_form_of(chosen).storage == load_profile("inav").behaviour.item_storage
