"""Benchmark: the protocol fuzzer against a vehicle in another process, over UDP loopback.

Starts `mavconform vehicle --listen udp:127.0.0.1:0 --quiet` (OS-chosen port, read from
its first line; killed at the end), runs `fuzz.protocol.search("udp:127.0.0.1:PORT", ...)`
against it with link faults on (the `mavconform fuzz` knobs otherwise), and prints
examples, steps, wall time, steps/s and examples/s, then how much of that wall time the
protocol itself forced (goals: >= 5 steps/s, wall / forced <= 1.5).

    python bench/protocol_fuzz_udp.py [--time S | --examples N] [--seed S] [--no-faults]
           [--max-wait S] [--profile NAME|FILE] [--phases] [--cprofile OUT] [--dump OUT.json]
    python bench/protocol_fuzz_udp.py --find-planted [--time 120] [--seed S]

Defaults: --time 15 (a step running when the budget ends still finishes: a wait step can
add up to --max-wait), seed 0, faults on, the spec vehicle.

"Forced wait" is measured two ways, both printed:

- virtual replay: every example's steps, recorded as the UDP run applied them, are run
  again with the same example seeds against an in-process vehicle of the same profile
  (`Runner` on a `SimNetwork`, whose clock jumps from timer to timer). The virtual seconds
  that pass are exactly the waits the protocol and the step program force (our retry
  timers, the vehicle's own timers, wait steps, `after` delays, fault-model delays and
  bursts); everything else costs nothing there. The settle is made the one the wire
  allows (in process it would also wait until the vehicle is idle, e.g. until it gives up
  an upload a stray MISSION_COUNT opened: the UDP run never waits for that; that variant
  is printed too). Exact and machine-independent, but a sibling run: the fault RNG draws
  differ, and in process each GCS has a link of its own while over UDP the four share one.
  Per step kind the two runs differ by whole retry ladders either way; the sum is fair.
- wire ledger: this UDP run's time inside `UdpDriver.run_until` is cut at every datagram
  received (HEARTBEAT / GLOBAL_POSITION_INT / MISSION_CURRENT streams excepted), at every
  retry timer of our GCSs, and at every return of run_until. A piece that ends with a
  datagram arriving less than FAST s after the previous cut is turnaround (loopback, the
  vehicle's processing, ours); one that ends later (the vehicle's timer or a fault delay),
  on our retry timer, or at the end of a wait step / `after` delay / unanswered probe try,
  is forced. Discovery, UDP_DRAIN and the settle wait are the fuzzer's own choices, and
  time outside run_until (Hypothesis, world setup, bookkeeping) is overhead. It judges the
  run that happened (its drops, its shared link), at the price of a threshold.

`--phases` prints where the wall time went: exclusive time per Runner/World phase (calls,
per call), the same per call path with run_until split into CPU and select(), and the
wire ledger. `--cprofile OUT` writes a cProfile of the search; `--dump` every example.
`--find-planted` serves a vehicle with a planted non-atomic upload (a profile file
`base = "spec"` + `atomic_upload = false`, written to a temp dir) and reports the time to
the first finding and its invariant (goal: within 120 s).

Only this file and udp_time_ledger.py beside it change anything, and only while it runs: it
wraps `Runner` (to record the steps) and, unless --bare, a few Runner/World/UdpDriver methods
(to time them; udp_time_ledger.py).
"""

from __future__ import annotations

import argparse
import contextlib
import cProfile
import os
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.fuzz.protocol import Knobs, search  # noqa: E402
from mavconform.fuzz.protocol.search import udp_knobs  # noqa: E402

UDP_KNOBS = udp_knobs("udp:127.0.0.1:0")   # what `mavconform fuzz` uses against a UDP target


def _knobs(args: Any) -> Knobs:
    """The campaign's UDP knobs, with the bench's overrides."""
    import dataclasses
    return dataclasses.replace(UDP_KNOBS, faults=not args.no_faults, max_wait=args.max_wait)
from mavconform.fuzz.protocol import machine as machine_mod  # noqa: E402
from mavconform.fuzz.protocol import world as world_mod  # noqa: E402
from mavconform.fuzz.protocol.steps import Runner  # noqa: E402
from udp_time_ledger import FAST, FORCED_WIRE, Phases, instrumented, print_phases  # noqa: E402  (beside this file)

LISTENING = "listening on udp:127.0.0.1:"
PLANTED_PROFILE = """\
name = "planted-non-atomic"
description = "spec vehicle with a planted bug: uploads written item by item (VARIANTS A2)"
base = "spec"

[[knob]]
knob = "atomic_upload"
value = false
"""


# --- the vehicle in another process ------------------------------------------------------------

@contextlib.contextmanager
def vehicle_process(duration: float, profile: str | None) -> Iterator[int]:
    """`mavconform vehicle` on 127.0.0.1, an OS-chosen port; yields the port. --quiet: an
    unread stdout pipe must never fill up and block the vehicle. Killed afterwards (bounded)."""
    cmd = [sys.executable, "-m", "mavconform", "vehicle", "--listen", "udp:127.0.0.1:0",
           "--duration", f"{duration:g}", "--quiet"]
    if profile:
        cmd += ["--profile", profile]
    root = str(Path(__file__).resolve().parents[1])   # this checkout's mavconform, not another
    env = {**os.environ, "PYTHONPATH": root + os.pathsep + os.environ.get("PYTHONPATH", "")}
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=root, env=env)
    try:
        line = proc.stdout.readline()   # the process ends after --duration at the latest
        if LISTENING not in line:
            proc.kill()
            raise SystemExit(f"vehicle did not start: {line}{proc.stderr.read()}")
        yield int(line.split(LISTENING)[1].split()[0])
    finally:
        proc.kill()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass


# --- what the UDP run did, step by step --------------------------------------------------------

@dataclass
class Example:
    seed: int
    steps: list[dict[str, Any]] = field(default_factory=list)
    wall: list[float] = field(default_factory=list)   # per step: apply + check, s
    violation: Any = None


class Recorder:
    """Every Runner the machine builds, its steps and their wall time (apply + check)."""

    def __init__(self) -> None:
        self.examples: list[Example] = []
        self.first_violation: tuple[float, Any] | None = None
        self.t0 = time.monotonic()
        self.last_step_end = self.t0   # time.monotonic() when the last step (apply + check) ended

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        rec = self

        class RecordingRunner(Runner):
            def __init__(self, target: str, seed: int, **kw: Any) -> None:
                self._ex = Example(seed)
                rec.examples.append(self._ex)
                super().__init__(target, seed, **kw)

            def apply(self, step: dict[str, Any]) -> Any:
                t = time.perf_counter()
                self._ex.steps.append(step)
                v = super().apply(step)
                self._ex.wall.append(time.perf_counter() - t)
                rec.last_step_end = time.monotonic()   # past the budget no check follows
                return self._seen(v)

            def check(self) -> Any:
                t = time.perf_counter()
                v = super().check()
                self._ex.wall[-1] += time.perf_counter() - t
                rec.last_step_end = time.monotonic()
                return self._seen(v)

            def _seen(self, v: Any) -> Any:
                if v is not None and self._ex.violation is None:
                    self._ex.violation = v
                    if rec.first_violation is None:
                        rec.first_violation = (time.monotonic() - rec.t0, v)
                return v

        saved = machine_mod.Runner
        machine_mod.Runner = RecordingRunner
        try:
            yield
        finally:
            machine_mod.Runner = saved


@contextlib.contextmanager
def replay_vehicle(profile: str | None) -> Iterator[str]:
    """The in-process target whose timers match the vehicle process's profile."""
    if not profile or profile == "spec":
        yield "builtin:spec"
        return
    if profile in ("px4", "ardupilot"):
        yield f"builtin:{profile}"
        return
    import dataclasses

    from mavconform.reference_impl.profiles import load_profile
    from mavconform.reference_impl.vehicle import VehicleNode
    config = load_profile(profile).config
    saved = world_mod.build_vehicle

    def build(uri: Any, **kw: Any) -> VehicleNode:
        return VehicleNode(dataclasses.replace(config, **kw))
    world_mod.build_vehicle = build
    try:
        yield "builtin:spec"
    finally:
        world_mod.build_vehicle = saved


def virtual_times(examples: list[Example], profile: str | None, *, wire_settle: bool = True
                  ) -> list[list[float]]:
    """Per example, per step: the virtual seconds its replay in process took. `wire_settle`:
    settle as over the wire, where the vehicle's own state cannot be seen (in process the
    settle also waits until the vehicle is idle, e.g. until it gives up an upload a stray
    MISSION_COUNT opened, which the UDP run never waits for)."""
    out = []
    saved = world_mod.World.vehicle_idle
    if wire_settle:
        world_mod.World.vehicle_idle = lambda self: True   # type: ignore[method-assign]
    try:
        with replay_vehicle(profile) as target:
            for ex in examples:
                runner = Runner(target, ex.seed)
                per: list[float] = []
                try:
                    for step in ex.steps:
                        t = runner.world.now()
                        runner.apply(step) or runner.check()
                        per.append(runner.world.now() - t)
                except Exception as exc:   # noqa: BLE001 - a measurement, not a verdict: say so, go on
                    print(f"  (virtual replay of example seed {ex.seed} stopped at step {len(per)}: "
                          f"{type(exc).__name__}: {exc})")
                finally:
                    runner.close()
                out.append(per + [0.0] * (len(ex.steps) - len(per)))
    finally:
        world_mod.World.vehicle_idle = saved
    return out


def _ratio(wall: float, forced: float) -> str:
    return f"{wall / forced:.2f}" if forced > 0.01 else "inf (nothing forced)"


# --- main ---------------------------------------------------------------------------------------

def run(args: argparse.Namespace, profile: str | None) -> int:
    knobs = _knobs(args)
    budget = args.time if args.examples is None else None
    rec = Recorder()
    ph = Phases()
    units: list[int] = []
    duration = (budget or 600) + 600
    with vehicle_process(duration, profile) as port:
        target = f"udp:127.0.0.1:{port}"
        print(f"protocol fuzz over UDP loopback vs `mavconform vehicle --profile {profile or 'spec'}` "
              f"(pid apart, port {port}); faults {'off' if args.no_faults else 'on'}, seed {args.seed}, "
              + f"max_wait {args.max_wait:g} s, "
              + (f"--time {budget:g} s" if budget is not None else f"--examples {args.examples}"), flush=True)
        prof = cProfile.Profile() if args.cprofile else None
        inst = contextlib.nullcontext() if args.bare else instrumented(ph)
        with rec.installed(), inst:
            t0 = ph.last = time.perf_counter()   # the vehicle's start-up is no phase of ours
            rec.t0 = time.monotonic()
            if prof:
                prof.enable()
            try:
                cases = search(target, seed=args.seed, stop_after=budget, max_examples=args.examples,
                               knobs=knobs, on_example=units.append)
            finally:
                if prof:
                    prof.disable()
            wall = time.perf_counter() - t0
    if prof:
        prof.dump_stats(args.cprofile)
    examples, steps = len(units), sum(units)
    print(f"  examples {examples}, steps {steps}, wall {wall:.1f} s: {steps / wall:.2f} steps/s, "
          f"{examples / wall:.2f} examples/s   (goal >= 5 steps/s)")
    if rec.first_violation is not None:
        t, v = rec.first_violation
        print(f"  first finding after {t:.1f} s: {v.invariant}: {v.detail}")
    for case in cases:
        print(f"  finding: {case.violation} ({len(case.steps)} steps)")

    ran = [ex for ex in rec.examples if ex.steps]
    vt = virtual_times(ran, profile)
    forced = sum(map(sum, vt))
    full = sum(map(sum, virtual_times(ran, profile, wire_settle=False)))
    stepwall = sum(sum(ex.wall) for ex in ran)
    print(f"  forced, virtual replay of the same {sum(len(e.steps) for e in ran)} steps and seeds in process "
          f"(settle as over the wire): {forced:.1f} s -> wall / forced = {_ratio(wall, forced)}  (goal <= 1.5)")
    print(f"  (the same replay with the in-process settle, which also waits for the vehicle to be idle: "
          f"{full:.1f} s -> {_ratio(wall, full)})")
    if not args.bare:
        wire = sum(ph.wire[k] for k in FORCED_WIRE)
        print(f"  forced, wire ledger of this run (retry timers, replies >= {1000 * FAST:g} ms after the last "
              f"cut, wait steps, after delays): {wire:.1f} s -> wall / forced = {_ratio(wall, wire)}")
    tail = rec.t0 + wall - rec.last_step_end
    print(f"  wall inside the steps (apply + check): {stepwall:.1f} s; outside them: {wall - stepwall:.1f} s, "
          f"of which {tail:.1f} s after the last step ended (empty examples drawn past the budget, close)")
    if budget is not None:
        print(f"  budget {budget:g} s: the last step ended at {rec.last_step_end - rec.t0:.1f} s, search "
              f"returned at {wall:.1f} s")
    if args.dump:
        import json
        Path(args.dump).write_text(json.dumps([{"seed": ex.seed, "steps": ex.steps, "wall": ex.wall,
                                                "virtual": per} for ex, per in zip(ran, vt)], indent=1))
    by_op: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0])
    for ex, per in zip(ran, vt):
        for step, w, v in zip(ex.steps, ex.wall, per):
            acc = by_op[step["op"]]
            acc[0] += w
            acc[1] += v
            acc[2] += 1
    print("  per step kind (excess = wall - virtual; with faults on, noisy: the fault draws differ)")
    print(f"  {'step':12s} {'n':>5s} {'wall s':>8s} {'virtual s':>10s} {'excess s':>9s} {'excess/step':>12s}")
    for op, (w, v, n) in sorted(by_op.items(), key=lambda kv: -(kv[1][0] - kv[1][1])):
        print(f"  {op:12s} {n:5d} {w:8.2f} {v:10.2f} {w - v:9.2f} {1000 * (w - v) / n:10.0f}ms")
    if args.phases and not args.bare:
        print_phases(ph, wall, examples)
    return 0


def find_planted(args: argparse.Namespace) -> int:
    budget = args.time if args.time_given else 120.0
    with tempfile.TemporaryDirectory(prefix="mavconform-planted-") as tmp:
        path = Path(tmp) / "planted-non-atomic.toml"
        path.write_text(PLANTED_PROFILE)
        rec = Recorder()
        units: list[int] = []
        with vehicle_process(budget + 600, str(path)) as port:
            print(f"find the planted bug: vehicle with atomic_upload = false over UDP (port {port}), "
                  f"faults {'off' if args.no_faults else 'on'}, max_wait {args.max_wait:g} s, seed {args.seed}, "
                  f"budget {budget:g} s", flush=True)
            with rec.installed():
                t0 = time.monotonic()
                rec.t0 = t0
                cases = search(f"udp:127.0.0.1:{port}", seed=args.seed, stop_after=budget,
                               knobs=_knobs(args),
                               on_example=units.append)
                wall = time.monotonic() - t0
    print(f"  {len(units)} examples, {sum(units)} steps, search returned after {wall:.1f} s")
    if rec.first_violation is None:
        print(f"  no finding within {budget:g} s (goal: within 120 s)")
        return 1
    t, v = rec.first_violation
    print(f"  first finding after {t:.1f} s (goal <= 120 s): {v.invariant}: {v.detail}")
    for case in cases:
        print(f"  reported: {case.violation.invariant} at step {case.violation.step} of {len(case.steps)}: "
              + ", ".join(s["op"] for s in case.steps))
    return 0 if t <= 120 else 1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--time", type=float, default=None, help="wall-time budget, s (default 15; --find-planted 120)")
    ap.add_argument("--examples", type=int, default=None, help="stop after N examples instead")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--profile", default=None, metavar="NAME|FILE", help="vehicle profile (default spec)")
    ap.add_argument("--no-faults", action="store_true", help="draw no link-fault steps")
    ap.add_argument("--max-wait", type=float, default=UDP_KNOBS.max_wait,
                    help="Knobs.max_wait: longest wait step, s (default: the fuzzer's over UDP, %(default)g; "
                         "`after` cues: min(4, it))")
    ap.add_argument("--phases", action="store_true", help="print where the wall time went")
    ap.add_argument("--bare", action="store_true", help="no instrumentation (only the virtual replay)")
    ap.add_argument("--cprofile", metavar="OUT", help="write a cProfile of the search to OUT")
    ap.add_argument("--dump", metavar="OUT.json", help="write every example (seed, steps, wall and virtual s "
                    "per step) to OUT.json")
    ap.add_argument("--find-planted", action="store_true",
                    help="serve a non-atomic vehicle; report the time to the first finding")
    args = ap.parse_args()
    args.time_given = args.time is not None
    if args.time is None:
        args.time = 15.0
    if args.find_planted:
        return find_planted(args)
    return run(args, args.profile)


if __name__ == "__main__":
    raise SystemExit(main())
