"""`mavconform run`: the conformance suite against a target, clause by clause.

Prints one line per clause as it is decided (the requirement and the reason under every
clause that did not pass), then a summary, and writes run.json, run.junit.xml, run.md,
run.html and run.mcap to the report folder.

With --role gcs the suite plays the vehicle and judges a ground station or SDK instead (the
MIS.G.* clauses): a scripted vehicle on UDP 127.0.0.1 answers as the spec says except where a
clause's script drops, repeats, mistypes or refuses, and the GCS is told to upload, download,
clear or set current once per operation. The GCS under test is --target builtin:gcs (the
reference GCS, the default), gcs-mutant:NAME, or a command run per operation:
  --gcs-cmd 'CMD {port} {op} {file}'
where {port} is the scripted vehicle's UDP port on 127.0.0.1 (the GCS sends first; or
{gcs_port}: a free port on 127.0.0.1 the GCS listens on, the vehicle sending first), {op} is
upload, download, clear or set-current, and {file} a JSON job file naming the plan type, the
items (upload), the item (set-current) and where to write the result ({type} and {seq} are
there too). The command exits 0 when the GCS reported success; it is killed after
--gcs-timeout seconds. docs/gcs-conformance.md gives the job format and the adapters shipped
for the reference GCS, MAVSDK and MAVProxy (tools/gcs_adapters/).

An MSP flight controller (the MSP.* clauses: its waypoint store, seed 004 and INAV 9.1) is
judged when --target names one: builtin:msp (our model of INAV's, over TCP loopback),
msp-mutant:NAME, msp:tcp:HOST:PORT (INAV's SITL serves MSP on 5760 and 5761),
msp:serial:DEVICE[:BAUD] (115200 by default); docs/msp.md. The run reads the flight
controller's mission first and writes it back after; MSP.WP.09 saves to its non-volatile
storage and saves back what was there. Run it on a disarmed flight controller on the bench.

Exit codes: 0 every clause passed or is a known deviation (SHOULD failures count only with
--strict); 1 a clause failed unexpectedly, could not be decided, or the target did not
answer (with --baseline: only a clause that passed in the baseline and does not now);
2 a usage mistake; 130 interrupted.

Interrupted (Ctrl-C, or SIGTERM as CI cancel, `timeout` and `docker stop` send): the run
stops at the current clause, puts the target's plans back and writes every report, and
exits 130 for either signal (128 + SIGINT: "stopped on request, reports written", where a
143 would read as "killed"). run.json then says `run.interrupted: true`, where, and the
verdict "interrupted"; such a run is refused as --baseline. A second signal cannot cut the
restore or the reports short: it is honoured after them. A signal that comes after the
last clause, while the plans are put back, leaves the run complete, but still exits 130.
"""

from __future__ import annotations

import argparse
import sys
import textwrap
from typing import Any

from mavconform.conformance import document, suite
from mavconform.conformance.clause import Clause
from mavconform.conformance.outcome import ClauseResult, Outcome
from mavconform.conformance.gcs import suite as gcs_suite
from mavconform.conformance.msp import suite as msp_suite
from mavconform.conformance.msp import target as msp_target
from mavconform.conformance.msp.target import FORMS as MSP_FORMS
from mavconform.conformance.msp.target import is_msp_target
from mavconform.conformance.session import BUILTIN_CLOCK_SPEED
from mavconform.conformance.target_uri import FORMS
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.interrupts import InterruptGuard

from .options import clock_speed, time_scale

MARK = {Outcome.PASS: "PASS", Outcome.FAIL: "FAIL", Outcome.KNOWN_DEVIATION: "KNOWN",
        Outcome.NOT_APPLICABLE: "N/A", Outcome.SKIPPED: "SKIP", Outcome.ERROR: "ERROR"}


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("run", help="run the conformance suite against a target",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--role", choices=("vehicle", "gcs", "msp"), default=None,
                   help="which side the target plays: vehicle (default; the MIS.* and HO.* clauses), gcs "
                        "(the suite plays the vehicle; the MIS.G.* clauses) or msp (an MSP flight controller; "
                        "the MSP.* clauses; implied by an MSP --target)")
    p.add_argument("--target", metavar="URI",
                   help=f"what to test: {FORMS} (default builtin:spec: our reference vehicle "
                        f"over UDP loopback); with --role gcs: {gcs_suite.TARGET_FORMS} (default {gcs_suite.BUILTIN}); "
                        f"an MSP flight controller: {MSP_FORMS}")
    p.add_argument("--gcs-cmd", metavar="CMD",
                   help="with --role gcs: the GCS under test as a command run per operation, "
                        "'CMD {port} {op} {file}' (see above)")
    p.add_argument("--gcs-timeout", type=float, default=gcs_suite.DEFAULT_TIMEOUT_S, metavar="S",
                   help=f"with --role gcs: the bound on one operation; past it the GCS is stopped "
                        f"(default {gcs_suite.DEFAULT_TIMEOUT_S:g})")
    p.add_argument("--clauses", default="*", metavar="GLOB",
                   help="clause ids to run, comma-separated globs, e.g. 'MIS.UP.*,MIS.CLR.0?' (default all)")
    p.add_argument("--level", metavar="LEVELS", help="only these levels, e.g. MUST or MUST,SHOULD")
    p.add_argument("--strict", action="store_true", help="SHOULD failures fail the run too")
    p.add_argument("--profile", metavar="NAME|FILE",
                   help="what an external target is, when its HEARTBEAT cannot say (INAV reports a generic "
                        "autopilot): the builtin profile or profile file whose stored form the plans are "
                        "compared in (`mavconform profiles`; default: chosen from the HEARTBEAT)")
    p.add_argument("--expect", metavar="NAME|FILE",
                   help="expectations file (or bundled name) listing known deviations")
    p.add_argument("--baseline", metavar="RUN.json",
                   help="fail only on regressions: clauses that passed in this earlier run.json "
                        "(a complete run: an interrupted one is refused)")
    p.add_argument("--report-dir", default="reports/out", metavar="DIR",
                   help="where the reports go (default reports/out)")
    p.add_argument("--time-scale", type=time_scale, default=1.0, metavar="X",
                   help="stretch every protocol wait by X for slow links (default 1)")
    p.add_argument("--clock-speed", type=clock_speed, metavar="X",
                   help="a builtin: or mutant: target (with --role gcs: builtin:gcs or gcs-mutant:) and the "
                        "suite share one clock running X times real time: every timer, timeout and bound a "
                        f"clause judges is in its seconds (default {BUILTIN_CLOCK_SPEED:g}; 1: real time). "
                        "External targets and GCS commands live in real time")
    p.add_argument("--seed", type=int, default=0, help="seed recorded in the report (default 0)")
    p.add_argument("--allow-flight", action="store_true",
                   help="let progress clauses start the mission (always on for builtin targets)")
    p.add_argument("--handover-scenario", metavar="FILE|NAME",
                   help="the handover scenario the target's mission computer was loaded with (GCS ids, "
                        "coverages, dwell, bound): what the HO.SEQ clauses fly; a file, or a shipped "
                        "scenario's name (default: conformance, the one builtin:spec runs)")
    p.add_argument("--no-restore", action="store_true",
                   help="do not read the target's plans first and put them back afterwards")
    p.add_argument("-q", "--quiet", action="store_true", help="print only the summary")
    p.set_defaults(run=run)


EXIT_INTERRUPTED = 130


def run(args: argparse.Namespace) -> int:
    """Exit 130 on SIGINT or SIGTERM, once the plans are back and the reports written (see
    the module docstring); SIGTERM before or after the run raises KeyboardInterrupt, which
    the command line also turns into 130."""
    args.role = _role(args)
    with InterruptGuard():
        if args.role == "gcs":
            doc, outcome = _run_gcs(args)
        elif args.role == "msp":
            doc, outcome = _run_msp(args)
        else:
            _vehicle_only(args)
            options = document.RunOptions(target=args.target or "builtin:spec", clauses=args.clauses,
                                          strict=args.strict, time_scale=args.time_scale, seed=args.seed,
                                          expectations=args.expect, baseline=args.baseline,
                                          handover_scenario=args.handover_scenario, profile=args.profile,
                                          clock_speed=args.clock_speed)
            prepared = suite.prepare(options, levels=args.level, report_dir=args.report_dir)
            print(f"mavconform: {len(prepared.clauses)} clauses against {prepared.uri}", flush=True)
            on_result = None if args.quiet else _printer()
            allow = True if args.allow_flight else None
            doc, outcome = suite.execute(prepared, allow_flight=allow, restore=not args.no_restore,
                                         on_result=on_result)
        if outcome.unresponsive and outcome.identity is None:
            print(f"mavconform: target unresponsive: {outcome.unresponsive}", file=sys.stderr)
        _summary(doc, args.report_dir)
        if outcome.interrupted:
            by = f" by {outcome.interrupted_by}" if outcome.interrupted_by else ""
            print(f"mavconform: interrupted{by} during {outcome.interrupted_at}; the clauses not "
                  f"decided are marked skipped; plans: {doc['restore']['status']}", file=sys.stderr)
            return EXIT_INTERRUPTED
        if outcome.late_signal:
            print(f"mavconform: {outcome.late_signal} came after the last clause; the plans were put "
                  "back and the reports written first", file=sys.stderr)
            return EXIT_INTERRUPTED
        return 0 if doc["summary"]["verdict"] == "pass" else 1


def _role(args: argparse.Namespace) -> str:
    """--role as given, or as the target implies (an MSP target is the msp role)."""
    implied = "msp" if is_msp_target(args.target) else None
    if args.role is None:
        return implied or "vehicle"
    if args.role == "msp" and args.target is not None and implied is None:
        raise UsageError(f"--role msp: --target {args.target!r} is no MSP target ({MSP_FORMS})")
    if implied and args.role != "msp":
        raise UsageError(f"--target {args.target!r} is an MSP flight controller: its clauses are --role msp")
    return args.role


def _run_msp(args: argparse.Namespace) -> tuple[dict[str, Any], Any]:
    """An MSP flight controller: the options of a MAVLink vehicle run that mean nothing here are refused."""
    given = [flag for flag, value in (("--gcs-cmd", args.gcs_cmd),
                                      ("--gcs-timeout", args.gcs_timeout != gcs_suite.DEFAULT_TIMEOUT_S),
                                      ("--handover-scenario", args.handover_scenario),
                                      ("--allow-flight", args.allow_flight), ("--profile", args.profile),
                                      ("--clock-speed", args.clock_speed is not None)) if value]
    if given:
        raise UsageError(f"{given[0]} is not for an MSP flight controller (--role msp)")
    options = document.RunOptions(target=args.target or msp_target.BUILTIN, clauses=args.clauses,
                                  strict=args.strict, time_scale=args.time_scale, seed=args.seed,
                                  expectations=args.expect, baseline=args.baseline, role="msp")
    prepared = msp_suite.prepare(options, levels=args.level, report_dir=args.report_dir)
    print(f"mavconform: {len(prepared.clauses)} MSP clauses against {prepared.target}", flush=True)
    return msp_suite.execute(prepared, restore=not args.no_restore,
                             on_result=None if args.quiet else _printer())


def _vehicle_only(args: argparse.Namespace) -> None:
    given = [flag for flag, value in (("--gcs-cmd", args.gcs_cmd),
                                      ("--gcs-timeout", args.gcs_timeout != gcs_suite.DEFAULT_TIMEOUT_S))
             if value]
    if given:
        raise UsageError(f"{given[0]} is for --role gcs")


def _run_gcs(args: argparse.Namespace) -> tuple[dict[str, Any], Any]:
    """The GCS side: the options a vehicle run has that mean nothing here are refused."""
    given = [flag for flag, value in (("--handover-scenario", args.handover_scenario),
                                      ("--allow-flight", args.allow_flight), ("--no-restore", args.no_restore),
                                      ("--time-scale", args.time_scale != 1.0)) if value]
    if given:
        raise UsageError(f"{given[0]} is for --role vehicle (a GCS run has no vehicle of its own to fly, "
                         "restore or slow down; its bound is --gcs-timeout)")
    target = f"cmd:{args.gcs_cmd}" if args.gcs_cmd is not None else (args.target or gcs_suite.BUILTIN)
    options = document.RunOptions(target=target, clauses=args.clauses, strict=args.strict, seed=args.seed,
                                  expectations=args.expect, baseline=args.baseline, role="gcs",
                                  clock_speed=args.clock_speed)
    prepared = gcs_suite.prepare(options, target=args.target, command=args.gcs_cmd, levels=args.level,
                                 report_dir=args.report_dir, timeout_s=args.gcs_timeout)
    print(f"mavconform: {len(prepared.clauses)} GCS clauses against {prepared.adapter.describe()}", flush=True)
    return gcs_suite.execute(prepared, on_result=None if args.quiet else _printer())


def _printer():
    def show(clause: Clause, result: ClauseResult) -> None:
        print(f"  {MARK[result.outcome]:<5} {clause.id:<11} {clause.level.value:<6} {clause.title}", flush=True)
        if result.outcome is not Outcome.PASS or result.detail:
            if result.outcome in (Outcome.FAIL, Outcome.KNOWN_DEVIATION):
                print(textwrap.fill(f"requirement: {clause.requirement} [{clause.source}]",
                                    width=100, initial_indent=" " * 8, subsequent_indent=" " * 10))
            print(textwrap.fill(result.detail, width=100, initial_indent=" " * 8,
                                subsequent_indent=" " * 10), flush=True)
    return show


def reading_lines(doc: dict[str, Any], width: int = 100) -> list[str]:
    """The clauses not passing, in the reports' order (reports/reading_order.py): what fails
    the run, the known deviations with what excuses each, what else did not pass, then one
    line per reason for the clauses that do not apply or were skipped."""
    from mavconform.reports.reading_order import group_title, reading_order
    from mavconform.reports.text import one_line
    order = reading_order(doc)
    mark = {o.value: m for o, m in MARK.items()}
    out: list[str] = []
    for title, members in (("fails the run", order.failing), ("known deviations", order.deviations),
                           ("did not pass, does not fail the run", order.other)):
        if members:
            out.append(f"{title} ({len(members)}):")
            for c in members:
                head = f"  {mark[c['outcome']]:<5} {c['id']:<11} {c['level']:<6} "
                out.append(head + one_line(c["title"], width - len(head)))
                if c["outcome"] == Outcome.KNOWN_DEVIATION.value and c["expectation"]:
                    out.append("        excused: " + one_line(c["expectation"], width - 17))
    for group in order.groups:
        out.append(one_line(group_title(group), width))
        out += textwrap.wrap(", ".join(c["id"] for c in group.clauses), width,
                             initial_indent="  ", subsequent_indent="  ")
    return out


def _summary(doc: dict[str, Any], report_dir: str) -> None:
    from mavconform.reports.run_document import run_facts
    from mavconform.reports.text import dropped_text, flight_endings, identity_text, link_text, safety_alarm
    s = doc["summary"]
    ident, timing = doc["identity"], run_facts(doc)
    where = f" at {timing['address']}" if timing["address"] else ""
    if ident and "msp_api" in ident:
        who = identity_text(ident, address=timing["address"])
    else:
        who = f"system {ident['system']} component {ident['component']}{where}" if ident else "no HEARTBEAT"
    print(f"\ntarget {doc['run']['target']} ({who}); {timing['duration_s']:.1f} s")
    print("  outcome          clauses")
    for name in ("pass", "fail", "known-deviation", "not-applicable", "skipped", "error"):
        print(f"  {name:<16} {s[name]:>7}")
    print(f"  {'total':<16} {s['total']:>7}")
    for line in reading_lines(doc):
        print(line)
    gating = doc["gating"]
    if gating["mode"] == "baseline":
        print(f"baseline: {len(gating['regressions'])} regression(s)"
              + (f": {', '.join(gating['regressions'])}" if gating["regressions"] else "")
              + (f"; fixed since: {', '.join(gating['fixed'])}" if gating["fixed"] else ""))
    print(f"restore: {doc['restore']['status']}: {doc['restore']['detail']}")
    link = link_text(doc)
    if link is not None:
        print(f"link: {link}")
    dropped = dropped_text(doc)
    if dropped is not None:
        print(f"our receive queues: {dropped}")
    for line in flight_endings(doc):
        print(f"flight: {line}")
    alarm = safety_alarm(doc)
    if alarm is not None:
        print(f"\n!!! {alarm}\n", flush=True)
    print(f"verdict: {s['verdict'].upper()} ({s['gating_failures']} clause(s) fail the run); "
          f"reports in {report_dir}/")
