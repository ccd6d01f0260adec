"""Which clauses judge each profile knob: the table of the negative-control matrix.

A profile knob (reference_impl/profiles/knobs.py) makes the reference vehicle depart from
the spec, or take a choice the spec leaves open, as a real autopilot does. A clause *judges*
a knob when its verdict changes with that knob: it fails (or, for an optional behaviour,
becomes not-applicable). A probe can be blind to the very deviation it is about (issue 23:
MIS.UP.05 passed on ArduPilot's non-atomic upload because the abandoned upload delivered
only item 0, which ArduPilot keeps as home), so every claim here is run, for every builtin
profile (tests/profiles/test_knob_matrix.py), and a knob no clause judges says why.

`JUDGES` has a row for every knob. For a value other than the spec default (a profile's
value, its alternative, or the row's `example`, which gives a knob no builtin profile sets
a run too):

(a) alone: the spec vehicle (builtin:spec as the suite runs it) with just that knob, and the
    knobs the row `needs` and those of its `side` the profile sets (at the profile's values),
    gives exactly the row's verdicts:
    each listed clause its listed outcome, every other clause the verdict it has on the spec
    vehicle. A row without clauses claims that the knob changes no verdict at all.
(b) needed: the profile's vehicle with the knob put back to the spec default (and any knob
    whose row needs it) passes each listed clause, unless another knob the profile sets
    lists that clause too.
(c) not masked: the profile's vehicle with every other knob that lists the clause put back
    (but the ones this knob needs) still gives the clause this knob's outcome: the
    profile's other knobs (home at seq 0, say) do not hide the deviation from the probe.

A knob a profile sets to the spec default (`loader.spec_default`; P1', P2', A3) changes
nothing and is left out. A row's verdicts hold for every non-default value the profiles use;
a value that gives other verdicts makes (a) fail, and the row must say what that value changes.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from .outcome import Outcome

FAIL, NOT_APPLICABLE = Outcome.FAIL, Outcome.NOT_APPLICABLE


@dataclass(frozen=True)
class Judged:
    """One knob's row: the clauses that judge it, each with its verdict with the knob on;
    why they see it (or why no clause does); the knobs it only works together with; a value
    to try it with when no builtin profile sets it."""
    clauses: Mapping[str, Outcome]
    why: str
    needs: tuple[str, ...] = ()
    example: Any = None
    side: tuple[str, ...] = ()       # tried with those of these knobs the profile sets too

    @property
    def together(self) -> tuple[str, ...]:
        """Every knob that goes with this one: what it needs and its side."""
        return self.needs + tuple(k for k in self.side if k not in self.needs)


def fails(*clauses: str, why: str, needs: tuple[str, ...] = (), example: Any = None) -> Judged:
    return Judged({c: FAIL for c in clauses}, why, needs, example)


def not_applicable(*clauses: str, why: str, example: Any = None) -> Judged:
    return Judged({c: NOT_APPLICABLE for c in clauses}, why, (), example)


def unjudged(why: str, example: Any = None) -> Judged:
    return Judged({}, why, (), example)


_INAV_ONLY = ("not run in the matrix: only the inav profile sets it, and the matrix leaves that profile "
              "out (see ignored_messages); tests/profiles/test_inav_profile.py checks its answers")


# The autopilot side of a vehicle, one unit: the HEARTBEAT's autopilot picks the suite's flight
# style (harness/flight_styles.py), which only flies a vehicle whose modes, arming and start
# are that autopilot's; so each of these is tried together with every other one the profile sets.
FLYING = ("autopilot", "vehicle_type", "params", "modes", "set_mode_params", "boot_mode", "mission_end_mode",
          "command_refusal", "arming", "no_arming_modes", "landing_required", "land_start_blocks_arming",
          "mission_start", "takeoff_first", "takeoff_command", "takeoff_altitude", "rtl_lands",
          "disarm_after_landing", "disarm_idle_after", "disarm_resets_mission", "statustexts", "cruise_speed")


def flown(why: str) -> Judged:
    """A knob of the autopilot side (FLYING): no clause judges it, with the rest of its side."""
    return Judged({}, why, (), None, FLYING)


JUDGES: dict[str, Judged] = {
    # --- timings ----------------------------------------------------------------------------
    "default_timeout": unjudged(
        "the vehicle's own reply timeout only drops a download its GCS stopped driving (after six "
        "of them), which no clause waits for", example=0.5),
    "item_timeout": fails(
        "MIS.UP.07", why="re-requests come every item_timeout; MIS.UP.07 measures them (about 250 ms)"),
    "max_retries": fails(
        "MIS.UP.09", why="MIS.UP.09 counts the resends of the silent upload's request (at most 5)",
        example=8),
    "protocol_timeout": unjudged(
        "it ends only an upload whose retries are uncapped (judged with retry_cap, by MIS.UP.09); "
        "with capped retries the vehicle gives up first"),
    # --- upload -----------------------------------------------------------------------------
    "retry_cap": fails(
        "MIS.UP.09", needs=("protocol_timeout",),
        why="uncapped, the silent upload's request is resent until protocol_timeout: more than 5 times"),
    "atomic_upload": fails(
        "MIS.UP.05", "MIS.UP.12", "MIS.UP.17", "MIS.CAN.02",
        why="items written as they arrive, after a count that truncates: an upload abandoned, ended "
            "by the GCS's error, refused at an item or cancelled leaves a changed plan"),
    "nack_ends_upload": fails(
        "MIS.UP.17", why="a refused item must end the upload (seed 000:547): MIS.UP.17 watches for "
                         "requests after the vehicle's error"),
    "out_of_sequence_reply": fails(
        "MIS.UP.11", why="an error ACK for an out-of-sequence item, which seed 000:553 says is no error"),
    "rerequest_gap": unjudged(
        "seed 000 asks for the expected item to be re-requested, not at once: the item timer's "
        "re-request meets MIS.UP.10"),
    "honour_cancel_upload": fails(
        "MIS.UP.12", "MIS.CAN.01", why="the GCS's error or OPERATION_CANCELLED ACK does not stop the requests"),
    "error_ack_ends_upload": fails(
        "MIS.UP.12", why="the GCS's ERROR ACK does not stop the requests (OPERATION_CANCELLED does)"),
    "notify_upload_give_up": unjudged(
        "seed 000 asks a vehicle that gives an upload up to go idle (MIS.UP.08), not to tell the GCS"),
    "give_up_statustext": unjudged("a STATUSTEXT informs the operator; no clause asks for or reads it"),
    "request_int": fails("MIS.UP.15", why="MIS.UP.15 reads the form of the first request"),
    "follow_gcs_int_mode": unjudged(
        "requests change form only after the GCS sends MISSION_ITEM: MIS.UP.15 judges the first "
        "request, MIS.UP.14 that float items are taken"),
    "legacy_warnings": unjudged("a STATUSTEXT informs the operator; no clause asks for or reads it"),
    "partial_write": unjudged("MISSION_WRITE_PARTIAL_LIST is an optional extension no clause uses"),
    "foreign_type_item_reply": unjudged(
        "MIS.TYP.05 judges that an item of another plan type stays out of the upload, which it does; "
        "an ERROR while the upload goes on is against seed 000:547, which no clause judges here"),
    "busy_reply": fails("MIS.GCS.01", why="MIS.GCS.01 asks for DENIED to another GCS during an upload"),
    # --- item rules -------------------------------------------------------------------------
    "accept_unknown_commands": unjudged(
        "taking an item it cannot fly is the vehicle's choice; MIS.UP.17 then offers another "
        "item it may refuse", example=True),
    "mission_commands": unjudged(
        "refusing a command it does not store is the spec's own answer (UNSUPPORTED); the clauses "
        "upload NAV_WAYPOINTs in a global frame, which every list holds"),
    "frame_lists_all_plans": Judged({}, "which frames a fence or rally item may use is the fidelity survey's "
                                    "to judge (mavconform fidelity: the frame matrix's refusals); the clauses "
                                    "upload fence and rally items in frames 0 and 3, which the global list holds",
                                    needs=("mission_commands",)),
    "location_frames": unjudged(
        "taking a location in more frames than the spec vehicle does is the vehicle's choice; the "
        "clauses use global frames"),
    "nan_params": unjudged(
        "refusing a NaN param is refusing an item (INVALID_PARAMn), the vehicle's right; no clause "
        "sends one"),
    "location_alt_max": unjudged(
        "refusing an altitude is refusing an item, the vehicle's right; the clauses fly at 10-30 m"),
    "value_rules": unjudged(
        "which param values a vehicle refuses is its own (the spec asks a value it cannot store to be "
        "refused, not which); the fidelity survey's command matrix shows each (mavconform fidelity "
        "--matrix-scope commands)", example="px4"),
    "lat_lon_range_check": unjudged(
        "the spec does not ask for a position range check; MIS.UP.17 then offers the next item "
        "it may refuse (an unknown command)"),
    # --- plan types, capacity, idle ---------------------------------------------------------
    "capacity": unjudged(
        "how many items a plan holds is the vehicle's own; MIS.UP.13 needs some count it refuses "
        "(65535)"),
    "supported_types": unjudged(
        "a vehicle need not store every plan type (seed 000: UNSUPPORTED); the MIS.TYP clauses take "
        "the types it stores"),
    "unknown_type_count0": fails(
        "MIS.TYP.04", why="MISSION_COUNT 0 for an unknown mission_type, where an error ACK is due"),
    "idle_reply": unjudged(
        "seed 000 lets an idle vehicle ignore a stray or answer it with an error; only ACCEPTED "
        "would fail MIS.IDL.01", example="none"),
    "reack_last_item": unjudged(
        "repeating ACCEPTED for a late copy of the last item is lost-ack recovery the spec leaves "
        "open; no clause loses the final ACK", example=False),
    "mavlink2_types": unjudged(
        "seed 000: fence and rally transfers need MAVLink 2, which the suite's GCS speaks"),
    # --- download ---------------------------------------------------------------------------
    "stateful_download": fails(
        "MIS.IDL.01", why="a request with no download open is answered with the item"),
    "sequential_download": unjudged(
        "no clause requests download items out of order: seed 000:553 (out-of-sequence messages "
        "are no errors) has a clause for uploads only (MIS.UP.11)"),
    "deny_reads_during_upload": unjudged(
        "no clause reads a plan while an upload of it runs; the spec does not say a vehicle must "
        "serve one then"),
    "download_current_flag": fails(
        "MIS.DN.09", why="the current item's downloaded copy has current=0"),
    # --- plan content, ids ------------------------------------------------------------------
    "home_at_seq0": fails(
        "MIS.UP.04", why="a download's item 0 is home, not the uploaded item 0: MIS.UP.04 owns A1 and "
                         "compares item 0; every other clause compares in the stored form"),
    "item_storage": unjudged(
        "every plan comparison allows the target's stored form (harness/stored_form.py): a compact "
        "record is the target's storage, not a departure (A13)"),
    "opaque_id_fields": not_applicable(
        "MIS.OID.01", "MIS.OID.02", why="the older dialect has no plan ids: the clauses about them "
                                        "do not apply"),
    # --- clear, set current, progress -------------------------------------------------------
    "clear_all_supported": not_applicable(
        "MIS.CLR.04", why="clearing every type at once is optional (MAY): refused, MIS.CLR.04 does not apply"),
    "clear_while_flying": unjudged("seed 000 says nothing of clearing a plan in flight; no clause does"),
    "set_current_failure_text": fails(
        "MIS.CUR.02", why="an impossible MISSION_SET_CURRENT draws no STATUSTEXT"),
    "set_current_command": fails(
        "MIS.CUR.05", why="MAV_CMD_DO_SET_MISSION_CURRENT is answered UNSUPPORTED"),
    "set_current_only_idle": unjudged(
        "no clause sets the current item during a transfer, and seed 000 does not say it must work then"),
    "current_period": fails(
        "MIS.CUR.06", why="MIS.CUR.06 counts MISSION_CURRENTs (about 1 Hz)", example=3.0),
    "item_reached_repeats": unjudged(
        "MISSION_ITEM_REACHED repeated still says the item was reached (MIS.PRG.01)"),
    "item_reached_one_slot": fails(
        "MIS.PRG.01", why="the flight's plan has a waypoint with a DO_CHANGE_SPEED right after it: the "
                          "DO command's report takes the waypoint's pending one over"),
    "item_reached_unreported": unjudged(
        "a DO command needs no report of its own (MIS.PRG.01 asks for the navigation items'); "
        "without one, the waypoint before it keeps its pending report"),
    # --- flying: the autopilot side (reference_impl/flight_rules.py) ------------------------
    # How a vehicle is flown is the autopilot's own: the suite's flight style follows the
    # HEARTBEAT (harness/flight_styles.py), so these change no verdict on the vehicles that
    # have them; they judge the suite's flight, which tests/conformance/test_flight_*.py do.
    "vehicle_type": flown(
        "HEARTBEAT identity: the flight is laid out and flown for the vehicle's class; no clause "
        "judges the type"),
    "cruise_speed": flown("how fast the flight model flies: the flight's window allows for the slowest "
                             "of its class"),
    "params": flown("the radii the flight reads to size its legs; no clause judges them"),
    "modes": flown("the autopilot's own flight modes: the flight asks for its style's and confirms it "
                      "from the HEARTBEAT"),
    "set_mode_params": flown("how MAV_CMD_DO_SET_MODE names a mode (ArduPilot's or PX4's numbers)"),
    "boot_mode": flown("HEARTBEAT identity: the mode the autopilot starts in"),
    "mission_end_mode": flown("where the vehicle goes after its last item: the flight then lands it"),
    "command_refusal": flown("the MAV_RESULT a refused flight command gets"),
    "arming": flown("a mission flies armed: the flight arms it in its style's mode, and disarms it after"),
    "no_arming_modes": flown("modes the vehicle will not arm in: the flight arms in its style's mode"),
    "landing_required": flown("the plan the flight flies ends with a landing"),
    "land_start_blocks_arming": flown("the plan the flight flies has no DO_LAND_START"),
    "mission_start": flown("how MAV_CMD_MISSION_START starts a mission: the flight starts it as the "
                              "style says"),
    "takeoff_first": flown("the flight's plan starts with its take-off item"),
    "takeoff_command": flown("the flight takes off with the plan's take-off item, not the command"),
    "takeoff_altitude": flown("the flight's plan says its take-off altitude"),
    "rtl_lands": flown("the flight lands a vehicle by its LAND mode or its plan's landing, not by RTL"),
    "disarm_after_landing": flown("the flight disarms a landed vehicle that did not disarm itself"),
    "disarm_idle_after": flown("the flight arms only to fly at once"),
    "disarm_resets_mission": flown("the flight sets its first item current before every start"),
    "statustexts": flown("a STATUSTEXT informs the operator; no clause asks for or reads it"),
    # --- the node ---------------------------------------------------------------------------
    "autopilot": flown(
        "HEARTBEAT identity: a GCS adapts to it; an in-process vehicle's stored form comes from "
        "its knobs"),
    "custom_mode_idle": unjudged("HEARTBEAT identity: the autopilot's own mode number, which the "
                                 "Mission Protocol does not read"),
    "custom_mode_mission": unjudged("HEARTBEAT identity: the autopilot's own mode number, which the "
                                    "Mission Protocol does not read"),
    # --- INAV 9.1 (the inav profile). The knob matrix leaves the one profile that sets these
    # out (Profile.int_messages_ignored: its transfers go through the tester's float-form
    # fallback, which the matrix's example runs do not take), so these rows are not run
    # there; builtin:inav is run whole against expectations/inav.toml (the self-check), and
    # each knob's answers are checked in tests/profiles/test_inav_profile.py ---
    "ignored_messages": unjudged(
        "a vehicle that ignores MISSION_ITEM_INT / MISSION_REQUEST_INT: the tester falls back to "
        "MISSION_ITEM / MISSION_REQUEST (float_forms.py) and MIS.DN.02 fails; not run in the matrix (above)"),
    "mission_type_ignored": unjudged(_INAV_ONLY),
    "target_system_only": unjudged(_INAV_ONLY),
    "item0_clears_plan": unjudged(_INAV_ONLY),
    "count0_opens_upload": unjudged(_INAV_ONLY),
    "upload_counters_persist": unjudged(_INAV_ONLY),
    "upload_timers": unjudged(_INAV_ONLY),
    "transfer_owner": fails("MIS.GCS.01", "MIS.GCS.02", example=False,
                            why="with no owner a second GCS's MISSION_COUNT restarts the upload instead of "
                                "being DENIED, and the first GCS's upload is lost"),
    "command_frames": unjudged(_INAV_ONLY),
    "autocontinue_required": unjudged(_INAV_ONLY),
    "single_peer_link": unjudged(
        "how GCSs reach the vehicle (L1, L2): the session's second GCS shares the first one's "
        "socket, as a real SITL link needs"),
}


def listers(clause: str, knobs: set[str] | frozenset[str]) -> set[str]:
    """The knobs among `knobs` whose rows list `clause`."""
    return {k for k in knobs if clause in JUDGES[k].clauses}


def dependents(knob: str, knobs: set[str] | frozenset[str]) -> set[str]:
    """`knob` and every knob among `knobs` that needs it, however indirectly: what must go
    back to the default with it (retry_cap cannot be off without protocol_timeout)."""
    out, todo = {knob}, [knob]
    while todo:
        k = todo.pop()
        for other in knobs:
            if other not in out and k in JUDGES[other].together:
                out.add(other)
                todo.append(other)
    return out
