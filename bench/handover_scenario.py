"""Benchmark: a handover scenario of the thesis's size in virtual time (issue 14: "well under a second").

Flies each shipped delivery flight (6.6 km at 12 m/s: a 9-minute flight, two handovers, two
GCSs with lossy links) with `run_scenario` and prints the wall time per run, per simulated
flight minute, and network steps per second; then the same flight with the reports
(handover.mcap captured, handover.json and handover.html rendered) as `mavconform handover run`
does; then baselines measured in the same run, so the ratios do not depend on the machine:
the same flight with clean links (handover on), and with clean links and no handover at all
(no mission computer, no handover agents: the vehicle, its system manager and the GCSs'
heartbeats and telemetry only). `--profile` adds where the time of one polygon run goes.

    python bench/handover_scenario.py [--repeat N] [--profile]

Figures, not pass/fail.
"""

from __future__ import annotations

import argparse
import cProfile
import dataclasses
import io
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mavconform.reference_impl.gcs import GcsNode  # noqa: E402
from mavconform.reference_impl.handover.scenario import SCENARIOS_DIR, LinkFaults, Scenario, load_scenario  # noqa: E402
from mavconform.reference_impl.handover.scenario_fleet import (VEHICLE, flight_items, gcs_config,  # noqa: E402
                                                               vehicle_config)
from mavconform.reference_impl.handover.scenario_run import run_scenario  # noqa: E402
from mavconform.reference_impl.mission.constants import Cmd  # noqa: E402
from mavconform.reference_impl.mission.items import MissionType  # noqa: E402
from mavconform.reference_impl.net import McapCapture, SimNetwork  # noqa: E402
from mavconform.reference_impl.session import GcsSession  # noqa: E402
from mavconform.reference_impl.vehicle import VehicleNode  # noqa: E402
from mavconform.reference_impl.wire.dialect import mavlink as d  # noqa: E402
from mavconform.reports.handover_report import dump_timeline, handover_html, timeline  # noqa: E402

SHIPPED = ("delivery_flight.json", "delivery_flight_circles.json", "delivery_flight_waypoints.json")


def timed(fn, repeat: int) -> tuple[float, object]:
    """Median wall seconds of `repeat` calls, and the last result."""
    times, result = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def clean(s: Scenario) -> Scenario:
    return dataclasses.replace(s, gcs=tuple(dataclasses.replace(g, up=LinkFaults(), down=LinkFaults()) for g in s.gcs))


def with_reports(s: Scenario) -> object:
    with tempfile.TemporaryDirectory() as folder:
        with McapCapture(Path(folder) / "handover.mcap") as capture:
            run = run_scenario(s, capture=capture)
        doc = timeline(run)
        (Path(folder) / "handover.json").write_text(dump_timeline(doc), encoding="utf-8")
        (Path(folder) / "handover.html").write_text(handover_html(doc, s), encoding="utf-8")
    return run


def no_handover(s: Scenario) -> float:
    """The same flight, clean links, no mission computer and no handover agents; returns the
    simulated flight seconds."""
    net = SimNetwork(seed=s.seed)
    vehicle = VehicleNode(dataclasses.replace(vehicle_config(s), handover=None), wall_clock=net.clock.wall)
    net.add_node(VEHICLE, vehicle)
    sessions = {}
    for g in s.gcs:
        node = GcsNode(gcs_config(s, g), remote=VEHICLE, wall_clock=net.clock.wall)
        net.add_node(g.name, node)
        net.connect(g.name, VEHICLE)
        sessions[g.name] = GcsSession(net, node)
    for session in sessions.values():
        session.wait_for_target(20)
    parent = sessions[s.parent]
    assert parent.request_control().ok and parent.upload(MissionType.MISSION, flight_items(s)).ok
    parent.gcs.send(d.MAVLink_command_long_message(s.vehicle_sysid, 1, Cmd.MISSION_START, 0, 0, 0, 0, 0, 0, 0, 0))
    assert net.run_until(lambda: vehicle.flight.flying, timeout=2.0)
    started = net.clock.now()
    assert net.run_until(lambda: not vehicle.flight.flying, timeout=s.timeouts.max_duration_s)
    return net.clock.now() - started


def flight_minutes(run) -> float:
    return (run.flight_ended - run.mission_started) / 60


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5, help="runs per figure (the median is printed)")
    ap.add_argument("--profile", action="store_true", help="also profile one polygon run: where the time goes")
    args = ap.parse_args()
    repeat = max(1, args.repeat)
    print(f"handover scenarios in virtual time (median of {repeat} runs)")
    baseline_s, flown = timed(lambda: no_handover(load_scenario(SCENARIOS_DIR / SHIPPED[0])), repeat)
    minutes = flown / 60
    print(f"  baseline: the delivery flight, clean links, no handover: {baseline_s * 1000:7.1f} ms "
          f"({baseline_s / minutes * 1000:.1f} ms per simulated flight minute, {minutes:.2f} min flown)")
    for name in SHIPPED:
        s = load_scenario(SCENARIOS_DIR / name)
        wall, run = timed(lambda: run_scenario(s), repeat)
        clean_wall, _ = timed(lambda: run_scenario(clean(s)), repeat)
        report_wall, _ = timed(lambda: with_reports(s), repeat)
        m = flight_minutes(run)
        outcomes = ", ".join(f"{h.commander}->{h.partner} {h.result.outcome.name}" for h in run.handovers)
        print(f"  {s.region_method.value:9s} {wall * 1000:7.1f} ms per run  ({wall / m * 1000:5.1f} ms per simulated "
              f"flight minute, {m:.2f} min, {run.network_steps / wall:,.0f} network steps/s; {outcomes})")
        print(f"  {'':9s} {clean_wall * 1000:7.1f} ms with clean links; {report_wall * 1000:7.1f} ms with the reports "
              f"(MCAP + JSON + HTML);  x{wall / baseline_s:.1f} the baseline, x{report_wall / baseline_s:.1f} "
              f"with the reports")
    if args.profile:
        s = load_scenario(SCENARIOS_DIR / SHIPPED[0])
        profiler = cProfile.Profile()
        profiler.enable()
        run_scenario(s)
        profiler.disable()
        stats = pstats.Stats(profiler)
        total = stats.total_tt
        share = {}
        for (file, _, func), (_, _, _, cumulative, _) in stats.stats.items():
            for key, label in (("mission_computer.py", "_check"), ("polygon.py", "contains"), ("sim.py", "run_until"),
                               ("scenario_run.py", "_region_events")):
                if file.endswith(key) and func == label:
                    share[f"{key.split('.')[0]}.{label}"] = cumulative / total
        print("  where the time of one polygon run goes (cumulative share, under cProfile):")
        for label, part in sorted(share.items(), key=lambda kv: -kv[1]):
            print(f"    {part * 100:5.1f} %  {label}")
        out = io.StringIO()
        pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(8)
        print("\n".join("    " + line for line in out.getvalue().splitlines() if line.strip())[-2000:])


if __name__ == "__main__":
    main()
