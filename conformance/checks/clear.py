"""Clear (seed 000, "Clear Missions"): MIS.CLR.*"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ..harness import plans, procedures
from ..harness.match import ack
from ..harness.tester import Tester
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION = MissionType.MISSION
MT = int(MISSION)
OTHER_TYPES = (MissionType.FENCE, MissionType.RALLY)


def _clear_once(t: Tester, mission_type: MissionType | int):
    """Send one MISSION_CLEAR_ALL; the vehicle's MISSION_ACK, or None within the reply timeout."""
    t.mark()
    t.send(m.clear_all_message(mission_type, t.target))
    return t.poll_for(ack(mission_type=int(mission_type)), t.timings.default_timeout)


def _count(t: Tester, mission_type: MissionType) -> int:
    got = procedures.download(t, mission_type)
    if got is None:
        raise PreconditionFailed(f"could not download the {mission_type.label} plan to check it")
    return got.count


def _stored_types(t: Tester, variant: int) -> dict[MissionType, list[MissionItem]]:
    """Put a plan of every type the vehicle stores on it: {type: plan}. A type refused as
    UNSUPPORTED is left out; the mission plan is required."""
    out = {}
    for mission_type in (MISSION, *OTHER_TYPES):
        items = plans.plan(mission_type, variant)
        frame = procedures.upload(t, items, mission_type)
        if frame is not None and frame.msg.type == MissionResult.UNSUPPORTED and mission_type is not MISSION:
            continue
        crossed = procedures.other_type_answer(t, mission_type) if frame is None else None
        if crossed is not None:
            raise NotApplicable(crossed)
        if frame is None or frame.msg.type != MissionResult.ACCEPTED:
            raise PreconditionFailed(f"setup: uploading a {mission_type.label} plan "
                                     + ("got no MISSION_ACK" if frame is None else
                                        f"was answered {procedures.result_name(frame.msg.type)}"))
        out[mission_type] = items
    return out


@check("MIS.CLR.01")
def clear_is_accepted(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=21), MISSION)
    frame = _clear_once(t, MISSION)
    if frame is None:
        raise ClauseFailed(f"MISSION_CLEAR_ALL was not answered within {t.reply_timeout:g} s; "
                           "expected MISSION_ACK MAV_MISSION_ACCEPTED")
    if frame.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed(f"MISSION_CLEAR_ALL was answered {procedures.result_name(frame.msg.type)}; "
                           "expected MAV_MISSION_ACCEPTED")


@check("MIS.CLR.02")
def clear_empties_the_plan(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(3, variant=22), MISSION)
    frame = _clear_once(t, MISSION)
    if frame is not None and frame.msg.type != MissionResult.ACCEPTED:
        raise PreconditionFailed(f"the clear was refused ({procedures.result_name(frame.msg.type)}), "
                                 "so nothing had to be cleared (MIS.CLR.01 judges that)")
    count = _count(t, MISSION)
    if count != 0:
        raise ClauseFailed(f"after MISSION_CLEAR_ALL{' was accepted' if frame else ''}, a download "
                           f"reported {count} items; expected 0")


@check("MIS.CLR.03")
def clear_leaves_other_types(s: Session) -> None:
    t = s.t
    stored = _stored_types(t, variant=23)
    others = [mt for mt in stored if mt is not MISSION]
    if not others:
        raise NotApplicable("the vehicle stores only mission plans (fence and rally were refused "
                            "as unsupported), so there is no other type to keep")
    for mission_type in others:   # the vehicle must hold them before the clear can be judged
        if not procedures.same_plan(procedures.stored(t, mission_type), stored[mission_type], t.form):
            raise PreconditionFailed(f"setup: the vehicle does not hold the {mission_type.label} plan "
                                     "it accepted (MIS.UP.04 judges that)")
    frame = _clear_once(t, MISSION)
    if frame is not None and frame.msg.type != MissionResult.ACCEPTED:
        raise PreconditionFailed(f"the clear was refused ({procedures.result_name(frame.msg.type)}) "
                                 "(MIS.CLR.01 judges that)")
    for mission_type in others:
        procedures.require_same_plan(procedures.stored(t, mission_type), stored[mission_type],
                                     f"after clearing the mission plan, the {mission_type.label} plan", t.form)


@check("MIS.CLR.04")
def clear_all_types(s: Session) -> None:
    t = s.t
    stored = _stored_types(t, variant=24)
    frame = _clear_once(t, MissionType.ALL)
    if frame is None:
        frame = t.poll_for(ack(), 0.0)   # some vehicles answer with another mission_type
    if frame is None:
        raise NotApplicable("MISSION_CLEAR_ALL for MAV_MISSION_TYPE_ALL was not answered, so it was "
                            "not accepted (clearing every type at once is optional)")
    if frame.msg.type != MissionResult.ACCEPTED:
        raise NotApplicable("MISSION_CLEAR_ALL for MAV_MISSION_TYPE_ALL was answered "
                            f"{procedures.result_name(frame.msg.type)} (clearing every type at once "
                            "is optional)")
    left = {mt.label: n for mt in stored if (n := _count(t, mt)) != 0}
    if left:
        raise ClauseFailed("MISSION_CLEAR_ALL for MAV_MISSION_TYPE_ALL was accepted, but downloads "
                           "still report " + ", ".join(f"{n} {label} items" for label, n in left.items())
                           + "; expected every plan type empty")


@check("MIS.CLR.05")
def repeated_clear_answered_again(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(2, variant=25), MISSION)
    first = _clear_once(t, MISSION)
    if first is None:
        raise ClauseFailed(f"MISSION_CLEAR_ALL was not answered within {t.reply_timeout:g} s")
    if first.msg.type != MissionResult.ACCEPTED:
        raise PreconditionFailed(f"the clear was refused ({procedures.result_name(first.msg.type)}) "
                                 "(MIS.CLR.01 judges that)")
    t.note("the GCS resends MISSION_CLEAR_ALL, as if the ACK had been lost")
    again = _clear_once(t, MISSION)
    if again is None:
        raise ClauseFailed(f"the repeated MISSION_CLEAR_ALL was not answered within "
                           f"{t.reply_timeout:g} s; expected MISSION_ACK MAV_MISSION_ACCEPTED again")
    if again.msg.type != MissionResult.ACCEPTED:
        raise ClauseFailed("the repeated MISSION_CLEAR_ALL was answered "
                           f"{procedures.result_name(again.msg.type)}; expected MAV_MISSION_ACCEPTED "
                           "(the plan is empty, as the GCS asked)")
