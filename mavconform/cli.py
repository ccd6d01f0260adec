"""`mavconform`: the command line. Each subcommand lives in its own module.

Exit codes: 0 success, 1 a finding (an operation failed, a target did not answer),
2 a usage mistake (bad option, URI or file), with one line saying what and where.
Every usage mistake, whether argparse or a command finds it, is one stderr line starting
with ERROR_PREFIX, so scripts and people look for one thing; argparse's lines then name the
subcommand whose parser refused ("mavconform: error: gcs upload: the following arguments
are required: --target"), as its messages do not say which command they are about.
"""

from __future__ import annotations

import argparse
import sys

from mavconform.reference_impl.errors import LocalProtocolError, UsageError

from . import (__version__, clauses_cmd, demo_cmd, fault_table_cmd, fuzz_cmd, gcs_cmd, handover_cmd, profiles_cmd,
               proxy_cmd, report_cmd, run_cmd, vectors_cmd, vehicle_cmd, bridge_cmd, fidelity_cmd)

EXIT_USAGE = 2
ERROR_PREFIX = "mavconform: error: "


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2 (argparse's own convention)
        command = self.prog.partition(" ")[2]   # "mavconform gcs upload" -> "gcs upload"
        self.exit(EXIT_USAGE, f"{ERROR_PREFIX}{command + ': ' if command else ''}{message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="mavconform",
        description="Conformance and fuzz test suite for MAVLink mission implementations: a "
                    "spec-exact reference vehicle and GCS, runnable over UDP, TCP and serial links.",
    )
    parser.add_argument("--version", action="version", version=f"mavconform {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True,
                                parser_class=_Parser)
    run_cmd.add_parser(sub)
    clauses_cmd.add_parser(sub)
    report_cmd.add_parser(sub)
    vehicle_cmd.add_parser(sub)
    gcs_cmd.add_parser(sub)
    demo_cmd.add_parser(sub)
    profiles_cmd.add_parser(sub)
    fault_table_cmd.add_parser(sub)
    fuzz_cmd.add_parser(sub)
    proxy_cmd.add_parser(sub)
    vectors_cmd.add_parser(sub)
    handover_cmd.add_parser(sub)
    bridge_cmd.add_parser(sub)
    fidelity_cmd.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except UsageError as exc:
        print(f"{ERROR_PREFIX}{exc}", file=sys.stderr)
        return EXIT_USAGE
    except LocalProtocolError as exc:  # our bug, not the user's nor the target's
        print(f"mavconform: internal error (please report it): {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:   # the reader stopped reading (`| head`): a normal way to end
        _silence_stdout()
        return 0


def _silence_stdout() -> None:
    """Point stdout at /dev/null, so the flush at exit does not raise on the closed pipe."""
    import os
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


if __name__ == "__main__":
    sys.exit(main())
