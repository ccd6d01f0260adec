"""Benchmark: stateful protocol fuzzing in virtual time against builtin:spec.

Runs the protocol fuzzer (50-item plans, link faults on) for a number of examples and
prints examples/s and steps/s, then a baseline measured in the same run: the same number
of plain fault-free 50-item upload + download round trips through the reference GCS and
vehicle, and the ratio (fuzz example time / round-trip time), which does not depend on
the machine.

    python bench/protocol_fuzz.py [--examples N] [--items N] [--seed S]
    python bench/protocol_fuzz.py --long [--examples 100000]    # not for CI

`--long` runs a long campaign in chunks of fresh seeds and prints the invariant
violations (goal 0) and exceptions (goal 0) it met, each with the seed to rerun it.
"""

from __future__ import annotations

import argparse
import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.fuzz.protocol import Knobs, search  # noqa: E402
from mavconform.reference_impl.gcs import GcsNode  # noqa: E402
from mavconform.reference_impl.mission.items import MissionItem, MissionType  # noqa: E402
from mavconform.reference_impl.net import SimNetwork  # noqa: E402
from mavconform.reference_impl.session import GcsSession  # noqa: E402
from mavconform.reference_impl.vehicle import VehicleNode  # noqa: E402


def fuzz(examples: int, items: int, seed: int) -> tuple[float, int, int, list]:
    """Wall seconds, examples and steps run, findings."""
    units: list[int] = []
    knobs = Knobs(max_items=items, min_items=items, faults=True)
    t0 = time.perf_counter()
    cases = search("builtin:spec", seed=seed, max_examples=examples, on_example=units.append, knobs=knobs)
    return time.perf_counter() - t0, len(units), sum(units), cases


def round_trips(n: int, items: int) -> float:
    """Wall seconds for n fault-free upload + download round trips of `items` items."""
    plan = [MissionItem(seq=i, frame=3, command=16, x=473977420 + 97 * i, y=85455940 - 53 * i,
                        z=30.0 + i % 20) for i in range(items)]
    t0 = time.perf_counter()
    for seed in range(n):
        net = SimNetwork(seed=seed)
        vehicle = VehicleNode(wall_clock=net.clock.wall)
        gcs = GcsNode(remote="vehicle", wall_clock=net.clock.wall)
        net.add_node("vehicle", vehicle)
        net.add_node("gcs", gcs)
        net.connect("gcs", "vehicle")
        session = GcsSession(net, gcs)
        session.wait_for_target(10)
        if not (session.upload(MissionType.MISSION, plan).ok and session.download(MissionType.MISSION).ok):
            raise SystemExit("baseline round trip failed")
    return time.perf_counter() - t0


def long_run(total: int, items: int, seed: int, chunk: int) -> int:
    """A long campaign in chunks (each a search with its own seed); prints what it meets."""
    knobs = Knobs(max_items=items, faults=True)
    done = steps = 0
    violations: list[str] = []
    exceptions: list[str] = []
    t0 = time.perf_counter()
    s = seed
    while done < total:
        units: list[int] = []
        try:
            cases = search("builtin:spec", seed=s, max_examples=min(chunk, total - done),
                           on_example=units.append, knobs=knobs)
        except Exception as exc:   # a bug in the fuzzer or the reference client: report it
            exceptions.append(f"seed {s}: {type(exc).__name__}: {exc}\n{traceback.format_exc(limit=4)}")
            cases = []
        for case in cases:
            violations.append(f"seed {s}: {case.violation} ({len(case.steps)} steps)")
        done += len(units)
        steps += sum(units)
        elapsed = time.perf_counter() - t0
        print(f"  {done:7d} examples  {steps:8d} steps  {elapsed:7.0f} s  "
              f"{done / elapsed:6.1f} ex/s  violations {len(violations)}  exceptions {len(exceptions)}",
              flush=True)
        s += 1
    print(f"long run: {done} examples, {steps} steps in {time.perf_counter() - t0:.0f} s "
          f"(plans up to {items} items, faults on)")
    print(f"invariant violations: {len(violations)} (goal 0)")
    for v in violations:
        print("  " + v)
    print(f"exceptions: {len(exceptions)} (goal 0)")
    for e in exceptions:
        print("  " + e)
    return 1 if violations or exceptions else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--examples", type=int, default=None, help="default 200 (--long: 100000)")
    ap.add_argument("--items", type=int, default=50, help="plan size (default 50)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--long", action="store_true", help="long campaign; prints violations and exceptions")
    ap.add_argument("--chunk", type=int, default=2000, help="--long: examples per seed")
    args = ap.parse_args()
    if args.long:
        return long_run(args.examples or 100_000, args.items, args.seed, args.chunk)
    n = args.examples or 200
    fuzz(5, args.items, args.seed + 1)                  # warm-up (imports, caches)
    wall, examples, steps, cases = fuzz(n, args.items, args.seed)
    base = round_trips(examples, args.items)
    print(f"protocol fuzz vs builtin:spec, {args.items}-item plans, faults on, virtual time")
    print(f"  fuzz:     {examples} examples, {steps} steps in {wall:.2f} s: "
          f"{examples / wall:.1f} examples/s, {steps / wall:.0f} steps/s")
    print(f"  baseline: {examples} fault-free {args.items}-item upload+download round trips in "
          f"{base:.2f} s: {examples / base:.1f} round trips/s")
    print(f"  ratio:    one fuzz example costs {wall / base:.1f} round trips")
    if cases:
        print(f"  findings: {len(cases)} (goal 0): " + "; ".join(str(c.violation) for c in cases))
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
