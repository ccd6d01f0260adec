"""MkDocs hook: the command reference page, generated from the argparse parsers.

`docs/reference/commands.md` holds a marker; at build time it becomes every command's and
subcommand's `--help`, so the reference says exactly what the installed parsers accept and
cannot drift from them. (mkdocs-argparse, the one plugin for this on PyPI, is a single 0.0.1
release; a hook is the 40 lines MkDocs itself documents for such a job.)
"""

from __future__ import annotations

import argparse
import os
from typing import Iterator

MARKER = "<!-- generated: every command's --help -->"
PAGE = "reference/commands.md"
WIDTH = "80"    # columns argparse wraps to: the same page on every machine, no sideways scrolling


def _subcommands(parser: argparse.ArgumentParser) -> list[tuple[str, argparse.ArgumentParser, str]]:
    """(name, parser, one-line help) of `parser`'s subcommands, in the order they were added."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            seen: set[int] = set()
            out = []
            for name, sub in action.choices.items():
                if id(sub) not in seen:   # an alias names the same parser again
                    seen.add(id(sub))
                    out.append((name, sub, helps.get(name, "")))
            return out
    return []


def _walk(parser: argparse.ArgumentParser, depth: int = 2) -> Iterator[str]:
    for name, sub, summary in _subcommands(parser):
        yield f"{'#' * depth} `{sub.prog}`\n"
        if summary:
            yield f"{summary}\n"
        yield f"```text\n{sub.format_help().rstrip()}\n```\n"
        yield from _walk(sub, min(depth + 1, 4))


def command_reference() -> str:
    """Markdown: the top-level `--help`, then each command's, nested commands under theirs."""
    from mavconform.cli import build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = WIDTH
    try:
        parser = build_parser()
        parts = [f"```text\n{parser.format_help().rstrip()}\n```\n", *_walk(parser)]
    finally:
        if previous is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = previous
    return "\n".join(parts)


def on_page_markdown(markdown: str, page, config, files) -> str:   # MkDocs' hook signature
    if page.file.src_uri != PAGE:
        return markdown
    if MARKER not in markdown:
        raise ValueError(f"docs/{PAGE}: the marker {MARKER!r} is missing")
    return markdown.replace(MARKER, command_reference())
