"""Property: any plans, any faults - every operation ends once, and the vehicle never lies.

Random plans of all three types, random fault models on both directions (loss up to 30 %,
duplication, reordering, delay and jitter), client <-> server over SimNetwork in virtual
time. After every operation:
- exactly one result, and both ends idle again in bounded time;
- success: the vehicle holds exactly what was uploaded / what was downloaded is what it holds;
- failure: the vehicle holds exactly the old plan (atomicity), except that when the result
  says `outcome_unknown` (final ACK never arrived) it holds the old or the new plan whole;
- no message was retried more often than the limit, on either end, and the traffic of an
  operation stays linear in the size of the plan (no duplicate storms).
"""

from __future__ import annotations

from hypothesis import given
from hypothesis import strategies as st

from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType as T, renumber
from mavconform.reference_impl.mission.transitions import SlotState
from mavconform.reference_impl.net import FaultModel

from ..rigs import vehicle_and_gcs
from ..strategies import fault_models, plan_items

LIMIT = 5
IDLE_BOUND = 30.0   # virtual seconds for both ends to settle after a result


def operations():
    t = st.sampled_from(PLAN_TYPES)
    upload = st.tuples(st.just("upload"), t).flatmap(
        lambda ut: st.tuples(st.just(ut[0]), st.just(ut[1]), plan_items(ut[1], max_size=12)))
    download = st.tuples(st.just("download"), t)
    clear = st.tuples(st.just("clear"), st.sampled_from((*PLAN_TYPES, T.ALL)))
    cancel_after = st.floats(0.0, 3.0)
    cancelled_upload = st.tuples(upload, cancel_after).map(lambda u: ("upload", *u[0][1:], u[1]))
    cancelled_download = st.tuples(download, cancel_after).map(lambda d: (*d[0], d[1]))
    return st.lists(st.one_of(upload, upload, download, clear, cancelled_upload, cancelled_download),
                    min_size=1, max_size=4)


def run_operation(net, gcs, session, op):
    """Run `op` to its result; an op with a cancel time is cancelled then if still running."""
    kind, t = op[0], op[1]
    if kind == "upload":
        start = lambda now: gcs.upload(t, op[2], now)  # noqa: E731
        cancel_after = op[3] if len(op) > 3 else None
    else:
        start = lambda now: gcs.download(t, now)  # noqa: E731
        cancel_after = op[2] if len(op) > 2 else None
    if cancel_after is None:
        return session.upload(t, op[2]) if kind == "upload" else session.download(t)
    done = len(gcs.results)
    start(net.clock.now())
    if not net.run_until(lambda: len(gcs.results) > done, timeout=cancel_after):
        gcs.cancel(net.clock.now())
    assert net.run_until(lambda: len(gcs.results) > done, timeout=120)
    return gcs.results[done]


def build(seed: int, up: FaultModel, down: FaultModel):
    r = vehicle_and_gcs(seed=seed, up=up, down=down, discovery=60)
    return r.net, r.vehicle, r.gcs, r.session


@given(seed=st.integers(0, 2**32 - 1), up=fault_models(), down=fault_models(), ops=operations())
def test_operations_under_faults_keep_the_protocol_invariants(seed, up, down, ops):
    net, vehicle, gcs, session = build(seed, up, down)
    store = vehicle.store
    for op in ops:
        before = store.snapshot()
        n_results = len(gcs.results)
        sent_before = sum(link.sent for link in net.stats.values())
        t_before = net.clock.now()
        if op[0] == "clear":
            result = session.clear(op[1])
        else:
            result = run_operation(net, gcs, session, op)
        settled = lambda: vehicle.server.is_idle() and not gcs.busy and net.in_flight() == 0  # noqa: E731
        assert net.run_until(settled, timeout=IDLE_BOUND), f"not idle {IDLE_BOUND}s after {result.summary()}"
        assert len(gcs.results) == n_results + 1, "an operation must end with exactly one result"
        # Traffic stays linear in the plan: per item a request and an answer, each resent at
        # most max_retries times, doubled for duplication; plus 4 stream messages a second.
        n = max(len(op[2]) if op[0] == "upload" else 0, *(len(p) for p in before.values()))
        sent = sum(link.sent for link in net.stats.values()) - sent_before
        bound = 2 * 2 * (n + 2) * (LIMIT + 1) + 5 * (net.clock.now() - t_before) + 10
        assert sent <= bound, f"{sent} datagrams for {result.summary()} (bound {bound:.0f})"
        assert result.max_consecutive_retries <= LIMIT
        after = store.snapshot()
        touched = set(PLAN_TYPES) if op[1] is T.ALL else {op[1]}
        for other in set(PLAN_TYPES) - touched:
            assert after[other] == before[other], f"{op[0]} of {op[1].name} changed {other.name}"
        if op[0] == "upload":
            t, items = op[1], op[2]
            new = tuple(renumber(items, t))
            if result.ok:
                assert after[t] == new
            elif result.outcome_unknown:
                assert after[t] in (before[t], new), "upload left a mix of old and new"
            else:
                assert after[t] == before[t], f"failed upload ({result.summary()}) changed the plan"
        elif op[0] == "download":
            assert before == after
            if result.ok:
                assert result.items == after[op[1]]
        else:
            for t in touched:
                if result.ok:
                    assert after[t] == ()
                elif result.outcome_unknown:
                    assert after[t] in (before[t], ())
                else:
                    assert after[t] == before[t]
    assert vehicle.server.stats.max_consecutive_retries <= LIMIT
    assert all(vehicle.server.state(t) is SlotState.IDLE for t in PLAN_TYPES)
