"""The host-lag guard against the builtin vehicle on its 4x clock over real UDP: a host that
oversleeps while the vehicle is being watched makes MIS.UP.06 fail, though the vehicle is
right; judged on time, the clause is run again and passes. The stall is a clock that jumps,
as a process descheduled for four seconds finds it, not a sleep."""

from __future__ import annotations

import pytest

from mavconform.conformance import session as session_module
from mavconform.conformance.catalogue import BY_ID
from mavconform.conformance.host_lag import LAG_TOLERANCE, judged_on_time
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import run_one
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.mission.transitions import SlotState

from ..net.nodes import JumpingClock

pytestmark = pytest.mark.udp
STALL = 4.0   # clock seconds: longer than the 3 s MIS.UP.06 waits for a silent vehicle to ask again


def _stall_once_while_the_vehicle_waits_for_item_2(s: Session) -> dict[str, bool]:
    """The first time the driver wakes from an idle wait in MIS.UP.06 while the vehicle waits
    for item 2 of the silent upload (it has asked once; its item timeout is running), the
    clock jumps STALL seconds: the host overslept."""
    server, selector, stalled = s.vehicle.server, s.driver._selector, {"done": False}
    select = selector.select

    def oversleeping(timeout=None):
        events = select(timeout)
        if not events and not stalled["done"] and s.current_clause == "MIS.UP.06" and any(
                slot.state is SlotState.RECEIVING and slot.expected == 2 for slot in server._slot_list):
            stalled["done"] = True
            s.driver.clock.stall(STALL)
        return events
    selector.select = oversleeping
    return stalled


@pytest.mark.parametrize("guarded", [False, True], ids=["as-judged", "judged-on-time"])
def test_a_host_stall_fails_a_right_vehicle_unless_the_clause_is_judged_on_time(monkeypatch, guarded):
    monkeypatch.setattr(session_module, "ScaledClock", JumpingClock)
    with Session(parse_target("builtin:spec")) as s:
        assert s.clock_speed == 4.0 and isinstance(s.driver.clock, JumpingClock)
        s.discover()
        stalled = _stall_once_while_the_vehicle_waits_for_item_2(s)
        clause = BY_ID["MIS.UP.06"]
        s.driver.take_lag()
        result = judged_on_time(s, clause, run_one) if guarded else run_one(s, clause)
        assert stalled["done"]
        if not guarded:
            # the probe sees it: the vehicle's re-request fell inside the stall
            assert result.outcome is Outcome.FAIL and "requested 1 time(s)" in result.detail
            assert s.driver.take_lag() > STALL - LAG_TOLERANCE
        else:
            assert result.outcome is Outcome.PASS, result.detail
            assert result.first_attempt["outcome"] == "fail"
            assert result.first_attempt["host_lag_s"] > STALL - LAG_TOLERANCE
            assert result.host_lag_s is None   # the second attempt kept the clock
