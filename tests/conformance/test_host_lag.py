"""conformance/host_lag.py: a clause that did not pass while the host lagged is run again,
and a second lagged non-pass is an error naming the host, never a verdict on the target."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from mavconform.conformance.document import _volatile
from mavconform.conformance.host_lag import LAG_TOLERANCE, judged_on_time
from mavconform.conformance.outcome import Outcome
from mavconform.conformance.runner import DecidedResult

LATE, ON_TIME = LAG_TOLERANCE * 5, LAG_TOLERANCE / 2


class ScriptedDriver:
    """take_lag() answers from a script: one value per attempt (the first call, before the
    first attempt, resets)."""

    def __init__(self, lags: list[float]) -> None:
        self.lags = [0.0] + lags

    def take_lag(self) -> float:
        return self.lags.pop(0)


FORGOTTEN: list[float] = []


def _judge(outcomes: list[Outcome], lags: list[float], speed: float = 1.0) -> tuple[DecidedResult, int]:
    FORGOTTEN.clear()
    session = SimpleNamespace(take_lag=ScriptedDriver(lags).take_lag, clock_speed=speed,
                              forget_lagged=FORGOTTEN.append)
    ran = []

    def run_one(_session, clause):
        ran.append(clause)
        outcome = outcomes[len(ran) - 1]
        return DecidedResult("MIS.UP.06", outcome, f"attempt {len(ran)}: {outcome.value}", 1.0, [],
                             decided_by=0)
    return judged_on_time(session, "MIS.UP.06", run_one), len(ran)


def test_a_fail_while_the_host_kept_up_stands_and_is_run_once():
    result, runs = _judge([Outcome.FAIL], [ON_TIME])
    assert (result.outcome, runs, result.first_attempt, result.host_lag_s) == (Outcome.FAIL, 1, None, None)
    assert FORGOTTEN == []


def test_a_fail_under_lag_is_run_again_and_the_second_attempt_decides():
    result, runs = _judge([Outcome.FAIL, Outcome.PASS], [LATE, ON_TIME])
    assert (result.outcome, runs, result.detail) == (Outcome.PASS, 2, "attempt 2: pass")
    assert result.first_attempt == {"outcome": "fail", "host_lag_s": round(LATE, 3)}
    assert FORGOTTEN == [LAG_TOLERANCE]   # observations made under lag are made again


def test_a_genuine_fail_survives_the_rerun():
    result, runs = _judge([Outcome.FAIL, Outcome.FAIL], [LATE, ON_TIME])
    assert (result.outcome, runs, result.detail) == (Outcome.FAIL, 2, "attempt 2: fail")
    assert result.first_attempt["outcome"] == "fail" and result.host_lag_s is None


@pytest.mark.parametrize("first", [Outcome.FAIL, Outcome.NOT_APPLICABLE, Outcome.ERROR])
def test_two_lagged_attempts_that_did_not_pass_are_the_hosts_error(first: Outcome):
    result, runs = _judge([first, Outcome.FAIL], [LATE, LATE * 2], speed=4.0)
    assert (result.outcome, runs, result.decided_by) == (Outcome.ERROR, 2, None)
    assert result.detail.startswith("not judged: the host was too busy")
    assert f"{LATE * 2:.2f} s behind" in result.detail and f"ended {first.value} and fail" in result.detail
    assert "--clock-speed 1" in result.detail
    assert result.host_lag_s == round(LATE * 2, 3)
    # the report keeps the numbers volatile: the stable detail is the same whatever the lag was
    clause = {"detail": result.detail, "exchange": [], "decided_by": None}
    entry = _volatile(result, clause)
    assert "<lag>" in clause["detail"] and entry["detail"]["lag"] == f"{LATE * 2:.2f}"
    assert entry["first_attempt"] == {"outcome": first.value, "host_lag_s": round(LATE, 3)}


def test_at_real_time_the_error_does_not_suggest_a_slower_clock():
    result, _ = _judge([Outcome.FAIL, Outcome.FAIL], [LATE, LATE])
    assert result.outcome is Outcome.ERROR and "--clock-speed" not in result.detail


def test_a_pass_under_lag_stands_with_the_lag_noted():
    result, runs = _judge([Outcome.PASS], [LATE])
    assert (result.outcome, runs, result.host_lag_s, result.first_attempt) == (Outcome.PASS, 1, round(LATE, 3), None)


def test_a_skip_is_not_run_again():
    result, runs = _judge([Outcome.SKIPPED], [LATE])
    assert (result.outcome, runs) == (Outcome.SKIPPED, 1)
