"""The `mavconform` commands the README and the guide show, read from their Markdown.

Shell examples live in fenced ```sh blocks. A command may continue over lines ending in a
backslash, carry a `# comment`, run in the background (`&`) or be piped on; what is kept is
`mavconform` and its arguments. A synopsis line (`[--out DIR]`, `md|json`) stands for the
command with every optional part given and the first of each choice, so its options are
checked too; it is never run.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
SHELL_LANGUAGES = {"sh", "bash", "shell", "console"}
FENCE = re.compile(r"^(\s*)(`{3,})\s*([\w-]*)")
SHELL_OPERATORS = {"&", "&&", "|", "||", ";", ">", ">>", "2>&1", "<"}
PROGRAMS = ("mavconform", ".venv/bin/mavconform")


@dataclass(frozen=True)
class DocCommand:
    """One documented command: where it is, its arguments after `mavconform`, and whether it
    is a synopsis (optional parts and choices written out) rather than a runnable line."""
    source: str   # "docs/fuzzing.md:12"
    args: tuple[str, ...]
    synopsis: bool

    @property
    def text(self) -> str:
        return shlex.join(("mavconform",) + self.args)


def documents() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]


def shell_blocks(path: Path) -> list[tuple[int, list[str]]]:
    """(line number of the first line, lines) of each fenced shell block in `path`."""
    blocks: list[tuple[int, list[str]]] = []
    lines = path.read_text(encoding="utf-8").splitlines()
    i = 0
    while i < len(lines):
        opened = FENCE.match(lines[i])
        if not opened:
            i += 1
            continue
        indent, ticks, language = opened.groups()
        body, start = [], i + 2
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(ticks):
            body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i].lstrip())
            i += 1
        i += 1
        if language in SHELL_LANGUAGES:
            blocks.append((start, body))
    return blocks


def _logical_lines(start: int, body: list[str]) -> list[tuple[int, str]]:
    """Lines joined where one ends in a backslash, each with its first line's number."""
    out: list[tuple[int, str]] = []
    pending, first = "", start
    for offset, line in enumerate(body):
        if not pending:
            first = start + offset
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        out.append((first, pending + line))
        pending = ""
    if pending:
        out.append((first, pending))
    return out


def _arguments(tokens: list[str]) -> tuple[tuple[str, ...], bool]:
    """The arguments up to the first shell operator, a synopsis written out as a command."""
    args: list[str] = []
    synopsis = False
    for token in tokens:
        if token in SHELL_OPERATORS:
            break
        if token.startswith("[") or token.endswith("]"):
            synopsis = True
            token = token.strip("[]")
        if "|" in token:   # a choice: md|json
            synopsis = True
            token = token.split("|")[0]
        if token:
            args.append(token)
    return tuple(args), synopsis


def doc_commands() -> list[DocCommand]:
    """Every `mavconform` command in every shell block of the README and docs/."""
    found: list[DocCommand] = []
    for path in documents():
        where = path.relative_to(ROOT).as_posix()
        for start, body in shell_blocks(path):
            for number, line in _logical_lines(start, body):
                text = line.strip().removeprefix("$ ")
                if not text.startswith(PROGRAMS):
                    continue
                tokens = shlex.split(text, comments=True)
                if tokens[0] not in PROGRAMS:
                    continue
                args, synopsis = _arguments(tokens[1:])
                found.append(DocCommand(f"{where}:{number}", args, synopsis))
    return found
