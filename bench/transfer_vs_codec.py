"""Benchmark: 100-item upload + download at 10 % loss each way, in virtual time.

Prints scenarios per second, and the ratio of the stack's wall time to pure pymavlink
encode + decode of exactly the frames the scenario sent (measured in the same run, so the
ratio is independent of the machine). Target: ratio <= 2.0 (project goal 1.5).

Beside it, a bare transfer loop over the same frames: each message built from its fields (as
a sender must), packed, pushed through a heap with a loss draw (the least a lossy network
costs) and decoded, with no protocol at all. It is the floor any stack on pymavlink in Python
can reach; "stack / bare loop" is what the protocol layers cost on top of it.

    python bench/transfer_vs_codec.py [--scenarios N] [--items N] [--loss P]
"""

from __future__ import annotations

import argparse
import heapq
import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.reference_impl.gcs import GcsNode  # noqa: E402
from mavconform.reference_impl.mission.items import MissionItem, MissionType  # noqa: E402
from mavconform.reference_impl.net import FaultModel, SimNetwork  # noqa: E402
from mavconform.reference_impl.session import GcsSession  # noqa: E402
from mavconform.reference_impl.vehicle import VehicleNode  # noqa: E402
from mavconform.reference_impl.wire.dialect import mavlink as dialect  # noqa: E402


def items(n: int) -> list[MissionItem]:
    return [MissionItem(seq=i, frame=3, command=16, param1=float(i % 5), x=473977420 + 97 * i,
                        y=85455940 - 53 * i, z=30.0 + i % 20) for i in range(n)]


def scenario(seed: int, n: int, loss: float, capture: list | None = None) -> None:
    net = SimNetwork(seed=seed)
    vehicle = VehicleNode(wall_clock=net.clock.wall)
    gcs = GcsNode(remote="vehicle", wall_clock=net.clock.wall)
    net.add_node("vehicle", vehicle)
    net.add_node("gcs", gcs)
    net.connect("gcs", "vehicle", a_to_b=FaultModel(loss=loss), b_to_a=FaultModel(loss=loss))
    if capture is not None:
        net.add_capture(lambda r: capture.append(r.data) if r.kind == "tx" else None)
    s = GcsSession(net, gcs)
    s.wait_for_target(10)
    up = s.upload(MissionType.MISSION, items(n))
    down = s.download(MissionType.MISSION)
    if not (up.ok and down.ok and len(down.items) == n):
        raise SystemExit(f"scenario {seed} failed: {up.summary()} / {down.summary()}")


def codec_only(frames: list[bytes]) -> float:
    """Seconds for pymavlink to encode and decode these frames once."""
    decoder = dialect.MAVLink(None, 0, 0)
    decoder.robust_parsing = True
    msgs = [(decoder.parse_char(f), f[5], f[6]) for f in frames]
    senders: dict = {}
    for _, sysid, compid in msgs:
        senders.setdefault((sysid, compid), dialect.MAVLink(None, sysid, compid))
    rx = dialect.MAVLink(None, 0, 0)
    rx.robust_parsing = True
    t0 = time.perf_counter()
    for msg, sysid, compid in msgs:
        mav = senders[(sysid, compid)]
        data = msg.pack(mav)
        mav.seq = (mav.seq + 1) & 0xFF
        rx.parse_char(data)
    return time.perf_counter() - t0


def bare_loop(frames: list[bytes]) -> float:
    """Seconds for the least a transfer of these frames costs on pymavlink: build, pack, a
    heap push and pop with a loss draw, decode (MAVLink.decode: datagrams need no stream
    parser). No protocol, no state, nothing dropped."""
    decoder = dialect.MAVLink(None, 0, 0)
    decoder.robust_parsing = True
    specs = []
    senders: dict = {}
    for f in frames:
        msg = decoder.parse_char(f)
        cls = type(msg)
        specs.append((cls, [getattr(msg, name) for name in cls.fieldnames],
                      senders.setdefault((f[5], f[6]), dialect.MAVLink(None, f[5], f[6]))))
    rx = dialect.MAVLink(None, 0, 0)
    rng = random.Random(0)
    heap: list = []
    t0 = time.perf_counter()
    for n, (cls, fields, mav) in enumerate(specs):
        data = cls(*fields).pack(mav)
        mav.seq = (mav.seq + 1) & 0xFF
        heapq.heappush(heap, (n * 0.001, n, data))
        rng.random()
        rx.decode(bytearray(heapq.heappop(heap)[2]))
    return time.perf_counter() - t0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenarios", type=int, default=30)
    ap.add_argument("--items", type=int, default=100)
    ap.add_argument("--loss", type=float, default=0.10)
    ap.add_argument("--repeats", type=int, default=7,
                    help="rounds; the fastest round of each is reported (least disturbed by noise)")
    args = ap.parse_args()
    seeds = range(args.scenarios)
    frames_per: dict[int, list[bytes]] = {}
    for seed in seeds:                          # warm-up, and the frames each scenario sends
        frames_per[seed] = []
        scenario(seed, args.items, args.loss, frames_per[seed])
    all_frames = [f for seed in seeds for f in frames_per[seed]]
    stack, codec, bare = [], [], []
    for _ in range(args.repeats):               # interleave, so drift affects all alike
        t0 = time.perf_counter()
        for seed in seeds:
            scenario(seed, args.items, args.loss)
        stack.append(time.perf_counter() - t0)
        codec.append(codec_only(all_frames))
        bare.append(bare_loop(all_frames))
    s, c, b = min(stack), min(codec), min(bare)
    print(f"scenario: {args.items}-item upload + download, loss {args.loss:.0%} each way, virtual time")
    print(f"frames sent per scenario: {len(all_frames) / args.scenarios:.0f}")
    print(f"scenarios per second:     {args.scenarios / s:.1f}")
    print(f"stack wall per scenario:  {s / args.scenarios * 1e3:.2f} ms")
    print(f"pymavlink encode+decode of the same frames: {c / args.scenarios * 1e3:.2f} ms")
    print(f"ratio stack / codec:      {s / c:.2f}  (target <= 2.0, goal 1.5)")
    print(f"bare transfer loop (build, pack, heap, decode; no protocol): {b / args.scenarios * 1e3:.2f} ms, "
          f"{b / c:.2f} x codec")
    print(f"ratio stack / bare loop:  {s / b:.2f}  (what the protocol layers cost on top of the floor)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
