"""An item the vehicle rejects (seed 000, "Errors/Completion"): MIS.UP.17

"Errors are considered unrecoverable. If an error is sent, both ends of the system should
reset themselves to the idle state and the current state of the mission on the vehicle
should be unaltered." To see that, the suite needs an item the vehicle refuses, and which
items a vehicle refuses is its own business: the check offers candidates, each one a real
autopilot is known to refuse, until the vehicle refuses one, and names the one it used.

The refused item comes after real ones were written (item 1 too: ArduPilot keeps home in
mission slot 0 and drops an uploaded item 0), in a count shorter than the old plan
(ArduPilot truncates at MISSION_COUNT): a vehicle that writes an upload as it arrives
(VARIANTS A2) holds a changed plan after the refusal, and the clause sees it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.wire.frame import Frame

from ..harness import plans, procedures
from ..harness.match import request
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, beyond_the_clause
from ..session import Session
from . import check
from .upload import ITEM_TIMEOUT, silence_window

MISSION = MissionType.MISSION
MT = int(MISSION)
OLD_ITEMS, NEW_ITEMS, REFUSED_AT = 4, 3, 2   # the old plan, the new count, the candidate's seq
UNKNOWN_COMMAND = 31999   # no MAV_CMD of common.xml, development.xml or ardupilotmega.xml


@dataclass(frozen=True)
class Candidate:
    """An item some vehicle refuses: what it is, how it is made from a plain waypoint, and
    who is known to refuse it (source)."""
    label: str
    make: Callable[[MissionItem], MissionItem]
    refused_by: str


CANDIDATES: tuple[Candidate, ...] = (
    Candidate("a waypoint at latitude 100 degrees", lambda it: replace(it, x=1_000_000_000),
              "ArduPilot (AP_Mission::mavlink_int_to_mission_cmd checks the location; seen on "
              "ArduCopter SITL); PX4 does not (parse_mavlink_mission_item copies x and y unchecked)"),
    Candidate(f"an item with command {UNKNOWN_COMMAND}, which is no MAV_CMD",
              lambda it: replace(it, command=UNKNOWN_COMMAND),
              "PX4 (parse_mavlink_mission_item's default: MAV_MISSION_UNSUPPORTED; seen on v1.16.0 "
              "SITL in frames 2 and 3); ArduPilot (mavlink_int_to_mission_cmd's default: "
              "MAV_MISSION_UNSUPPORTED; seen on ArduCopter SITL)"),
    Candidate("a waypoint in MAV_FRAME_LOCAL_NED", lambda it: replace(it, frame=_d.MAV_FRAME_LOCAL_NED),
              "PX4 (parse_mavlink_mission_item: a frame neither global nor MAV_FRAME_MISSION gets "
              "MAV_MISSION_UNSUPPORTED_FRAME; seed 000: PX4 takes only global frames for mission "
              "items); ArduPilot (mavlink_int_to_mission_cmd: UNSUPPORTED_FRAME for a frame it "
              "does not list)"),
)


@check("MIS.UP.17")
def rejected_item_keeps_plan(s: Session) -> str:
    t = s.t
    window = silence_window(s, ITEM_TIMEOUT * 3)   # measured first: it runs an upload of its own
    accepted: list[str] = []
    for candidate in CANDIDATES:
        # each try from the old plan: a candidate the vehicle accepted has replaced it
        procedures.ensure_plan(t, plans.mission(OLD_ITEMS, variant=17), MISSION)
        old = procedures.stored(t, MISSION)
        items = plans.mission(NEW_ITEMS, variant=18)
        items[REFUSED_AT] = candidate.make(items[REFUSED_AT])
        final = _offer(t, items)
        if final.msg.type == MissionResult.ACCEPTED:
            accepted.append(candidate.label)
            continue
        code = procedures.result_name(final.msg.type)
        what = (f"the vehicle refused {candidate.label} (item {REFUSED_AT} of {NEW_ITEMS}, after "
                f"items 0-{REFUSED_AT - 1}) with {code}")
        t.note(what)
        t.mark()
        later = t.poll_for(request(mission_type=MT), window)
        if later is not None:
            t.decided_by_frame(later)
            raise ClauseFailed(f"{what}, then went on requesting (item {later.msg.seq} after its "
                               "error): the error did not end the upload")
        procedures.require_same_plan(procedures.stored(t, MISSION), old, f"after {what}", t.form)
        tried = f"; it accepted {'; '.join(accepted)} first" if accepted else ""
        return f"{what} and kept the old plan{tried}"
    raise NotApplicable(f"the vehicle accepted every item tried as one it might reject ({'; '.join(accepted)}), "
                        "so no item it rejects was found")


def _offer(t: Tester, items: list[MissionItem]) -> Frame:
    """Upload `items`: the plain items before the candidate are setup, the vehicle's answer
    to the candidate (its MISSION_ACK, the final one if it took the candidate) the clause."""
    with beyond_the_clause(f"bringing an upload to its request for item {REFUSED_AT}"):
        t.mark()
        t.send(m.count_message(len(items), MISSION, t.target))
        for seq in range(REFUSED_AT):
            t.expect(request(seq, mission_type=MT))
            t.send(m.item_message(items[seq], t.target))
        t.expect(request(REFUSED_AT, mission_type=MT))
    t.send(m.item_message(items[REFUSED_AT], t.target))
    final = procedures.serve_upload(t, items)
    if final is None:
        t.check_alive()
        raise ClauseFailed(f"after item {REFUSED_AT} of {len(items)} the upload stalled: the vehicle "
                           "neither accepted the plan nor refused the item with a MISSION_ACK")
    return final
