"""How the reference GCS adapts to vehicles that depart from the spec, as data.

Real GCSs talk to PX4 and ArduPilot by knowing where they differ (VARIANTS.md, "What GCSs
already do about it"). Each such habit is an `Adaptation` with a stable id, what it does and
where it comes from; `Adaptations` holds the knobs the client engine reads. The engine never
asks which autopilot it talks to: `for_autopilot` (the HEARTBEAT `autopilot` field -> a set,
as QGroundControl chooses its firmware plugin) is the only place that knows autopilot names.

Some knobs act from the start of an operation (home at seq 0, clearing types one by one,
longer waits); others only react to what the vehicle does (a MISSION_REQUEST is answered
with MISSION_ITEM_INT, an INVALID_SEQUENCE NACK mid-upload is ignored). Either way the
client records an adaptation as used only when it changed what the GCS did, and every
`OperationResult` lists them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Sequence

from ..wire.dialect import mavlink as _d
from .constants import Cmd
from .items import GLOBAL_FRAMES, MissionItem, MissionType


@dataclass(frozen=True)
class Adaptation:
    id: str
    description: str
    source: str


HOME_AT_SEQ0 = Adaptation(
    "home-at-seq0",
    "mission seq 0 is the vehicle's home: uploads send a home placeholder at seq 0 and count+1, "
    "downloads drop item 0, a DO_JUMP's target (param1) goes up by one on upload and down by one "
    "on download, set-current and MISSION_CURRENT are offset by one",
    "VARIANTS A1; QGroundControl and MAVSDK send count+1 to ArduPilot; QGroundControl "
    "src/MissionManager/PlanManager.cc writeMissionItems / _handleMissionItem shift DO_JUMP param1 "
    "by one between its home-at-0 numbering and a vehicle without a home item")
ITEM_INT_FOR_REQUEST = Adaptation(
    "item-int-for-request",
    "a MISSION_REQUEST (float) is answered with MISSION_ITEM_INT, as if it were MISSION_REQUEST_INT",
    "VARIANTS A6, P8; MAVSDK sends only MISSION_ITEM_INT")
IGNORE_NONTERMINATING_NACK = Adaptation(
    "ignore-nonterminating-nack",
    "an INVALID_SEQUENCE (or, once items flow, DENIED) NACK during an upload does not end it: "
    "the GCS keeps answering requests until the vehicle accepts, refuses an item or goes quiet",
    "VARIANTS A3; Cockpit ignores ArduPilot's out-of-spec NACKs")
CLEAR_TYPES_SEPARATELY = Adaptation(
    "clear-types-separately",
    "clearing all plan types sends MISSION_CLEAR_ALL once per type (mission, fence, rally) "
    "instead of once with MAV_MISSION_TYPE_ALL",
    "VARIANTS A10 (MAV_MISSION_TYPE_ALL is answered UNSUPPORTED)")
LONG_VEHICLE_TIMEOUT = Adaptation(
    "long-vehicle-timeout",
    "during an upload the GCS waits longer than the vehicle's re-request interval before "
    "resending, and does not give up before the vehicle's own transfer timeout has passed",
    "VARIANTS A5 (8 s, re-requests about every 1 s), P3 (5 s, every 250 ms)")
NON_ATOMIC_UPLOAD = Adaptation(
    "non-atomic-upload",
    "a failed upload is reported with outcome_unknown: the vehicle writes items as they arrive, "
    "so its plan may now be a mix of old and new",
    "VARIANTS A2; seed 000 (ArduPilot: uploads are not atomic)")
FINISH_RESTARTED_UPLOAD = Adaptation(
    "finish-restarted-upload",
    "requests that come after a successful upload (a late duplicate MISSION_COUNT restarted it "
    "on a vehicle that truncates at once and ignores cancellation) are answered from the plan "
    "just uploaded, so the vehicle ends up holding that plan rather than a truncated one",
    "VARIANTS A2, A4, A8; our own (QGC and MAVSDK answer such requests with a cancel or not at all)")
RESTART_DOWNLOAD_ON_ERROR = Adaptation(
    "restart-download-on-error",
    "a MISSION_ACK ERROR during a download restarts it from MISSION_REQUEST_LIST (at most "
    "max_retries times): a vehicle that ends downloads on any out-of-order request does so on "
    "a late duplicate of one of our earlier requests",
    "VARIANTS P6; our own (QGC and MAVSDK report the failure and leave the retry to the user)")
RETRY_REFUSED_SET_CURRENT = Adaptation(
    "retry-refused-set-current",
    "a set-current refused because the vehicle is busy (a STATUSTEXT saying busy / in progress, "
    "COMMAND_ACK TEMPORARILY_REJECTED) is retried on the normal timer, at most max_retries times, "
    "after a MISSION_ACK OPERATION_CANCELLED per plan type ends any transfer the vehicle still "
    "holds for us (a late duplicate request can open one); any other refusal ends it at once",
    "VARIANTS P12 (set-current only while no transfer runs), P2' (a cancel resets it); our own")
AWAIT_ACCEPT_AFTER_NACK = Adaptation(
    "await-accept-after-nack",
    "a generic NACK (not about an item) after the last item went out does not end the upload at "
    "once: the vehicle answers a late duplicate item with an error once it has committed, and "
    "its ACCEPTED may still be on the way; the GCS waits one response timeout for it",
    "ArduPilot GCS_Common.cpp (an item while not receiving gets MISSION_ACK ERROR, no re-ACK); our own")

CATALOGUE: tuple[Adaptation, ...] = (
    HOME_AT_SEQ0, ITEM_INT_FOR_REQUEST, IGNORE_NONTERMINATING_NACK, CLEAR_TYPES_SEPARATELY,
    LONG_VEHICLE_TIMEOUT, NON_ATOMIC_UPLOAD, FINISH_RESTARTED_UPLOAD, RESTART_DOWNLOAD_ON_ERROR,
    RETRY_REFUSED_SET_CURRENT, AWAIT_ACCEPT_AFTER_NACK)
BY_ID: dict[str, Adaptation] = {a.id: a for a in CATALOGUE}


@dataclass(frozen=True)
class Adaptations:
    """The knobs the client engine reads. The default (`NONE`) is the spec-exact GCS."""

    name: str = "none"
    home_at_seq0: bool = False               # HOME_AT_SEQ0 (mission plan type only)
    item_int_for_request: bool = False       # ITEM_INT_FOR_REQUEST
    ignore_nonterminating_nack: bool = False  # IGNORE_NONTERMINATING_NACK
    clear_types_separately: bool = False     # CLEAR_TYPES_SEPARATELY
    non_atomic_upload: bool = False          # NON_ATOMIC_UPLOAD
    finish_restarted_upload: bool = False    # FINISH_RESTARTED_UPLOAD
    restart_download_on_error: bool = False  # RESTART_DOWNLOAD_ON_ERROR
    retry_refused_set_current: bool = False  # RETRY_REFUSED_SET_CURRENT
    await_accept_after_nack: bool = False    # AWAIT_ACCEPT_AFTER_NACK
    # LONG_VEHICLE_TIMEOUT: the vehicle's re-request interval and transfer timeout, seconds
    vehicle_request_interval: float | None = None
    vehicle_timeout: float | None = None

    def __post_init__(self) -> None:
        for name in ("vehicle_request_interval", "vehicle_timeout"):
            value = getattr(self, name)
            if value is not None and not value > 0:
                raise ValueError(f"Adaptations.{name} must be > 0 seconds, got {value!r}")

    def armed(self) -> tuple[Adaptation, ...]:
        """The adaptations this set may use (whether they are used depends on the vehicle)."""
        on = {HOME_AT_SEQ0.id: self.home_at_seq0, ITEM_INT_FOR_REQUEST.id: self.item_int_for_request,
              IGNORE_NONTERMINATING_NACK.id: self.ignore_nonterminating_nack,
              CLEAR_TYPES_SEPARATELY.id: self.clear_types_separately,
              LONG_VEHICLE_TIMEOUT.id: self.vehicle_timeout is not None
              or self.vehicle_request_interval is not None,
              NON_ATOMIC_UPLOAD.id: self.non_atomic_upload,
              FINISH_RESTARTED_UPLOAD.id: self.finish_restarted_upload,
              RESTART_DOWNLOAD_ON_ERROR.id: self.restart_download_on_error,
              RETRY_REFUSED_SET_CURRENT.id: self.retry_refused_set_current,
              AWAIT_ACCEPT_AFTER_NACK.id: self.await_accept_after_nack}
        return tuple(a for a in CATALOGUE if on[a.id])

    def home_offset(self, mission_type: MissionType) -> int:
        """1 where the vehicle keeps home at seq 0 of this plan type, else 0."""
        return 1 if self.home_at_seq0 and mission_type is MissionType.MISSION else 0


NONE = Adaptations()

ARDUPILOT = Adaptations(
    name="ardupilot", home_at_seq0=True, item_int_for_request=True, ignore_nonterminating_nack=True,
    clear_types_separately=True, non_atomic_upload=True, finish_restarted_upload=True,
    retry_refused_set_current=True, await_accept_after_nack=True,
    vehicle_request_interval=1.0, vehicle_timeout=8.0)
PX4 = Adaptations(
    name="px4", item_int_for_request=True, restart_download_on_error=True,
    retry_refused_set_current=True,
    vehicle_request_interval=0.25, vehicle_timeout=5.0)

NAMED: dict[str, Adaptations] = {a.name: a for a in (NONE, ARDUPILOT, PX4)}


def for_autopilot(autopilot: int) -> Adaptations:
    """The set a GCS uses for a vehicle whose HEARTBEAT says `autopilot` (MAV_AUTOPILOT).

    The one place that maps an autopilot to behaviour. Anything else gets the spec-exact
    GCS: a vehicle that follows the spec needs no adaptation."""
    if autopilot == _d.MAV_AUTOPILOT_ARDUPILOTMEGA:
        return ARDUPILOT
    if autopilot == _d.MAV_AUTOPILOT_PX4:
        return PX4
    return NONE


def home_placeholder(items: list[MissionItem]) -> MissionItem:
    """The item a GCS sends at seq 0 for the vehicle to overwrite with its home.

    QGroundControl sends its planned home there; lacking one, the first global item's
    position stands in (any valid position does: the vehicle keeps its own home)."""
    anchor = next((i for i in items if i.frame in GLOBAL_FRAMES), None)
    x, y = (anchor.x, anchor.y) if anchor is not None else (0, 0)
    return MissionItem(0, 0, 16, x=x, y=y, z=0.0, mission_type=MissionType.MISSION)


def shift_jumps(items: Sequence[MissionItem], by: int) -> list[MissionItem]:
    """The items with every DO_JUMP target (param1, a seq) moved by `by`: a plan names the
    target by its position without a home item, a home-at-seq-0 vehicle by its seq (one more).
    QGroundControl numbers from its home (0) and shifts the other way for PX4: -1 on write,
    +1 on read (PlanManager.cc writeMissionItems, _handleMissionItem)."""
    return [replace(it, param1=it.param1 + by)
            if it.command == Cmd.DO_JUMP and math.isfinite(it.param1) else it for it in items]
