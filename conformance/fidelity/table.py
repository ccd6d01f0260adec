"""The matrices for people: Markdown tables a maintainer can paste into an issue (frames ×
plan-type item kinds; commands × params, one row per command listing every probe that did not
come back as sent), and the same words for the terminal."""

from __future__ import annotations

from typing import Any

from .cells import FENCE_CIRCLE, FENCE_RETURN, FENCE_VERTEX, FRAME_NAMES, RALLY_POINT, entry_key
from .command_facts import COMMANDS

COLUMNS = (("mission", 16, "mission waypoint"), ("fence", FENCE_VERTEX, "fence vertex"),
           ("fence", FENCE_CIRCLE, "fence circle"), ("fence", FENCE_RETURN, "fence return point"),
           ("rally", RALLY_POINT, "rally point"))


def short(cls: str | None) -> str:
    """A class for a table: "refused X", "INT twin", a rule named by its id alone (run.json and
    the legend under the table have it whole)."""
    if cls is None:
        return "-"
    if cls.startswith("refused:"):
        return "refused " + cls.removeprefix("refused:")
    text = cls.replace("changed:", "changed: ").replace("int_twin", "INT twin")
    head, rule = text.split(" (rule: ", 1) if " (rule: " in text else (text, "")
    return head + (f" (rule: {rule_id(rule.removesuffix(')'))})" if rule else "")


def rule_id(rule: str) -> str:
    """`upstream` or `<storage> storage` for a rule's whole text."""
    return "upstream" if rule.startswith("upstream") else rule.split(" item storage")[0] + " storage"


def legend(fidelity: dict[str, Any]) -> list[str]:
    """Each rule the cells name, by id, with what it is: upstream's whole text, or the
    profile's storage form and where the profile has it (`basis`)."""
    rules = {}
    for e in fidelity["cells"]:
        if " (rule: " in e["class"]:
            whole = e["class"].split(" (rule: ", 1)[1][:-1]
            rules[rule_id(whole)] = whole if whole.startswith("upstream") else \
                f"{whole} of the profile ({fidelity.get('basis') or fidelity['profile']})"
    return [f"- rule {k}: {v}" for k, v in sorted(rules.items())]


def cell_text(entry: dict[str, Any]) -> str:
    text = short(entry["class"])
    if entry.get("as_predicted") is False:
        text += f" ⚠ profile: {short(entry['predicted'])}"
    return text


def unlike(cells: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The cells that came out otherwise than the profile predicted."""
    return [e for e in cells if e.get("as_predicted") is False]


def as_sent(cls: str) -> bool:
    return cls in ("exact", "int_twin")


def markdown(fidelity: dict[str, Any]) -> str:
    frame_cells = [e for e in fidelity["cells"] if not e.get("probe")]
    command_cells = [e for e in fidelity["cells"] if e.get("probe")]
    out = [f"{len(fidelity['cells'])} cells, {fidelity['uploads']} uploads; profile {fidelity['profile']}: "
           f"{len(unlike(fidelity['cells']))} cell(s) unlike its prediction (⚠)", ""]
    if frame_cells:
        out += _frames(frame_cells) + [""]
    if command_cells:
        out += _commands(command_cells) + [""]
    out += legend(fidelity)
    return "\n".join(out) + "\n"


def _frames(cells: list[dict[str, Any]]) -> list[str]:
    by = {entry_key(e)[:3]: e for e in cells}
    out = [f"### Frames × plan types ({len(cells)} cells)", "",
           "| frame | " + " | ".join(title for _, _, title in COLUMNS) + " |",
           "|---|" + "---|" * len(COLUMNS)]
    for f in sorted({e["frame"] for e in cells}):
        row = [cell_text(by[(pt, f, cmd)]) if (pt, f, cmd) in by else "" for pt, cmd, _ in COLUMNS]
        out.append(f"| {f} {FRAME_NAMES.get(f, '')} | " + " | ".join(c.replace("|", "\\|") for c in row) + " |")
    return out


def refused_as_such(cells: list[dict[str, Any]]) -> dict[str, list[int]]:
    """The commands whose nominal item was refused, as predicted, by refusal: one line each in
    the tables rather than a row of empty cells."""
    out: dict[str, list[int]] = {}
    for e in cells:
        if e.get("probe") == "nominal" and e["class"].startswith("refused:") and e.get("as_predicted") is not False:
            out.setdefault(e["class"], []).append(e["command"])
    return out


def command_name(command: int) -> str:
    return f"{command} {COMMANDS[command].name}" if command in COMMANDS else str(command)


def _commands(cells: list[dict[str, Any]]) -> list[str]:
    """One row per command the vehicle took (or did otherwise than predicted): its nominal
    item's class, how many probes came back as sent, and every other probe with what happened
    to it; then the commands refused as such, by refusal."""
    aside = refused_as_such(cells)
    hidden = {c for cs in aside.values() for c in cs}
    rows: dict[int, list[dict[str, Any]]] = {}
    for e in cells:
        rows.setdefault(e["command"], []).append(e)
    out = [f"### Commands × params ({len(cells)} cells, {len(rows)} commands; params probed for the "
           f"{len(rows) - len(hidden)} the vehicle takes)", "",
           "| command | nominal item | probes as sent | probes not as sent |", "|---|---|--:|---|"]
    for command in sorted(set(rows) - hidden):
        es = rows[command]
        nominal = next((e for e in es if e["probe"] == "nominal"), None)
        probes = [e for e in es if e["probe"] != "nominal"]
        kept = sum(1 for e in probes if as_sent(e["class"]) and e.get("as_predicted") is not False)
        other = "; ".join(f"{e['probe']} {cell_text(e)}" for e in probes
                          if not as_sent(e["class"]) or e.get("as_predicted") is False)
        out.append(f"| {command_name(command)} | {cell_text(nominal) if nominal else ''} | "
                   f"{kept if probes else ''} | {other.replace('|', chr(92) + '|')} |")
    for cls, commands in sorted(aside.items()):
        out += ["", f"Refused {cls.removeprefix('refused:')} as such ({len(commands)}): "
                + ", ".join(command_name(c) for c in sorted(commands)) + "."]
    return out
