"""Link faults drawn by Hypothesis: `fault_models` for the tool's own property tests (a
FaultModel, partitions in time included), `fault_schedules` for the protocol fuzzer (JSON-safe
data a saved case replays; fuzz/protocol/faults.py turns one into FaultModels)."""

from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

from mavconform.reference_impl.net import FaultModel


partition = st.tuples(st.floats(0, 30), st.floats(0.5, 12)).map(lambda p: (p[0], p[0] + p[1]))


@st.composite
def fault_models(draw, max_loss: float = 0.3) -> FaultModel:
    """Loss, duplication, reordering, delay and jitter, and sometimes a partition in time."""
    return FaultModel(
        partitions=tuple(sorted(draw(st.lists(partition, max_size=2)))),
        loss=draw(st.floats(0, max_loss)),
        duplicate=draw(st.floats(0, 0.2)),
        reorder=draw(st.floats(0, 0.2)),
        reorder_delay=draw(st.floats(0.0, 0.1)),
        delay=draw(st.floats(0, 0.05)),
        jitter=draw(st.floats(0, 0.05)),
    )


MISSION_MESSAGES = ("MISSION_ACK", "MISSION_COUNT", "MISSION_REQUEST_INT", "MISSION_REQUEST",
                    "MISSION_ITEM_INT", "MISSION_ITEM", "MISSION_REQUEST_LIST",
                    "MISSION_CLEAR_ALL", "MISSION_CURRENT", "MISSION_SET_CURRENT")
_prob = st.floats(0, 1).map(lambda p: round(p, 3))


@st.composite
def fault_schedules(draw, max_loss: float = 0.3, max_burst: float = 30.0) -> dict[str, Any]:
    """One direction's faults: random loss, duplication, reordering, delay, jitter and
    corruption; bursts (short total outages, `[start, length]` seconds after the schedule
    is set); scripted drops ("the 2nd MISSION_ACK", "MISSION_ITEM_INT from the 3rd on");
    and a cut: from the nth message called NAME on, the next `span` messages are all lost
    (a partition that begins at a chosen message). Keys at their zero value are left out."""
    spec = {
        "loss": round(draw(st.floats(0, max_loss)), 3),
        "duplicate": round(draw(st.floats(0, 0.2)), 3),
        "reorder": round(draw(st.floats(0, 0.2)), 3),
        "reorder_delay": round(draw(st.floats(0, 0.2)), 3),
        "delay": round(draw(st.floats(0, 0.05)), 3),
        "jitter": round(draw(st.floats(0, 0.05)), 3),
        "corrupt": round(draw(st.floats(0, 0.05)), 3),
        "bursts": [[round(s, 2), round(n, 2)] for s, n in draw(st.lists(
            st.tuples(st.floats(0, min(20.0, max_burst)), st.floats(0.05, max_burst)), max_size=2))],
        "drops": draw(st.lists(st.fixed_dictionaries({
            "name": st.sampled_from(MISSION_MESSAGES), "nth": st.integers(1, 6),
            "onwards": st.booleans()}), max_size=2)),
        "cut": draw(st.one_of(st.none(), st.fixed_dictionaries({
            "name": st.sampled_from(MISSION_MESSAGES), "nth": st.integers(1, 6),
            "span": st.integers(1, 40)}))),
    }
    return {k: v for k, v in spec.items() if v}
