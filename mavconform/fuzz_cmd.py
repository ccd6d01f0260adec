"""`mavconform fuzz`: a fuzz campaign against a target, or the replay of one saved case."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from mavconform.fuzz.campaign import (MODES, RESTART_TIMEOUT, CampaignInterrupted, CampaignOptions, Progress,
                                      load_mode, parse_duration, replay_recorded, run_campaign)
from mavconform.conformance.target_uri import parse_target
from mavconform.fuzz.case import load_case
from mavconform.fuzz.outcomes import TargetUnresponsive, ToolError
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.interrupts import InterruptGuard

from .options import seconds_up_to

EXIT_FINDING = 1
EXIT_TOOL_ERROR = 3
EXIT_INTERRUPTED = 130   # 128 + SIGINT, as shells report Ctrl-C

DESCRIPTION = """\
Fuzz a mission implementation and save what breaks it.

  protocol  a Hypothesis state machine plays GCS operations (upload, download, clear,
            set-current of every plan type, cancels, a second GCS, stray and malformed
            messages, edge-value items) and link faults against the target, and checks
            invariants after every step: atomic uploads, exactly one result per operation,
            both ends back to idle, retries within limits, download == last accepted upload,
            the vehicle still answers.
            With --operator-control the vehicle is also an operator-control system manager
            (MAV_CMD_REQUEST_OPERATOR_CONTROL, CONTROL_STATUS) and the GCSs request,
            release and hand over control and fall silent for a while; the safety
            properties are invariants too: never two owners, nothing a GCS not in control
            sends takes effect, control changes only by a grant, a release or owner loss,
            CONTROL_STATUS tells the truth, every request answered once in bounded time,
            a silent owner is dropped.
  frames    byte-level mutations of valid mission frames and garbage (bad CRC, bad length,
            truncation, bad magic, unknown ids, v1/v2 mixing, incompat flags, wrong-key and
            stale signatures, bytes between frames); the target must keep sending HEARTBEAT,
            still serve a normal download, and (in-process) neither raise nor change its plans.
            Over tcp: the frames go at 5760 bytes/s (a 57600-baud radio: INAV's SITL loses
            bytes of a faster burst), over serial: at the line's baud rate.

In-process targets (builtin:, mutant:) run in virtual time: fast, and every case replays
exactly. Each finding is shrunk and saved as FINDINGS/NAME.json (the case: seed and steps)
with NAME.mcap (the capture of its replay); `mavconform fuzz --replay FINDINGS/NAME.json`
runs it again. The campaign also writes fuzz.json / .junit.xml / .md / .html to --report-dir,
one row per invariant.

A real target (udp:, udpin:, tcp:, tcpin:, serial:) is judged by the rules of --profile, by
default the builtin profile of the autopilot its HEARTBEAT names (px4, ardupilot; else the
spec; INAV says "generic": give --profile inav). In protocol mode the profile also sets what
is fuzzed: a plan type, message or operation it documents the vehicle does not have (INAV:
fence and rally, the _INT forms, set-current, empty uploads) is left out, and the header
says so (fuzz/protocol/scope.py). A target that
stops answering is a target-crash (no HEARTBEAT either) or target-hang finding: the campaign
stops and saves the last steps with the capture of the live traffic. Replaying and
minimising it needs the target restarted: give --restart-cmd, run (bounded) before every
attempt; without it the case is saved unminimised and says so.

Ctrl-C or SIGTERM (a CI cancel, `timeout`, `docker stop`) ends a campaign as its budget
would, at once: the findings seen so far are saved (shrunk as far as the search had got, not
minimised; over UDP with the live capture, not replayed), the summary is printed and the
reports are written, marked interrupted (run.interrupted, fuzz.interrupted) with the verdict
"fail" if something was found, else "interrupted". A second signal while the reports are
written waits for them, so no report is left half-written.

Exit codes: 0 no finding; 1 a finding (or, with --replay, the case still fails), or the
target never answered; 2 usage; 3 a tool error (a bug in mavconform: the steps that led to
it are saved for the bug report); 130 interrupted (Ctrl-C or SIGTERM), findings or not.
"""

EPILOG = """\
examples:
  mavconform fuzz --target builtin:spec --mode protocol --examples 200 --seed 1
  mavconform fuzz --target builtin:spec --mode frames --time 60s
  mavconform fuzz --target mutant:non-atomic-upload --examples 100     # a planted bug: found
  mavconform fuzz --operator-control --examples 300 --seed 1                   # operator control too
  mavconform fuzz --operator-control --target mutant:screens-commands-only     # a non-owner's write: found
  mavconform fuzz --target udpin:14550 --mode frames --time 5m          # a SITL that sends to us
  mavconform fuzz --target udpin:14550 --time 5m --restart-cmd './restart-sitl.sh'
  mavconform fuzz --replay fuzz-findings/protocol-atomic-upload-1a2b3c4d5e.json
across cores and machines: pytest --pyargs mavconform.fuzz -n auto --fuzz-target builtin:spec (docs/fuzzing.md)
"""

DEFAULT_EXAMPLES = 100


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fuzz", help="fuzz a target (protocol or frames) and save shrunk, replayable findings",
                       description=DESCRIPTION, epilog=EPILOG,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--target", default="builtin:spec", metavar="URI",
                   help="builtin:PROFILE (spec, px4, ardupilot, ...: `mavconform profiles`), mutant:NAME, "
                        "udp:HOST:PORT or udpin:[HOST:]PORT (default builtin:spec)")
    p.add_argument("--mode", choices=MODES, default="protocol", help="what to fuzz (default protocol)")
    p.add_argument("--examples", type=_count, metavar="N",
                   help=f"stop after N examples (default {DEFAULT_EXAMPLES} unless --time is given)")
    p.add_argument("--time", type=_duration, metavar="DURATION",
                   help="stop after this wall time, e.g. 60s, 5m, 1h (with --examples: whichever comes first)")
    p.add_argument("--seed", type=int, default=0, help="campaign seed: the same seed runs the same examples (default 0)")
    p.add_argument("--findings", default="fuzz-findings", metavar="DIR",
                   help="where shrunk findings are saved (default fuzz-findings)")
    p.add_argument("--report-dir", default="reports/fuzz", metavar="DIR",
                   help="where fuzz.json/.junit.xml/.md/.html go (default reports/fuzz)")
    p.add_argument("--database", default=".hypothesis/fuzz", metavar="DIR|none|redis://HOST:PORT",
                   help="Hypothesis example database shared by campaigns: a directory (default "
                        ".hypothesis/fuzz), 'none', or a Redis server for a fleet of machines")
    p.add_argument("--profile", metavar="NAME|FILE",
                   help="external targets (udp:, tcp:, serial: ...): the vehicle profile whose rules the oracles apply (home in "
                        "slot 0, compact storage, non-atomic upload, retries); default: from the "
                        "HEARTBEAT autopilot (px4, ardupilot), else spec")
    p.add_argument("--restart-cmd", metavar="CMD",
                   help="shell command that restarts a target that died, so its case can be replayed "
                        "and minimised (run before every attempt, bounded by --restart-timeout)")
    p.add_argument("--restart-timeout", type=seconds_up_to(3600), default=RESTART_TIMEOUT, metavar="S",
                   help=f"longest a --restart-cmd may run, and then the wait for HEARTBEAT "
                        f"(default {RESTART_TIMEOUT:g})")
    p.add_argument("--operator-control", dest="handover", action="store_true",
                   help="protocol mode: fuzz operator control too (requests, releases, takeovers, GCS "
                        "loss; never two owners, nothing from a non-owner executed, ...). builtin: and "
                        "mutant: vehicles are built as their own system manager; an external target "
                        "must already send CONTROL_STATUS (else a usage error, exit 2)")
    p.add_argument("--replay", metavar="CASE.json",
                   help="run one saved case again (target and mode come from the case)")
    p.add_argument("--capture", metavar="FILE.mcap", help="with --replay: record the replay to this MCAP file")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress line; only the summary")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    with InterruptGuard(once=False):   # a CI cancel (SIGTERM) stops a campaign as Ctrl-C does
        if args.replay:
            return _replay(args)   # interrupted: KeyboardInterrupt, 130 (the capture is closed)
        return _campaign(args)


def _campaign(args: argparse.Namespace) -> int:
    if args.capture:
        raise UsageError("--capture goes with --replay (a campaign saves each finding's capture itself)")
    from mavconform.fuzz.report import campaign_document, replay_command
    from mavconform.reports.write import write_reports

    parse_target(args.target)   # a bad address says so before any banner or folder appears
    if args.handover and args.mode != "protocol":
        raise UsageError("--operator-control applies to --mode protocol (operator control is fuzzed as GCS "
                         f"operations, not as {args.mode})")
    for option, folder in (("--findings", args.findings), ("--report-dir", args.report_dir)):
        _writable(option, folder)   # before the search: a finding must never be lost to a bad path
    examples = args.examples if args.examples is not None or args.time is not None else DEFAULT_EXAMPLES
    options = CampaignOptions(target=args.target, mode=args.mode, seed=args.seed, examples=examples,
                              time_s=args.time, findings_dir=args.findings,
                              database=open_database(args.database), profile=args.profile,
                              restart_cmd=args.restart_cmd, restart_timeout=args.restart_timeout,
                              handover=args.handover)
    budget = " and ".join(x for x in (f"{examples} examples" if examples is not None else "",
                                      f"{args.time:g} s" if args.time is not None else "") if x)
    control = ", operator control on (--operator-control)" if args.handover else ""
    print(f"mavconform fuzz: {args.mode} mode against {args.target}{control}, seed {args.seed}, "
          f"budget {budget}", flush=True)
    scope = _scope(args) if args.mode == "protocol" else None
    if scope is not None and not scope.whole:
        print(f"  fuzzed: {scope.describe()}", flush=True)
    unit = "steps" if args.mode == "protocol" else "frames"
    bar = None if args.quiet else ProgressLine(unit, sys.stderr)
    try:
        result = run_campaign(options, bar)
    except CampaignInterrupted as exc:
        result = exc.result
    except KeyboardInterrupt:      # before the search began (the campaign raises the above after)
        print("mavconform fuzz: interrupted before the search began; nothing was fuzzed", file=sys.stderr)
        return EXIT_INTERRUPTED
    except TargetUnresponsive as exc:
        print(f"mavconform: target unresponsive: {exc}; nothing was fuzzed", file=sys.stderr)
        return EXIT_FINDING
    except ToolError as exc:
        saved = getattr(exc, "saved", None)
        print(f"mavconform fuzz: tool error (a bug in mavconform, not a finding about the target): "
              f"{exc.failure.error}", file=sys.stderr)
        if saved is not None:
            print(f"  the steps that led to it: {saved} (traceback: {saved.with_suffix('.txt')}); "
                  f"replay: mavconform fuzz --replay {saved}", file=sys.stderr)
        return EXIT_TOOL_ERROR
    finally:
        if bar is not None:
            bar.done()
    with InterruptGuard(held=True) as late:   # a signal now waits: no report is left half-written
        doc = campaign_document(result)
        paths = write_reports(doc, args.report_dir, basename="fuzz")
    rate = result.examples / result.duration_s if result.duration_s > 0 else 0.0
    urate = result.units / result.duration_s if result.duration_s > 0 else 0.0
    print(f"\n{result.examples} examples (shrinking included), {result.units} {unit} in {result.duration_s:.1f} s "
          f"({rate:.1f} examples/s, {urate:.0f} {unit}/s)")
    checked = ", ".join(result.invariants) or "(the mode's oracles)"
    print(f"invariants checked: {checked}")
    if result.interrupted:
        by = f" by {result.interrupted_by}" if result.interrupted_by else ""
        print(f"interrupted{by} during {result.interrupted_at}: the search did not finish; "
              f"verdict {doc['summary']['verdict']}")
    if not result.findings:
        print(f"findings: none; reports in {paths['json'].parent}/")
        return _interrupted(result.interrupted_at) if result.interrupted or late.received else 0
    print(f"findings: {len(result.findings)}")
    for f in result.findings:
        print(f"  {f.case.violation}")
        print(f"    {len(f.case.steps)} step(s), saved {f.path} (+ {f.capture.name if f.capture else 'no capture'})"
              + ("" if f.reproduced or f.note else "  [WARNING: its replay did not reproduce it]"))
        if f.note:
            print(f"    {f.note}")
        print(f"    replay: {replay_command(f)}")
    print(f"reports in {paths['json'].parent}/")
    return _interrupted(result.interrupted_at) if result.interrupted or late.received else 1


def _interrupted(where: str | None) -> int:
    if where is None:   # the signal came while the reports were written: they are whole
        print("mavconform fuzz: interrupted after the campaign had finished; its reports are complete",
              file=sys.stderr)
    else:
        print(f"mavconform fuzz: interrupted during {where}; the findings seen are saved and the "
              "reports written, marked interrupted", file=sys.stderr)
    return EXIT_INTERRUPTED


def _replay(args: argparse.Namespace) -> int:
    if args.examples is not None or args.time is not None or args.restart_cmd or args.profile or args.handover:
        raise UsageError("--replay runs one saved case: --examples, --time, --profile and --restart-cmd "
                         "do not apply, nor does --operator-control (the case names its profile and whether "
                         "operator control was on; restart the target yourself)")
    case = load_case(args.replay)
    mode = load_mode(case.mode)
    print(f"mavconform fuzz: replaying {args.replay} ({case.mode} mode, {len(case.steps)} step(s), "
          f"seed {case.seed}) against {case.target}", flush=True)
    if case.violation is not None:
        print(f"  recorded: {case.violation}")
    try:
        violation, _ = replay_recorded(mode, case, Path(args.capture) if args.capture else None)
    except UsageError as exc:
        raise UsageError(f"{args.replay}: {exc}") from None
    except TargetUnresponsive as exc:
        print(f"mavconform: target unresponsive: {exc}; nothing was replayed (restart it first)",
              file=sys.stderr)
        return EXIT_FINDING
    if violation is None:
        print("  replayed: no invariant broke (fixed, or the target differs from the one it was found on)")
        return 0
    same = case.violation is not None and violation.invariant == case.violation.invariant
    print(f"  replayed: {violation}" + ("" if same or case.violation is None else "  (a different invariant)"))
    if args.capture:
        print(f"  capture: {args.capture}")
    return 1


def _scope(args: argparse.Namespace):
    """The protocol fuzzer's scope where it is known before the search (a builtin target's
    profile, or --profile); a remote target's comes from its HEARTBEAT later."""
    from mavconform.fuzz.protocol.world import profile_from
    uri = parse_target(args.target)
    name = args.profile if args.profile else uri.name if uri.kind == "builtin" else None
    return None if name is None else profile_from(name, f"profile {name}").scope


def _writable(option: str, folder: str) -> None:
    path = Path(folder)
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / ".mavconform-write-test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise UsageError(f"{option} {folder}: cannot write there ({exc.strerror or exc})") from None


REDIS_CONNECT_TIMEOUT = 3.0      # s to reach a fleet's Redis server, and for each command after


def _redis_database(url: str) -> Any:
    """A fleet's shared database, checked once with a PING (bounded): a server that cannot be
    reached is the user's address, a one-line error, not a tool error mid-campaign."""
    import redis
    from hypothesis.extra.redis import RedisExampleDatabase
    try:
        client = redis.Redis.from_url(url, socket_connect_timeout=REDIS_CONNECT_TIMEOUT,
                                      socket_timeout=REDIS_CONNECT_TIMEOUT)
        client.ping()
    except ValueError as exc:
        raise UsageError(f"--database {url}: not a Redis address ({exc})") from None
    except redis.exceptions.RedisError as exc:
        raise UsageError(f"--database {url}: cannot reach the Redis server ({exc})") from None
    return RedisExampleDatabase(client)


def open_database(spec: str) -> Any:
    """'none', a directory, or redis://HOST:PORT -> a Hypothesis ExampleDatabase (or None)."""
    from hypothesis.database import DirectoryBasedExampleDatabase

    text = spec.strip()
    if text.lower() == "none":
        return None
    if text.startswith("redis://"):
        return _redis_database(text)
    if "://" in text:
        raise UsageError(f"--database {spec!r}: expected a directory, 'none' or redis://HOST:PORT")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise UsageError(f"--database {spec}: exists and is not a directory")
    try:   # Hypothesis would fail to write into it silently: make sure it can be written
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"--database {spec}: cannot create the directory ({exc.strerror or exc})") from None
    return DirectoryBasedExampleDatabase(str(path))


class ProgressLine:
    """One status line: examples, rate, units, findings. Redrawn in place on a terminal (at
    most 5 times a second); elsewhere (CI logs) printed every 10 s."""

    def __init__(self, unit: str, stream: Any) -> None:
        self.unit = unit
        self.stream = stream
        self.tty = bool(getattr(stream, "isatty", lambda: False)())
        self.every = 0.2 if self.tty else 10.0
        self.last = 0.0
        self.shown = False

    def __call__(self, p: Progress) -> None:
        now = time.monotonic()
        if now - self.last < self.every:
            return
        self.last = now
        self._show(p)

    def _show(self, p: Progress) -> None:
        t = max(p.elapsed, 1e-9)
        text = (f"{p.examples} examples ({p.examples / t:.1f}/s)  {p.units} {self.unit} "
                f"({p.units / t:.0f}/s)  findings {p.findings}  {p.elapsed:.0f} s")
        if self.tty:
            self.stream.write("\r" + text.ljust(79))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
        self.shown = True

    def done(self) -> None:
        if self.tty and self.shown:
            self.stream.write("\n")
            self.stream.flush()


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be at least 1")
    return value


def _duration(text: str) -> float:
    try:
        return parse_duration(text)
    except UsageError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None

