"""A user's profile file written for a test (the loader reads files, not strings)."""

from __future__ import annotations


def write_profile(tmp_path, text: str, name: str = "mine.toml") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)
