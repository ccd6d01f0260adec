"""What the GCS checks share: the plans and operations they have the GCS do, and how they judge.

Operations several clauses judge alike (a clean upload, a vehicle silent to MISSION_COUNT) are
run once per run (`GcsHarness.observe`). Every plan is small and distinct
(conformance/harness/plans.py), so a wrong item can never match by accident.
"""

from __future__ import annotations

from dataclasses import replace
from decimal import Decimal
from typing import Any

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType

from ...harness import plans
from ...harness.measured import Measured
from ...outcome import ClauseFailed, PreconditionFailed
from ..harness import GcsHarness, Operation
from ..job import Job
from ..scripted_vehicle import ITEMS, REQUESTS, Deaf, Event, Swap, named

MISSION, FENCE, RALLY = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY
N = 3                           # items in the plans the checks move
DEFAULT_TIMEOUT = 1.5           # s, seed 000:533
MAX_RETRIES = 5                 # seed 000:537
ACCEPTED_TIMEOUT = (0.5 * DEFAULT_TIMEOUT, 2 * DEFAULT_TIMEOUT)   # MIS.UP.07's tolerance: half to twice
KEPT_OPEN = 0.5 * DEFAULT_TIMEOUT * (MAX_RETRIES + 1)             # half the spec's whole retry sequence
REANSWER_WITHIN = 0.5 * DEFAULT_TIMEOUT   # s: an answer, not the GCS's own resend at its timeout
WATCH_AFTER = 1.5 * DEFAULT_TIMEOUT   # s watched after an operation ended, for anything still sent
FLOAT_XY_SLACK = 64             # degE7: what float32 degrees may lose near 47 degrees (ulp ~38)
TYPED = ("MISSION_COUNT", "MISSION_REQUEST_LIST", "MISSION_ACK", "MISSION_CLEAR_ALL") + ITEMS + REQUESTS
MISSION_NAMES = TYPED + ("MISSION_SET_CURRENT",)


# --- the operations ---------------------------------------------------------------------------
def truncation_prone(start: int) -> int:
    """The first degE7 value from `start` that `int(degrees * 1e7)` gets wrong (1e-7 degree
    short), though the degrees are its exact decimal: about 6 % of coordinates are. A GCS
    that converts with int() instead of round() sends them changed (MAVProxy does)."""
    value = start
    while int(float(Decimal(value).scaleb(-7)) * 1e7) == value:
        value += 1
    return value


def plan_of(mt: MissionType = MISSION) -> list[MissionItem]:
    """The plan of that type. A mission's coordinates are truncation-prone, and its first
    item is marked current, as a GCS's plan files have it (MAVSDK refuses a mission with no
    current item before sending anything)."""
    if mt is not MISSION:
        return plans.plan(mt)
    items = [replace(i, x=truncation_prone(i.x), y=truncation_prone(i.y)) for i in plans.mission(N)]
    return [replace(items[0], current=1)] + items[1:]


def upload_job(mt: MissionType = MISSION) -> Job:
    return Job("upload", mt, tuple(plan_of(mt)))


def download_job(mt: MissionType = MISSION) -> Job:
    return Job("download", mt)


def stored(mt: MissionType = MISSION, items: list[MissionItem] | None = None) -> dict[MissionType, list]:
    return {mt: plan_of(mt) if items is None else items}


def clean_upload(h: GcsHarness) -> Operation:
    return h.observe("clean upload", upload_job())


def clean_download(h: GcsHarness) -> Operation:
    return h.observe("clean download", download_job(), plans=stored())


def clean_clear(h: GcsHarness) -> Operation:
    return h.observe("clean clear", Job("clear", MISSION), plans=stored())


def silent_to_count(h: GcsHarness) -> Operation:
    return h.observe("silent to MISSION_COUNT", upload_job(),
                     rules=[Deaf(named("MISSION_COUNT"), times=None, what="every MISSION_COUNT")])


# --- judging helpers --------------------------------------------------------------------------
def fail(h: GcsHarness, op: Operation, event: Event | None, text: str) -> ClauseFailed:
    h.decide(op, event)
    return ClauseFailed(text)


def mission_sent(op: Operation) -> list[Event]:
    """What the GCS sent of the Mission Protocol (not its commands: MAVSDK asks for
    AUTOPILOT_VERSION on connect, MAVProxy for the home position every 2 s)."""
    return [e for e in op.sent() if e.msg._type.startswith("MISSION_")]


def first_mission_message(h: GcsHarness, op: Operation) -> Event:
    """The first Mission Protocol message the GCS sent: what an operation must start with."""
    sent = mission_sent(op)
    if not sent:
        raise fail(h, op, None, f"the GCS sent no mission message ({op.result.line()})")
    return sent[0]


def names(events: list[Event]) -> str:
    shown = ", ".join(short(e.msg) for e in events[:8])
    return (shown + (", ..." if len(events) > 8 else "")) or "nothing"


def short(msg: Any) -> str:
    seq = getattr(msg, "seq", None)
    return msg._type + (f" {seq}" if seq is not None and msg._type != "MISSION_COUNT" else "")


def item_diff(got: MissionItem | Any, want: MissionItem, slack: int = 0) -> str | None:
    """How a sent item differs from the planned one (None: it does not); `current` is the
    GCS's to set, and x/y may differ by `slack` (the float form's rounding)."""
    if not isinstance(got, MissionItem):
        return "its x/y cannot be an int32"
    diffs = []
    for name in ("frame", "command", "autocontinue"):
        if getattr(got, name) != getattr(want, name):
            diffs.append(f"{name} {getattr(got, name)} (planned {getattr(want, name)})")
    for name in ("param1", "param2", "param3", "param4", "z"):
        a, b = getattr(got, name), getattr(want, name)
        if not (a == b or (a != a and b != b)):
            diffs.append(f"{name} {a:g} (planned {b:g})")
    for name in ("x", "y"):
        if abs(getattr(got, name) - getattr(want, name)) > slack:
            diffs.append(f"{name} {getattr(got, name)} (planned {getattr(want, name)})")
    return ", ".join(diffs) or None


def plan_diff(got: tuple[MissionItem, ...] | None, want: list[MissionItem]) -> str | None:
    if got is None:
        return "the GCS reported no items"
    if len(got) != len(want):
        return f"{len(got)} items, the vehicle holds {len(want)}"
    for a, b in zip(got, want):
        diff = item_diff(a, b)
        if diff:
            return f"item {b.seq}: {diff}"
    return None


def require_success(h: GcsHarness, op: Operation, what: str) -> None:
    if not op.result.ok:
        raise fail(h, op, op.sent()[-1] if op.sent() else None, f"{what}, but {op.result.line()}")


def require_failure(h: GcsHarness, op: Operation, what: str) -> None:
    if not op.result.ended:
        raise fail(h, op, op.sent()[-1] if op.sent() else None,
                   f"{what}; the GCS never ended the operation ({op.result.said})")
    if op.result.ok:
        raise fail(h, op, op.sent()[-1] if op.sent() else None, f"{what}, but {op.result.line()}")


def answer_after(op: Operation, request: Event, names_: tuple[str, ...]) -> Event | None:
    """The first item the GCS sent after `request` with the request's seq."""
    return next((e for e in op.after(request, *names_) if e.msg.seq == request.msg.seq), None)


def first_told(op: Operation, *names_: str, **fields: Any) -> Event | None:
    return next((e for e in op.told(*names_) if all(getattr(e.msg, k) == v for k, v in fields.items())), None)


def scripted(op: Operation, what: str, *names_: str, **fields: Any) -> Event:
    """The vehicle's scripted move the check is about; if the GCS never led the vehicle to
    it, the clause is undecided, not failed (another clause judges what the GCS did)."""
    event = first_told(op, *names_, **fields)
    if event is None:
        raise PreconditionFailed(f"the GCS never led the vehicle to send {what}; it sent "
                                 f"{names(mission_sent(op))} ({op.result.line()})")
    return event

def download_ended_by(h: GcsHarness, code: MissionResult) -> str:
    """A download whose item 1 the vehicle answers with MISSION_ACK `code`: the GCS must send
    nothing more for it and report it failed."""
    op = h.run(download_job(), plans=stored(), after=WATCH_AFTER, rules=[Swap(
        named(*ITEMS, seq=1), what=f"MISSION_ACK {code.name}",
        instead=lambda reply, v: [m.ack_message(code, MISSION, v.target)])])
    ack = scripted(op, f"its {code.name}", "MISSION_ACK")
    later = op.after(ack, *REQUESTS, *ITEMS, "MISSION_REQUEST_LIST", "MISSION_COUNT")
    if later:
        raise fail(h, op, later[0], f"{short(later[0].msg)} was sent after the vehicle's {code.name}")
    require_failure(h, op, f"the vehicle answered with MISSION_ACK {code.name}")
    h.decide(op, ack)
    return f"nothing sent after {code.name}; {op.result.line()}"


def resent(h: GcsHarness, op: Operation, sent: list[Event], what: str, unanswered: str) -> Measured:
    """The clause holds when `what` went out again after `unanswered` (and the operation then
    succeeded): `sent` is every copy the GCS sent, in order."""
    if len(sent) < 2:
        raise fail(h, op, sent[0] if sent else None, f"{what} was sent {len(sent)} time(s): never again "
                                                     f"when {unanswered} ({op.result.line()})")
    require_success(h, op, f"{what} was resent")
    h.decide(op, sent[1])
    return Measured(f"{what} resent after <s> s", s=f"{sent[1].t - sent[0].t:.3f}")
