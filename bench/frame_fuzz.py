"""Benchmark: the frame fuzzer against the builtin vehicle over UDP loopback.

Prints frames per second sent (and checked: in examples the oracle judged and passed), the
datagrams the vehicle read against those sent, and, as the baseline measured in the same
run, the rate at which our reference decoder alone decodes the same kind of datagrams
(fuzz frames / decoder frames: how close the whole loop - Hypothesis, mutation, admission,
UDP, the vehicle, the oracle - comes to decoding alone). Goal: >= 20 000 frames/s.

    python bench/frame_fuzz.py [--seconds S] [--seed N] [--sitl udp:127.0.0.1:PORT --profile NAME]
    python bench/frame_fuzz.py --long [--frames 1000000] [--transport virtual|udp]

`--long` (not in CI) fuzzes until --frames frames were sent against builtin:spec (in
virtual time by default: a fresh vehicle per example, signing vehicles included, every
oracle check) and reports exceptions and invariant violations (goal: 0 of each).

`--sitl URI` (a real autopilot's SITL, e.g. PX4's udp:127.0.0.1:18570, run in a loopback-only
network namespace) then fuzzes it for as long, over the same loop, and prints its rate beside
the builtin vehicle's: how much of the rate is ours and how much the target's.
"""

from __future__ import annotations

import argparse
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.fuzz.case import dump_case, save_case  # noqa: E402
from mavconform.fuzz.frames import FrameCampaign  # noqa: E402
from mavconform.fuzz.frames.admission import Admission  # noqa: E402
from mavconform.fuzz.frames.mutators import MutationContext  # noqa: E402
from mavconform.fuzz.frames.program import RECORD, Builder, parse  # noqa: E402
from mavconform.fuzz.frames.rig import campaign_key  # noqa: E402
from mavconform.reference_impl.wire.codec import FrameDecoder  # noqa: E402


def decoder_rate(seed: int, frames: int = 60_000) -> float:
    """Frames per second our decoder alone gets through, on fuzz datagrams like the run's."""
    wall = time.time
    ctx = MutationContext(campaign_key(seed), campaign_key(seed, "wrong"), wall)
    builder = Builder((1, 1), ctx, Admission(None, False, wall), sign_frames=False)
    datagrams = []
    program = parse(random.Random(seed).randbytes(frames * RECORD))
    for specs in program:
        datagrams.append(b"".join(builder.datagram(specs)[0]))
    decoder = FrameDecoder()
    t0 = time.perf_counter()
    for d in datagrams:
        decoder.feed(d)
    return frames / (time.perf_counter() - t0)


def fast(args: argparse.Namespace) -> int:
    found, rate = one_run("builtin:spec", args)
    base = decoder_rate(args.seed)
    print(f"baseline: reference decoder alone on such datagrams: {base:,.0f} frames/s")
    print(f"ratio fuzz loop / decoder alone: {rate / base:.2f}")
    if args.sitl:
        sitl_found, sitl_rate = one_run(args.sitl, args, profile=args.profile)
        print(f"ratio {args.sitl} / builtin:spec: {sitl_rate / rate:.2f}")
        found += sitl_found
    return 1 if found else 0


def one_run(target: str, args: argparse.Namespace, profile: str | None = None) -> tuple[list, float]:
    """Fuzz `target` over UDP for --seconds; print what happened; the findings and frames/s."""
    campaign = FrameCampaign(target, seed=args.seed, stop_after=args.seconds, transport="udp", profile=profile)
    t0 = time.perf_counter()
    found = campaign.run()
    wall = time.perf_counter() - t0
    rig = campaign.rig
    rate = campaign.frames_sent / wall
    print(f"frame fuzz vs {target} over UDP loopback, {wall:.1f} s, seed {args.seed}")
    print(f"  examples                {campaign.examples}")
    goal = "; goal >= 20,000/s" if target == "builtin:spec" else ""
    print(f"  frames sent             {campaign.frames_sent}  ({rate:,.0f}/s{goal})")
    print(f"  frames checked (passed) {campaign.passed_frames}  ({campaign.passed_frames / wall:,.0f}/s)")
    if rig.counted is not None:   # our own vehicle: how many of them it read
        print(f"  datagrams sent / read   {rig.datagrams_sent} / {rig.counted.received - _oracle_datagrams(rig)}"
              " by the vehicle")
    else:
        print(f"  datagrams sent          {rig.datagrams_sent}")
    print(f"  neutralised by the admission rule: {campaign.neutralised}")
    for case in found:
        print(f"FINDING: {case.violation}")
    return found, rate


def _oracle_datagrams(rig) -> int:
    """Datagrams the oracle GCS itself sent (HEARTBEATs, uploads, downloads)."""
    return rig.gcs.endpoint.encoder.frames_sent


def long(args: argparse.Namespace) -> int:
    sent = [0]
    start = time.perf_counter()
    findings = []
    seed = args.seed
    examples = passed = 0
    while sent[0] < args.frames:
        campaign = FrameCampaign("builtin:spec", seed=seed, max_examples=200, transport=args.transport,
                                 on_example=lambda n: sent.__setitem__(0, sent[0] + n))
        found = campaign.run()
        examples += campaign.examples
        passed += campaign.passed_frames
        for case in found:
            findings.append(case)
            path = save_case(case, args.out)
            print(f"FINDING (seed {seed}): {case.violation}  -> {path}", flush=True)
        seed += 1
        el = time.perf_counter() - start
        print(f"  {sent[0]:>9} frames, {examples} examples, {el:6.1f} s, {sent[0] / el:,.0f}/s", flush=True)
    el = time.perf_counter() - start
    exceptions = sum(1 for c in findings if c.violation.invariant == "no-exception")
    print(f"long run vs builtin:spec ({args.transport}): {sent[0]} frames in {examples} examples, "
          f"{el:.0f} s ({sent[0] / el:,.0f}/s), seeds {args.seed}..{seed - 1}")
    print(f"  exceptions: {exceptions}   invariant violations: {len(findings) - exceptions}")
    for case in findings:
        print(dump_case(case))
    return 1 if findings else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seconds", type=float, default=10.0, help="length of the UDP run (default 10)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--sitl", metavar="URI", help="also fuzz this real target (udp:HOST:PORT) for as long")
    p.add_argument("--profile", metavar="NAME", help="--sitl's vehicle profile (px4, ardupilot, ...)")
    p.add_argument("--long", action="store_true", help="the long run (not in CI)")
    p.add_argument("--frames", type=int, default=1_000_000, help="frames for --long (default 1e6)")
    p.add_argument("--transport", choices=("virtual", "udp"), default="virtual", help="for --long")
    p.add_argument("--out", default="reports/out/frame-fuzz", help="where --long saves findings")
    args = p.parse_args()
    return long(args) if args.long else fast(args)


if __name__ == "__main__":
    raise SystemExit(main())
