"""Issue 29, item 3: every command the README and the guide show is real.

The commands are read from the Markdown (tests/docs/markdown_commands.py), never copied here.
Every one must parse with the installed parsers, options and choices included, so a renamed
or removed option fails here before a reader meets it. Those that need nothing but this
repository (a builtin or mutant target, no file the reader brings, no peer to serve) are run
as written, each in a fresh folder, and must end as the page says: 0, or 1 where the target is
a mutant (the planted bug is found), with no usage error and no traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from mavconform.cli import ERROR_PREFIX, build_parser

from .markdown_commands import ROOT, DocCommand, doc_commands

COMMANDS = doc_commands()
RUNNABLE = {"run", "clauses", "profiles", "fuzz", "fidelity", "handover", "fault-table", "report"}
OUR_TARGETS = ("builtin:", "mutant:", "gcs-mutant:")
MUTANTS = ("mutant:", "gcs-mutant:")
OUTPUT_OPTIONS = {"--report-dir", "--output", "--html", "--md", "--out", "--capture", "--database"}
FILE_SUFFIXES = (".json", ".toml", ".plan", ".waypoints", ".yaml", ".yml", ".mcap", ".xml")
PLACEHOLDER = re.compile(r"(?<![\w-])[A-Z][A-Z0-9_]+\b")   # a metavar: HEX, URI, FILE
SIDE_BY_SIDE = 8   # commands at once
TIMEOUT = 300.0   # s: the longest documented example takes a small part of this; a hang fails


def _subparser(parser: argparse.ArgumentParser, args: tuple[str, ...]) -> argparse.ArgumentParser:
    """The (sub)command parser the leading words of `args` select."""
    for word in args:
        choices = next((a.choices for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
        if not choices or word not in choices:
            break
        parser = choices[word]
    return parser


def _without_placeholders(parser: argparse.ArgumentParser, args: tuple[str, ...]) -> list[str]:
    """`args` less each `--option METAVAR` pair a synopsis writes with the option's own
    placeholder (`--signing-key HEX`) where the option checks its value: the option exists,
    and its value is the reader's. (An unchecked or required one keeps its placeholder.)"""
    options = _subparser(parser, args)._option_string_actions
    out, i = [], 0
    while i < len(args):
        action = options.get(args[i])
        if (action is not None and action.type is not None and not action.required and i + 1 < len(args)
                and args[i + 1] in (action.metavar, action.dest.upper())):
            i += 2
            continue
        out.append(args[i])
        i += 1
    return out


def _parse(command: DocCommand):
    parser = build_parser()
    args = _without_placeholders(parser, command.args) if command.synopsis or PLACEHOLDER.search(command.text) \
        else list(command.args)
    return parser.parse_args(args)


def _inputs(command: DocCommand) -> list[str]:
    """The arguments that name a file the command reads."""
    out, args = [], command.args
    for i, arg in enumerate(args):
        if arg.startswith("-") or (i and args[i - 1] in OUTPUT_OPTIONS):
            continue
        if arg.endswith(FILE_SUFFIXES) or ("/" in arg and ":" not in arg):
            out.append(arg)
    return out


def _in_repository(path: str) -> bool:
    """A file the repository holds (not one a run writes, such as reports/out/run.json)."""
    tracked = subprocess.run(["git", "ls-files", "--error-unmatch", path], cwd=ROOT,
                             capture_output=True, check=False)
    return tracked.returncode == 0


def why_not_run(command: DocCommand) -> str | None:
    """None when the command needs nothing but this repository, else why it is only parsed."""
    if command.synopsis:
        return "a synopsis"
    try:
        with contextlib.redirect_stderr(io.StringIO()):
            args = _parse(command)
    except SystemExit:
        return "it does not parse (test_every_documented_command_parses says why)"
    if args.command not in RUNNABLE:
        return f"`{args.command}` serves or drives a peer"
    target = getattr(args, "target", None)
    if target is not None and not str(target).startswith(OUR_TARGETS):
        return f"its target {target} is not ours"
    if getattr(args, "gcs_cmd", None):
        return "it drives the reader's GCS"
    if str(getattr(args, "database", "")).startswith("redis://"):
        return "it needs the reader's Redis server"
    missing = [p for p in _inputs(command) if not _in_repository(p)]
    if missing:
        return f"it reads the reader's {', '.join(missing)}"
    return None


def _id(command: DocCommand) -> str:
    return f"{command.source} {command.text}"


@pytest.mark.parametrize("command", COMMANDS, ids=_id)
def test_every_documented_command_parses(command: DocCommand, capsys) -> None:
    try:
        _parse(command)
    except SystemExit:
        pytest.fail(f"{command.source}: `{command.text}` does not parse: {capsys.readouterr().err.strip()}")


RUNS = list({c.args: c for c in reversed(COMMANDS) if why_not_run(c) is None}.values())[::-1]   # each once


def _run(command: DocCommand, folder: Path) -> str | None:
    """Run `command` as written in `folder`; None when it ended as the page says, else what happened."""
    folder.mkdir()
    for path in _inputs(command):   # the repository's files, where the command expects them
        (folder / path).parent.mkdir(parents=True, exist_ok=True)
        (folder / path).symlink_to(ROOT / path)
    target = str(getattr(_parse(command), "target", None) or "")
    expected = 1 if target.startswith(MUTANTS) else 0
    try:
        done = subprocess.run([sys.executable, "-m", "mavconform", *command.args], cwd=folder,
                              capture_output=True, text=True, timeout=TIMEOUT, check=False,
                              env={**os.environ, "PYTHONWARNINGS": "ignore"})
    except subprocess.TimeoutExpired:
        return f"{command.source}: `{command.text}` still running after {TIMEOUT:.0f} s"
    if "Traceback" in done.stderr or done.stderr.startswith(ERROR_PREFIX) or done.returncode != expected:
        return (f"{command.source}: `{command.text}` exited {done.returncode} (expected {expected})\n"
                f"{done.stdout[-1200:]}\n{done.stderr[-1200:]}")
    return None


def test_every_documented_command_against_our_targets_runs_as_written(tmp_path: Path) -> None:
    """Side by side: most of them wait on the targets' timers, not on the CPU."""
    with ThreadPoolExecutor(max_workers=SIDE_BY_SIDE) as pool:
        failures = [f for f in pool.map(lambda ic: _run(ic[1], tmp_path / str(ic[0])), enumerate(RUNS)) if f]
    assert not failures, f"{len(failures)} of {len(RUNS)} documented commands:\n\n" + "\n\n".join(failures)


def test_the_guide_shows_commands_and_runs_some() -> None:
    """The collector finds what the pages hold: a broken fence or prefix would empty both lists."""
    assert len(COMMANDS) >= 60 and len(RUNS) >= 15
    assert {c.source.split(":")[0] for c in RUNS} >= {"docs/testing-a-vehicle.md", "docs/fuzzing.md"}


def test_the_readme_stays_a_front_page() -> None:
    """Issue 29: what the project is, the two commands, a tour and help; the rest is the guide."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 150
    assert "```sh\nmake run\n```" in readme and "```sh\nmake test\n```" in readme
