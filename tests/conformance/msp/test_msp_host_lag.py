"""The host-lag guard in the MSP suite: builtin:msp over real TCP loopback, with a host that
stalls just as the flight controller's reply to an unknown command is on its way. As judged,
MSP.FR.03 fails (no reply within the bound); judged on time, it is run again and passes. The
stall is a clock jump, not a sleep."""

from __future__ import annotations

import pytest

from mavconform.conformance.host_lag import LAG_TOLERANCE, judged_on_time
from mavconform.conformance.msp import session as msp_session
from mavconform.conformance.msp.clauses import MSP_CLAUSES
from mavconform.conformance.msp.runner import discover, run_one
from mavconform.conformance.msp.session import MspSession
from mavconform.conformance.msp.target import parse_msp_target
from mavconform.conformance.msp.tester import REPLY_TIMEOUT
from mavconform.conformance.outcome import Outcome
from mavconform.reference_impl.net import UdpDriver

from ...net.nodes import JumpingClock

pytestmark = pytest.mark.udp
STALL = REPLY_TIMEOUT * 2


def _stalling_driver(monkeypatch) -> dict[str, bool]:
    """A driver on a JumpingClock that, once `armed`, jumps STALL seconds the first time a
    wait ends with something to read: the host stalled as the exchange was under way."""
    state = {"armed": False, "stalled": False}

    class Stalling(UdpDriver):
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(JumpingClock(), *args[1:], **kwargs)
            select = self._selector.select

            def stalling(timeout=None):
                events = select(timeout)
                if events and state["armed"] and not state["stalled"]:
                    state["stalled"] = True
                    self.clock.stall(STALL)
                return events
            self._selector.select = stalling

    monkeypatch.setattr(msp_session, "UdpDriver", Stalling)
    return state


@pytest.mark.parametrize("guarded", [False, True], ids=["as-judged", "judged-on-time"])
def test_a_host_stall_fails_a_right_flight_controller_unless_judged_on_time(monkeypatch, guarded):
    state = _stalling_driver(monkeypatch)
    [clause] = [c for c in MSP_CLAUSES if c.id == "MSP.FR.03"]
    with MspSession(parse_msp_target("builtin:msp")) as session:
        assert isinstance(session.driver.clock, JumpingClock)
        discover(session)
        session.take_lag()
        state["armed"] = True
        result = judged_on_time(session, clause, run_one) if guarded else run_one(session, clause)
        assert state["stalled"]
        if not guarded:
            assert result.outcome is Outcome.FAIL and "got no reply" in result.detail
            # the driver meant to be back when the reply's bound ran out: it was that much later
            assert session.take_lag() > STALL - REPLY_TIMEOUT - LAG_TOLERANCE
        else:
            assert result.outcome is Outcome.PASS, result.detail
            assert result.first_attempt == {"outcome": "fail",
                                             "host_lag_s": pytest.approx(STALL - REPLY_TIMEOUT, abs=0.2)}
