"""The operator-control steps of the protocol fuzzer (--operator-control): GCS A or B requests,
releases, allows or disallows takeover, falls silent for a while, or operates on its own.
Their strays are in stray_messages.py.
"""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from .strategies import operations, seconds


CONTROL_ACTIONS = ("request", "release", "allow", "disallow")
OWNER_ANSWERS = (None, "allow", "release", "refuse")


def control_step(max_timeout: float = 10.0, actions: tuple[str, ...] = CONTROL_ACTIONS
                 ) -> st.SearchStrategy[dict[str, Any]]:
    """GCS A or B asks for control (param 2: allow takeover; param 3: its timeout; with
    `wait_for_owner` a refusal waits for the owner's answer), releases it, or, as the owner,
    allows or disallows takeover. `answer` is what the owner answers a request the vehicle
    forwards to it meanwhile."""
    timeouts = [t for t in (3.0, 5.0, 10.0) if t <= max(3.0, max_timeout)]
    return st.fixed_dictionaries({
        "op": st.just("control"), "gcs": st.sampled_from(["a", "b"]),
        "action": st.sampled_from(actions), "allow": st.booleans(),
        "timeout": st.sampled_from(timeouts), "wait_for_owner": st.booleans(),
        "answer": st.sampled_from(OWNER_ANSWERS)})


def gcs_loss_step(max_silence: float = 12.0, max_wait: float = 20.0) -> st.SearchStrategy[dict[str, Any]]:
    """GCS A or B sends no HEARTBEAT for `seconds` (then beats again); `wait` seconds pass.
    Half the draws are 7 s, beyond the 5 s owner loss plus a status period, so a silent
    owner's loss is met as often as a short gap it must survive (not where the bounds are
    shorter: over UDP, where time is real)."""
    lost = 7.0
    if max_silence < lost or max_wait < lost:   # over UDP: short gaps only, no emphasis
        return st.fixed_dictionaries({"op": st.just("gcs_loss"), "gcs": st.sampled_from(["a", "b"]),
                                      "seconds": seconds(max_silence), "wait": seconds(max_wait)})
    return st.fixed_dictionaries({
        "op": st.just("gcs_loss"), "gcs": st.sampled_from(["a", "b"]),
        "seconds": st.one_of(st.just(lost), seconds(max_silence)),
        "wait": st.one_of(st.just(lost), seconds(max_wait))})


def b_operation(max_items: int = 20) -> st.SearchStrategy[dict[str, Any]]:
    """An operation of GCS B on its own (with operator control: maybe not the owner's)."""
    return operations(max_items).map(lambda op: {**op, "gcs": "b"})
