"""Where the protocol fuzzer's wall time goes over UDP (bench/protocol_fuzz_udp.py --phases):
exclusive time per Runner / World phase, the same per call path with run_until split into CPU
and select(), and the wire ledger that tells forced waits from turnaround. Patched into the
fuzzer's classes only while the bench runs (`instrumented`)."""

from __future__ import annotations

import contextlib
import time
from collections import defaultdict
from typing import Any, Callable, Iterator

from mavconform.fuzz.protocol import steps as steps_mod
from mavconform.fuzz.protocol import world as world_mod
from mavconform.fuzz.protocol.gcs import FuzzGcs
from mavconform.reference_impl.net import UdpDriver

FAST = 0.02        # s: a reply later than this after the previous cut waited on a timer
STREAMED = {0, 33, 42}   # HEARTBEAT, GLOBAL_POSITION_INT, MISSION_CURRENT (msg ids)


class Phases:
    """Exclusive wall time per phase path (a stack of wrapped calls), and the wire ledger."""

    def __init__(self) -> None:
        self.stack: list[str] = []
        self.excl: dict[tuple[str, ...], float] = defaultdict(float)
        self.calls: dict[tuple[str, ...], int] = defaultdict(int)
        self.select: dict[tuple[str, ...], list[float]] = defaultdict(lambda: [0.0, 0.0, 0])
        self.wire: dict[str, float] = defaultdict(float)
        self.wire_n: dict[str, int] = defaultdict(int)
        self.last = time.perf_counter()
        self.cut: float | None = None    # inside run_until: time of the last cut

    def _charge(self, now: float) -> None:
        self.excl[tuple(self.stack)] += now - self.last
        self.last = now

    def push(self, name: str) -> None:
        self._charge(time.perf_counter())
        self.stack.append(name)
        self.calls[tuple(self.stack)] += 1

    def pop(self) -> None:
        self._charge(time.perf_counter())
        self.stack.pop()

    # the wire ledger: pieces of run_until time, each named by what ended it
    def where(self) -> str:
        s = self.stack
        if "world.open" in s or "connection.open" in s:
            return "discovery"
        if "settle" in s:
            return "drain" if "run_for" in s else "settle"
        if "probe" in s:
            return "probe"
        if "run_for" in s:
            return "wait step"
        if "wait_results" in s:
            return "results"
        return "after"   # run_until straight from cancel / second_gcs / stray

    def cut_at(self, why: str) -> None:
        if self.cut is None:
            return
        now = time.perf_counter()
        d = now - self.cut
        self.cut = now
        place = self.where()
        if place in ("discovery", "drain", "settle"):
            key = place
        elif why == "rx":
            key = "turnaround" if d < FAST else "slow reply"
        elif why == "retry":
            key = "retry timer"
        elif why == "timeout":
            key = {"wait step": "wait step", "after": "after delay", "probe": "probe retry",
                   "results": "results bound"}[place]
        else:   # the condition held without a cut since the last (e.g. at once)
            key = "cpu"
        self.wire[key] += d
        self.wire_n[key] += 1


FORCED_WIRE = ("slow reply", "retry timer", "wait step", "after delay", "probe retry", "results bound")


@contextlib.contextmanager
def instrumented(ph: Phases) -> Iterator[None]:
    patches: list[tuple[Any, str, Any]] = []

    def patch(owner: Any, name: str, new: Any) -> None:
        patches.append((owner, name, getattr(owner, name)))
        setattr(owner, name, new)

    def timed(owner: Any, attr: str, label: Callable[..., str] | str) -> None:
        fn = getattr(owner, attr)

        def wrapper(*a: Any, **kw: Any) -> Any:
            ph.push(label(*a, **kw) if callable(label) else label)
            try:
                return fn(*a, **kw)
            finally:
                ph.pop()
        patch(owner, attr, wrapper)

    W, R = world_mod.World, steps_mod.Runner
    timed(W, "__init__", "world.open")
    try:   # one connection per campaign (newer trees): its discovery is a phase of its own
        from mavconform.fuzz.protocol import connection as connection_mod
        timed(connection_mod.TargetConnection, "__init__", "connection.open")
    except ImportError:
        pass
    timed(W, "close", "world.close")
    timed(W, "run_for", "run_for")
    timed(R, "apply", lambda self, step: f"step:{step.get('op')}")
    timed(R, "_start", "start")
    timed(R, "_wait_for_results", "wait_results")
    timed(R, "_settle", "settle")
    timed(R, "check", "check")
    timed(R, "_probe", "probe")

    run_until = UdpDriver.run_until

    def run_until_wrapped(self: UdpDriver, condition: Callable[[], bool], *, timeout: float,
                          **kw: Any) -> bool:
        ph.push("run_until")
        ph.cut = time.perf_counter()
        try:
            ok = run_until(self, condition, timeout=timeout, **kw)
            ph.cut_at("held" if ok else "timeout")
            return ok
        finally:
            ph.cut = None
            ph.pop()
    patch(UdpDriver, "run_until", run_until_wrapped)

    init = UdpDriver.__init__

    def init_wrapped(self: UdpDriver, *a: Any, **kw: Any) -> None:
        init(self, *a, **kw)
        sel = self._selector.select

        def select(timeout: float | None = None) -> Any:
            t = time.perf_counter()
            events = sel(timeout)
            d = time.perf_counter() - t
            acc = ph.select[tuple(ph.stack)]
            acc[0 if events else 1] += d
            acc[2] += 1
            return events
        self._selector.select = select   # type: ignore[method-assign]

        def hook(rec: Any) -> None:
            if rec.kind == "rx" and ph.cut is not None:
                d = rec.data
                msgid = int.from_bytes(d[7:10], "little") if d[:1] == b"\xfd" and len(d) > 10 else (
                    d[5] if d[:1] == b"\xfe" and len(d) > 5 else -1)
                if msgid not in STREAMED:
                    ph.cut_at("rx")
        self.add_capture(hook)
    patch(UdpDriver, "__init__", init_wrapped)

    gcs_poll = FuzzGcs.poll

    def poll(self: FuzzGcs, now: float) -> None:
        c = self.client
        d = c.next_deadline() if c is not None else None
        if d is not None and now >= d:
            ph.cut_at("retry")
        gcs_poll(self, now)
    patch(FuzzGcs, "poll", poll)
    try:
        yield
    finally:
        ph._charge(time.perf_counter())
        for owner, name, old in reversed(patches):
            setattr(owner, name, old)


def _group(path: tuple[str, ...]) -> tuple[str, bool]:
    """A phase path -> (the Runner/World phase it belongs to, whether this path is that
    phase's own call, counted as one call of it)."""
    last = path[-1] if path else ""
    if not path:
        return "Hypothesis + machine + search (outside Runner/World)", False
    if "world.open" in path or "connection.open" in path:
        return "world open (per example) / connection open (discovery)", last in ("world.open", "connection.open")
    if "world.close" in path:
        return "world close", last == "world.close"
    if "probe" in path:
        return "check > _probe (REQUEST_LIST, faults lifted)", last == "probe"
    if "check" in path:
        return "check (oracles)", last == "check"
    if "settle" in path:
        if "run_for" in path:
            return "_settle: UDP_DRAIN (after stray steps)", last == "run_for"
        return "_settle: idle wait", last == "settle"
    if "wait_results" in path:
        return "_wait_for_results (operations to their result)", last == "wait_results"
    if "start" in path:
        return "_start (operations sent)", last == "start"
    if "run_for" in path:
        return "wait steps (run_for)", last == "run_for"
    if last == "run_until" and len(path) == 2:
        return "`after` delays (cancel / second_gcs / stray during)", True
    return "step bookkeeping (apply, outside the above)", last.startswith("step:")


def print_phases(ph: Phases, wall: float, examples: int) -> None:
    """Exclusive time per phase path; run_until split into CPU / select (reply / timer)."""
    groups: dict[str, list[float]] = defaultdict(lambda: [0.0, 0])
    for path, t in ph.excl.items():
        name, own = _group(path)
        groups[name][0] += t
        if own:
            groups[name][1] += ph.calls.get(path, 0)
    groups["Hypothesis + machine + search (outside Runner/World)"][1] = examples
    print(f"\n  {'phase (Runner / World)':58s} {'total s':>8s} {'share':>6s} {'calls':>6s} {'per call':>9s}")
    for name, (t, n) in sorted(groups.items(), key=lambda kv: -kv[1][0]):
        per = f"{1000 * t / n:8.1f}ms" if n else ""
        print(f"  {name:58s} {t:8.2f} {100 * t / wall:5.1f}% {n:6d} {per:>9s}")
    names = {"": "Hypothesis + machine + rest (outside Runner/World)"}
    rows = []
    for path, t in ph.excl.items():
        label = " > ".join(path) if path else ""
        n = ph.calls.get(path, 0)
        rows.append((t, names.get(label, label), n))
    rows.sort(reverse=True)
    print(f"\n  the same by call path (exclusive, {wall:.1f} s; run_until = CPU + select)")
    print(f"  {'phase':58s} {'total s':>8s} {'share':>6s} {'calls':>6s} {'per call':>9s}")
    for t, label, n in rows:
        if t < 0.0005 * wall:
            continue
        per = f"{1000 * t / n:8.1f}ms" if n else ""
        print(f"  {label:58s} {t:8.2f} {100 * t / wall:5.1f}% {n:6d} {per:>9s}")
    sel_ev = sum(v[0] for v in ph.select.values())
    sel_to = sum(v[1] for v in ph.select.values())
    nsel = sum(v[2] for v in ph.select.values())
    inside = sum(t for p, t in ph.excl.items() if p and p[-1] == "run_until")
    print(f"  run_until: {inside:.2f} s, of which select() {sel_ev + sel_to:.2f} s in {nsel} calls "
          f"(ended by a datagram {sel_ev:.2f} s, by its timeout {sel_to:.2f} s), CPU "
          f"{inside - sel_ev - sel_to:.2f} s")
    print("\n  the wire ledger (run_until time cut at every datagram, retry timer and return)")
    total = sum(ph.wire.values())
    for key, t in sorted(ph.wire.items(), key=lambda kv: -kv[1]):
        tag = "forced" if key in FORCED_WIRE else "not forced"
        print(f"  {key:18s} {t:8.2f} s {100 * t / wall:5.1f}%  {ph.wire_n[key]:6d} pieces  {tag}")
    print(f"  {'(outside run_until)':18s} {wall - total:8.2f} s {100 * (wall - total) / wall:5.1f}%"
          f"                 not forced")


# --- the forced waits, in virtual time ----------------------------------------------------------
