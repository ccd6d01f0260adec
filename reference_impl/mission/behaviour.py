"""The server's behaviour knobs: everything a profile may change, as data.

The spec profile is the default of every field. PX4-like and ArduPilot-like profiles
(`reference_impl/profiles/*.toml`) are instances of this class with each changed knob
citing its VARIANTS.md row; engine code reads knobs and never asks which autopilot it is
imitating.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .constants import MissionResult
from .items import PLAN_TYPES, MissionType
from .store import STORAGE_FORMS
from .timing import Timings
from .validation import SPEC_RULES, ItemRule


def _default_capacity() -> dict[MissionType, int]:
    return {MissionType.MISSION: 1000, MissionType.FENCE: 256, MissionType.RALLY: 64}


@dataclass(frozen=True)
class ServerBehaviour:
    timings: Timings = Timings()
    # Most items each plan type can hold; a larger MISSION_COUNT gets MAV_MISSION_NO_SPACE.
    capacity: dict[MissionType, int] = field(default_factory=_default_capacity)
    # Plan types this vehicle stores; others get MAV_MISSION_UNSUPPORTED.
    supported_types: frozenset[MissionType] = frozenset(PLAN_TYPES)
    # Request items with MISSION_REQUEST_INT (spec) rather than MISSION_REQUEST.
    request_int: bool = True
    # Acceptance rules for uploaded items (validation.py).
    item_rules: tuple[ItemRule, ...] = SPEC_RULES
    # What a stray ITEM or REQUEST gets while no transfer of its type runs; None: silence.
    # Seed 000: the idle recipient "may respond with an appropriate error for that state".
    idle_reply: MissionResult | None = MissionResult.OPERATION_CANCELLED
    # Repeat ACCEPTED when an item of the upload just accepted arrives again from the same
    # sender: its final ACK was lost or overtaken (lost-ack recovery).
    reack_last_item: bool = True
    # Give up a silent upload with MISSION_ACK OPERATION_CANCELLED to the sender
    # (seed 000: after the retries "the client must cancel the operation").
    notify_upload_give_up: bool = True
    # MISSION_CURRENT stream period (upstream: "streamed all the time (nominally at 1Hz)").
    # None: MISSION_CURRENT is never sent, neither streamed nor on a change (INAV 9.1).
    current_period: float | None = 1.0
    # Every mission message is about the mission plan, whatever its mission_type: replies
    # carry MAV_MISSION_TYPE_MISSION, and a fence or rally request, clear or upload (any
    # type, ALL too) reads, clears or replaces the mission (INAV 9.1 never reads the field).
    mission_type_ignored: bool = False
    # A mission message is for this vehicle only when its target_system is the vehicle's own
    # (no broadcast 0), and its target_component is not looked at. False: target_system 0
    # or ours, and target_component 0 or ours.
    target_system_only: bool = False

    # --- upload ---------------------------------------------------------------------------
    # Collect an upload aside and replace the plan whole after the last item (seed 000).
    # False: MISSION_COUNT truncates the stored plan at once and each item is written as it
    # arrives, so a failed upload leaves a mix of old and new.
    atomic_upload: bool = True
    # With atomic_upload False: MISSION_COUNT leaves the stored plan alone; item 0 clears it
    # and each item is appended as it arrives, so a stalled upload leaves the items so far.
    # False: MISSION_COUNT truncates the plan and items overwrite it in place.
    item0_clears_plan: bool = False
    # MISSION_COUNT 0 opens an upload like any count: MISSION_REQUEST for item 0, which is
    # then the last (its ACCEPTED replaces the plan with that one item). False (seed 000):
    # an empty upload clears the plan at once with ACCEPTED.
    count0_opens_upload: bool = False
    # The upload's item counter outlives the upload: an item that arrives with none running
    # is taken if its seq is the counter's (after an upload of n items: seq n, appended;
    # INAV 9.1, upload_counters.py); any other seq is answered INVALID_SEQUENCE.
    upload_counters_persist: bool = False
    # An item the vehicle refuses ends the upload (seed 000: errors are unrecoverable).
    # False: the error ACK is sent and the vehicle goes on requesting.
    nack_ends_upload: bool = True
    # Answer an out-of-sequence item with this MISSION_ACK (the upload goes on); None: drop it.
    out_of_sequence_reply: MissionResult | None = None
    # Re-request the expected item at once when a later one arrives (seed 000); False:
    # leave it to the item timeout.
    rerequest_gap: bool = True
    # Resends of one request are capped at `timings.max_retries`; False: resend until
    # `timings.protocol_timeout` passes without a message from the partner.
    retry_cap: bool = True
    # The vehicle times an upload (item re-requests, giving up). False: no timer at all: a
    # stalled upload is never re-requested and never ended, it waits for its next item.
    upload_timers: bool = True
    # STATUSTEXT (WARNING) sent with the give-up of a silent upload; "" for none.
    give_up_statustext: str = ""
    # A MISSION_ACK from the GCS (e.g. OPERATION_CANCELLED) ends its running upload.
    honour_cancel_upload: bool = True
    # ...and so does one with any other error code (False: only OPERATION_CANCELLED does;
    # other codes are ignored and the vehicle goes on requesting).
    error_ack_ends_upload: bool = True
    # The MISSION_ACK a GCS gets when another GCS's transfer holds the plan type.
    busy_reply: MissionResult = MissionResult.DENIED
    # A transfer belongs to the GCS that opened it (others get `busy_reply`). False: a
    # transfer has no owner: any GCS's message acts on it and the replies go to whoever
    # spoke last (INAV 9.1 keeps two counters and answers the sender).
    transfer_owner: bool = True
    # MISSION_REQUEST_LIST for a mission_type that is no plan type is answered MISSION_COUNT 0
    # (False: MISSION_ACK UNSUPPORTED).
    unknown_type_count0: bool = False
    # MAV_CMD_DO_SET_MISSION_CURRENT is handled (False: answered MAV_RESULT_UNSUPPORTED).
    set_current_command: bool = True
    # A MISSION_SET_CURRENT that cannot be done draws a STATUSTEXT saying why (False: nothing).
    set_current_failure_text: bool = True
    # An item of another plan type, sent by the partner of a running upload, is answered
    # with this MISSION_ACK (for the running transfer's type); None: treated as a stray.
    foreign_type_item_reply: MissionResult | None = None
    # The form of the vehicle's requests follows the GCS's items (MISSION_ITEM switches to
    # MISSION_REQUEST), and a MISSION_ACK UNSUPPORTED mid-upload flips the form and resends.
    follow_gcs_int_mode: bool = False
    # MISSION_WRITE_PARTIAL_LIST rewrites a range of the stored plan (start..end inclusive).
    partial_write: bool = False

    # --- download -------------------------------------------------------------------------
    # A download is a transfer: it belongs to its GCS until that GCS's MISSION_ACK (or a
    # long silence). False: requests are answered whenever they come and the GCS's final
    # ACK means nothing (no download state).
    stateful_download: bool = True
    # Requests must come in order: seq == next answers, seq == next-1 resends, any other
    # seq ends the download with MISSION_ACK ERROR. False: any stored seq is answered.
    sequential_download: bool = False
    # While an upload of a type runs, MISSION_REQUEST_LIST / MISSION_REQUEST(_INT) /
    # MISSION_WRITE_PARTIAL_LIST for that type get DENIED, from its own partner too.
    deny_reads_during_upload: bool = False

    # --- plan content ---------------------------------------------------------------------
    # Mission plans hold the vehicle's home at seq 0: a download's item 0 is the home
    # position, the uploaded item 0 is not kept as sent, flights start at seq 1 and
    # MISSION_CURRENT.total is count - 1.
    home_at_seq0: bool = False
    # How items are kept: "exact" (as received), or "compact15": a 15-byte command record
    # (altitude in whole cm, hold time in whole seconds, other waypoint params dropped,
    # rally altitude in whole metres, *_INT frames reported as their plain frames), or
    # "compact15-plane": ArduPlane's build of it (a waypoint keeps acceptance radius and pass-by
    # distance as whole metres up to 255 instead of its hold time), or "float32-cm": a record
    # filled in float32 (lat/lon through x * 1e7f, altitude whole cm, params dropped, RTL in
    # MAV_FRAME_MISSION; INAV 9.1), or "px4": PX4 v1.16's mission_item_s (px4_storage.py), or
    # "ardupilot" / "ardupilot-plane": AP_Mission's per-command packing of the 15-byte record
    # (ardupilot_commands.py) with fence items rebuilt, ArduPlane's waypoint its own way.
    item_storage: str = "exact"
    # A downloaded mission item carries current=1 exactly when it is the current item
    # (False: the flag is 0 on every item, whatever is current).
    download_current_flag: bool = True
    # Report plan ids (opaque_id, MISSION_CURRENT mission_id/fence_id/rally_points_id).
    # False: the older dialect without them (the fields go out as zero, which MAVLink 2's
    # trailing-zero truncation makes byte-identical to a frame without the fields).
    opaque_id_fields: bool = True

    # --- clear, set current, progress -----------------------------------------------------
    # MISSION_CLEAR_ALL with MAV_MISSION_TYPE_ALL clears every type; False: UNSUPPORTED.
    clear_all_supported: bool = True
    # The mission plan may be cleared while it is being flown; False: MISSION_ACK ERROR.
    clear_while_flying: bool = True
    # MISSION_SET_CURRENT is refused (STATUSTEXT) while any transfer is in progress.
    set_current_only_idle: bool = False
    # MISSION_ITEM_REACHED is sent this many times for each item reached, 1 s apart.
    item_reached_repeats: int = 1
    # MISSION_ITEM_REACHED waits in one slot until the next send opportunity (progress.py
    # REACHED_SLOT_DELAY): an item reached meanwhile replaces it, so only the later is sent.
    item_reached_one_slot: bool = False
    # Commands whose completion sends no MISSION_ITEM_REACHED at all (ArduPilot verifies its
    # camera, servo and relay DO commands itself, never through the vehicle's callback that
    # reports); a report pending in the slot stays.
    item_reached_unreported: frozenset[int] = frozenset()

    # --- framing and warnings -------------------------------------------------------------
    # Plan types whose transfers need MAVLink 2: a MAVLink 1 frame about them gets
    # STATUSTEXT "Need mavlink2 for item transfer" and MISSION_ACK UNSUPPORTED.
    mavlink2_types: frozenset[MissionType] = frozenset()
    # A STATUSTEXT warning, once per transfer, when the GCS uses MISSION_REQUEST or
    # MISSION_ITEM instead of the _INT forms.
    legacy_warnings: bool = False

    def __post_init__(self) -> None:
        if self.item_storage not in STORAGE_FORMS:
            raise ValueError(f"item_storage must be one of {sorted(STORAGE_FORMS)}, got {self.item_storage!r}")
        if self.item_reached_repeats < 1:
            raise ValueError("item_reached_repeats must be >= 1")
        if self.item0_clears_plan and self.atomic_upload:
            raise ValueError("item0_clears_plan needs atomic_upload=False (an atomic upload never writes early)")
        if self.current_period is not None and not self.current_period > 0:
            raise ValueError("current_period must be > 0 seconds (or None: never sent)")
        if not self.retry_cap and self.timings.protocol_timeout is None:
            raise ValueError("retry_cap=False needs timings.protocol_timeout (else retries never end)")

    @property
    def download_idle_timeout(self) -> float:
        """How long a download stays open without a request from the GCS (it drives retries)."""
        t = self.timings
        return t.default_timeout * (t.max_retries + 1)
