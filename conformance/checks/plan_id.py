"""Plan ids (upstream MISSION_ACK/MISSION_COUNT opaque_id): MIS.OID.*

A vehicle that supports plan ids returns one in the MISSION_ACK that accepts an upload and
reports the stored plan's id in the MISSION_COUNT of a download; the id "must change when
there is any change to the on-vehicle plan type". An upload ACK with opaque_id 0 says the
vehicle does not support ids (both clauses are MAYs), unless the plan is empty.
"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import plans, procedures
from ..harness.match import msg
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
RETRIES = procedures.RETRIES


def _upload_id(t: Tester, items: list[MissionItem], mission_type: MissionType) -> int:
    """Upload `items`; the opaque_id of the accepting MISSION_ACK, or NotApplicable if 0."""
    frame = procedures.upload(t, items, mission_type)
    if frame is None or frame.msg.type != MissionResult.ACCEPTED:
        what = "no MISSION_ACK" if frame is None else procedures.result_name(frame.msg.type)
        raise PreconditionFailed(f"setup: uploading a {len(items)}-item {mission_type.label} plan got {what}")
    opaque_id = getattr(frame.msg, "opaque_id", 0)
    if not opaque_id:
        raise NotApplicable("the MISSION_ACK accepting an upload has opaque_id 0: the vehicle does not "
                            "support plan ids")
    return opaque_id


def _count_id(t: Tester, mission_type: MissionType) -> tuple[int, int]:
    """(count, opaque_id) of the MISSION_COUNT answering a MISSION_REQUEST_LIST."""
    t.mark()
    frame = procedures.open_download(t, mission_type)
    if frame is None:
        raise PreconditionFailed(f"MISSION_REQUEST_LIST for the {mission_type.label} plan got no MISSION_COUNT")
    if frame is not None:   # every download opened is ended, an empty one too
        t.send(m.ack_message(MissionResult.OPERATION_CANCELLED, mission_type, t.target))
    return frame.msg.count, getattr(frame.msg, "opaque_id", 0)


@check("MIS.OID.01")
def upload_id_reported_on_download(s: Session) -> None:
    t = s.t
    items = plans.mission(3, variant=90)
    opaque_id = _upload_id(t, items, MISSION)
    count, reported = _count_id(t, MISSION)
    if count != len(items):
        raise PreconditionFailed(f"the vehicle reports {count} items for the {len(items)}-item plan it "
                                 "accepted (MIS.UP.04 judges that)")
    if reported != opaque_id:
        raise ClauseFailed(f"the upload was accepted with opaque_id 0x{opaque_id:08x}, but the download's "
                           f"MISSION_COUNT reports opaque_id 0x{reported:08x}; expected the same id")


@check("MIS.OID.02")
def id_changes_with_plan(s: Session) -> None:
    t = s.t
    first = _upload_id(t, plans.mission(3, variant=91), MISSION)
    second = _upload_id(t, plans.mission(3, variant=92), MISSION)
    if second == first:
        raise ClauseFailed(f"two different plans were both accepted with opaque_id 0x{first:08x}; "
                           "expected the id to change when the plan changes")
    t.mark()
    t.send(m.clear_all_message(MISSION, t.target))
    frame = t.poll_for(msg("MISSION_ACK", mission_type=int(MISSION)), t.timings.default_timeout)
    if frame is None or frame.msg.type != MissionResult.ACCEPTED:
        return   # no cleared plan to look at (MIS.CLR.01 judges the clear)
    count, after_clear = _count_id(t, MISSION)
    if count == 0 and after_clear == second:
        raise ClauseFailed(f"after the plan was cleared, MISSION_COUNT still reports opaque_id "
                           f"0x{second:08x}, the id of the plan before; expected it to change")
