"""A message as the diagram shows it: every field, enum names beside numbers, wrapped.

A failure's text cites fields ("MISSION_CURRENT{seq=0, total=3, ...}", "x=473977460"), so
the label uses the wire's field names and hides none: a label cut to one line hid exactly
the values the verdict was about. Fields come in the message's definition order, with the
addressing fields (target_system, target_component) last; enum-valued ones read
`frame=3 (MAV_FRAME_GLOBAL_RELATIVE_ALT)` (see enum_names).
"""

from __future__ import annotations

from typing import Any

from mavconform.reports.enum_names import field_order, field_value_name
from mavconform.reports.run_document import NOTE
from mavconform.reports.text import one_line, value_text

ADDRESSING = ("target_system", "target_component")


def field_tokens(event: dict[str, Any]) -> list[str]:
    """["seq=0", "frame=3 (MAV_FRAME_GLOBAL_RELATIVE_ALT)", ...]: one per field, all fields."""
    fields = event["fields"]
    known = [name for name in field_order(event["msg"]) if name in fields]
    order = [n for n in known if n not in ADDRESSING]
    order += sorted(n for n in fields if n not in known and n not in ADDRESSING)
    order += [n for n in ADDRESSING if n in fields]
    tokens = []
    for name in order:
        value = fields[name]
        text = f"{one_line(name)}={one_line(value_text(value))}"
        enum_name = field_value_name(event["msg"], name, value)
        tokens.append(f"{text} ({enum_name})" if enum_name else text)
    return tokens


def full_label(event: dict[str, Any]) -> str:
    """The whole label on one line (a tooltip, a test's haystack): "MSG k=v k=v (NAME)"."""
    if event["dir"] == NOTE:
        return one_line(event["msg"])
    return " ".join([one_line(event["msg"]), *field_tokens(event)])


def wrap(tokens: list[str], width: int) -> list[str]:
    """Tokens joined with spaces into lines of at most `width` characters; a token longer
    than a line is broken inside (a long STATUSTEXT), never cut."""
    width = max(width, 8)
    lines: list[str] = []
    line = ""
    for token in tokens:
        while len(token) > width:
            if line:
                lines.append(line)
                line = ""
            lines.append(token[:width])
            token = token[width:]
        if not line:
            line = token
        elif len(line) + 1 + len(token) <= width:
            line += " " + token
        else:
            lines.append(line)
            line = token
    if line:
        lines.append(line)
    return lines
