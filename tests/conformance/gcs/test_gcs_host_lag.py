"""The host-lag guard in the GCS suite: the reference GCS on the 4x clock over real UDP, with
a host that oversleeps every idle wait of the first operation, resends MISSION_COUNT late by
the host's fault. As judged, MIS.G.TO.01 does not pass; judged on time, its shared operation
is made again and the clause passes. The stalls are clock jumps, not sleeps."""

from __future__ import annotations

import pytest

from mavconform.conformance.catalogue import select
from mavconform.conformance.clause import Role
from mavconform.conformance.gcs import harness as harness_module
from mavconform.conformance.gcs import stage as stage_module
from mavconform.conformance.gcs.adapters import NodeAdapter
from mavconform.conformance.gcs.harness import GcsHarness
from mavconform.conformance.gcs.runner import run_gcs_clauses, run_one
from mavconform.conformance.host_lag import LAG_TOLERANCE
from mavconform.conformance.outcome import Outcome
from mavconform.reference_impl.net import UdpDriver

from ...net.nodes import JumpingClock

pytestmark = pytest.mark.udp
STALL = 4.0   # clock seconds per idle wait: the 1.5 s resend timer then looks over 3 s, past the bound


def _oversleeping_first_operation(monkeypatch) -> dict[str, int]:
    """Every UdpDriver of the first operation's stage oversleeps each idle wait by STALL."""
    state = {"stalls": 0, "operations": 0}

    class Oversleeping(UdpDriver):
        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            first = state["operations"] == 0
            select = self._selector.select

            def oversleep(timeout=None):
                events = select(timeout)
                if first and not events:
                    state["stalls"] += 1
                    self.clock.stall(STALL)
                return events
            self._selector.select = oversleep

        def close(self) -> None:
            state["operations"] += 1
            super().close()

    monkeypatch.setattr(harness_module, "ScaledClock", JumpingClock)
    monkeypatch.setattr(stage_module, "UdpDriver", Oversleeping)
    return state


def test_a_host_that_oversleeps_fails_the_reference_gcs_unless_judged_on_time(monkeypatch):
    state = _oversleeping_first_operation(monkeypatch)
    [clause] = select("MIS.G.TO.01", role=Role.GCS)
    h = GcsHarness(NodeAdapter(), clock_speed=4.0)
    as_judged = run_one(h, clause)
    assert state["stalls"] and as_judged.outcome is not Outcome.PASS, as_judged.detail
    assert h.take_lag() > STALL - LAG_TOLERANCE

    state.update(stalls=0, operations=0)
    h = GcsHarness(NodeAdapter(), clock_speed=4.0)
    run = run_gcs_clauses(h, [clause])
    [result] = run.results
    assert state["stalls"] and result.outcome is Outcome.PASS, result.detail
    assert result.first_attempt["outcome"] == as_judged.outcome.value
    assert result.first_attempt["host_lag_s"] > STALL - LAG_TOLERANCE
