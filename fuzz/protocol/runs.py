"""What a protocol fuzz step runs: each operation a GCS started (`Run`, `ControlRun`), what
one step did that the oracle must hear about (`Group`), and an operation as a verdict names it."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.mission.items import PLAN_TYPE_BY_VALUE, MissionType
from mavconform.reference_impl.mission.results import OperationResult

from .gcs import FuzzGcs
from .versions import Plan, Write


@dataclass
class Run:
    gcs: FuzzGcs
    name: str
    op: dict[str, Any]
    done: int                     # len(gcs.results) when it started
    started: float
    plans: tuple[Plan, ...] = ()  # upload: what the vehicle may store if it applies it
    result: OperationResult | None = None
    # Its GCS sent stray messages meanwhile: the vehicle's replies to those carry no
    # correlation id and may be taken for this operation's answer, so its result says
    # nothing definite about the vehicle (a clear "refused" by a late reply to a stray).
    untrusted: bool = False

    @property
    def finished(self) -> bool:
        return len(self.gcs.results) > self.done


@dataclass
class ControlRun:
    """One operator-control operation of a GCS's control client, waited for like `Run`."""

    gcs: FuzzGcs
    name: str
    op: dict[str, Any]
    done: int                     # len(gcs.control_results) when it started
    started: float
    bound: float                  # `control.operation_bound`

    @property
    def finished(self) -> bool:
        return len(self.gcs.control_results) > self.done


@dataclass
class Group:
    """What one step did that the oracle must hear about."""

    runs: list[Run] = field(default_factory=list)
    writes: list[Write] = field(default_factory=list)
    strays: bool = False   # raw messages went out: their replies may still be on the way
    controls: list[ControlRun] = field(default_factory=list)


def describe_op(op: dict[str, Any]) -> str:
    kind = op.get("op")
    label = type_label(op.get("type"))
    if kind == "upload":
        return f"an upload of {len(op['items'])} {label} items" + (" (float)" if op.get("float") else "")
    if kind == "download":
        return f"a download of the {label} plan"
    if kind == "clear":
        return f"a clear of the {label} plan" + ("s" if op.get("type") == MissionType.ALL else "")
    if kind == "set_current":
        how = "MAV_CMD_DO_SET_MISSION_CURRENT" if op.get("command") else "MISSION_SET_CURRENT"
        return f"a set-current to {op.get('seq')} ({how})"
    if kind == "control":
        action = op.get("action")
        if action == "request":
            return (f"a request for control (takeover {'allowed' if op.get('allow') else 'disallowed'}, "
                    f"timeout {op.get('timeout', cm.DEFAULT_REQUEST_TIMEOUT):g} s"
                    + (", waiting for the owner)" if op.get("wait_for_owner") else ")"))
        return {"release": "a release of control", "allow": "allowing takeover",
                "disallow": "disallowing takeover"}.get(action, f"control {action}")
    if kind == "gcs_loss":
        return f"{op.get('seconds')} s without HEARTBEAT"
    return str(kind)


def type_label(value: Any) -> str:
    if value == MissionType.ALL:
        return "all"
    t = PLAN_TYPE_BY_VALUE.get(value)
    return t.label if t is not None else str(value)
