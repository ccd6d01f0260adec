"""The fidelity survey in run.html (issue 26): frames × plan-type item kinds and commands ×
params, a colour per class, a mark where the profile predicted otherwise, and each cell's
upload and download one click away (the messages of the exchange that decided it)."""

from __future__ import annotations

from html import escape
from typing import Any

from mavconform.conformance.fidelity.cells import FRAME_NAMES, entry_key
from mavconform.conformance.fidelity.table import COLUMNS, command_name, legend, refused_as_such, short, unlike

STYLE = """
table.matrix { border-collapse: collapse; font-size: .85em; }
table.matrix th, table.matrix td { border: 1px solid #d0d7de; padding: .25em .45em; vertical-align: top; }
td.exact { background: #dafbe1; } td.int_twin { background: #eef9f0; } td.refused { background: #eaeef2; }
td.changed { background: #fff8c5; } td.changed.ruleless { background: #ffebe9; }
td.unlike { outline: 3px solid #cf222e; outline-offset: -3px; }
td a { color: inherit; text-decoration: none; }
a.chip { display: inline-block; margin: 1px; padding: 0 .3em; border-radius: 3px; font-size: .85em; }
a.chip.exact { background: #aceebb; } a.chip.int_twin { background: #d1f5da; } a.chip.refused { background: #d0d7de; }
a.chip.changed { background: #fae17d; } a.chip.changed.ruleless { background: #ffcecb; }
a.chip.unlike { outline: 2px solid #cf222e; } .predicted { display: block; color: #cf222e; font-size: .85em; }
section.exchange { margin-top: 1em; } section.exchange ol { font-family: ui-monospace, monospace; font-size: .8em; }
"""


def _kind(cls: str) -> str:
    head = cls.split(":")[0]
    if head == "changed":
        return "changed" + ("" if "(rule:" in cls else " ruleless")
    return head if head in ("exact", "int_twin", "refused") else "refused"


def _text(entry: dict[str, Any]) -> str:
    return escape(short(entry["class"]))


def _cell(entry: dict[str, Any]) -> str:
    unlike = entry.get("as_predicted") is False
    classes = _kind(entry["class"]) + (" unlike" if unlike else "")
    text = _text(entry)
    if unlike:
        text += f'<span class="predicted">profile: {escape(short(entry["predicted"]))}</span>'
    return f'<td class="{classes}" title="{escape(entry["class"])}"><a href="#e{entry.get("exchange")}">{text}</a></td>'


def _chip(entry: dict[str, Any]) -> str:
    """One probe in the command matrix: its kind in its class's colour, the class on hover."""
    unlike = entry.get("as_predicted") is False
    title = entry["class"] + (f" (profile: {entry['predicted']})" if unlike else "")
    kind = entry["probe"].split(":", 1)[-1]
    return (f'<a class="chip {_kind(entry["class"])}{" unlike" if unlike else ""}" href="#e{entry.get("exchange")}" '
            f'title="{escape(title)}">{escape(kind)}</a>')


def _event(event: dict[str, Any]) -> str:
    fields = ", ".join(f"{k}={v}" for k, v in event.get("fields", {}).items()
                       if k in ("seq", "count", "type", "frame", "command", "x", "y", "z", "param1", "param2",
                                "param3", "param4", "autocontinue", "text"))
    return f"<li>{event['t']:.3f} {escape(event['dir'])} {escape(event['msg'])} {escape(fields)}</li>"


def _frame_matrix(cells: list[dict[str, Any]]) -> list[str]:
    by = {entry_key(e)[:3]: e for e in cells}
    out = [f"<h2>Frames × plan types ({len(cells)} cells)</h2>",
           '<table class="matrix"><tr><th>frame</th>'
           + "".join(f"<th>{escape(t)}</th>" for _, _, t in COLUMNS) + "</tr>"]
    for f in sorted({e["frame"] for e in cells}):
        row = "".join(_cell(by[(pt, f, cmd)]) if (pt, f, cmd) in by else "<td></td>" for pt, cmd, _ in COLUMNS)
        out.append(f"<tr><th>{f} {escape(FRAME_NAMES.get(f, ''))}</th>{row}</tr>")
    return out + ["</table>"]


def _command_matrix(cells: list[dict[str, Any]]) -> list[str]:
    rows: dict[int, dict[str, list[dict[str, Any]]]] = {}
    for e in cells:
        where = "nominal" if e["probe"] == "nominal" else e["probe"].split(":", 1)[0]
        rows.setdefault(e["command"], {}).setdefault(where, []).append(e)
    aside = refused_as_such(cells)
    hidden = {c for cs in aside.values() for c in cs}
    heads = ["nominal"] + [f"p{i}" for i in range(1, 8)]
    out = [f"<h2>Commands × params ({len(cells)} cells, {len(rows)} commands, {len(rows) - len(hidden)} taken)</h2>",
           "<p>Each command's nominal item first; a command the vehicle takes has each param probed (params 5-7 "
           "travel as x, y, z): hover a probe for its class, click it for its exchange.</p>",
           '<table class="matrix"><tr><th>command</th>' + "".join(f"<th>{h}</th>" for h in heads) + "</tr>"]
    for command in sorted(set(rows) - hidden):
        by = rows[command]
        tds = [_cell(by["nominal"][0]) if "nominal" in by else "<td></td>"]
        tds += ["<td>" + " ".join(_chip(e) for e in by.get(h, [])) + "</td>" for h in heads[1:]]
        out.append(f"<tr><th>{escape(command_name(command))}</th>{''.join(tds)}</tr>")
    out.append("</table>")
    for cls, commands in sorted(aside.items()):
        out.append(f"<p>Refused {escape(cls.removeprefix('refused:'))} as such ({len(commands)}): "
                   + ", ".join(escape(command_name(c)) for c in sorted(commands)) + ".</p>")
    return out


def fidelity_sections(doc: dict[str, Any]) -> list[str]:
    """The survey's part of run.html: what it is, the rules it names, the matrices, and each
    upload's exchange (a cell's link target)."""
    fid = doc["fidelity"]
    cells = fid["cells"]
    out = [f"<style>{STYLE}</style>", "<h2>Fidelity survey</h2>",
           f"<p>{len(cells)} cells in {fid['uploads']} uploads; profile {escape(str(fid['profile']))} "
           f"({escape(str(fid.get('basis') or ''))}): <b>{len(unlike(cells))}</b> cell(s) unlike its prediction (outlined). "
           "Green: exact or INT twin; grey: refused; yellow: changed, a documented rule explains it; red: "
           "changed, no rule does. A cell links to its exchange.</p>"]
    rules = legend(fid)
    if rules:
        out.append("<ul>" + "".join(f"<li>{escape(r.removeprefix('- '))}</li>" for r in rules) + "</ul>")
    frame_cells = [e for e in cells if not e.get("probe")]
    command_cells = [e for e in cells if e.get("probe")]
    if frame_cells:
        out += _frame_matrix(frame_cells)
    if command_cells:
        out += _command_matrix(command_cells)
    exchanges = fid.get("exchanges", [])
    decided: dict[int, list[dict[str, Any]]] = {}
    for e in cells:
        if isinstance(e.get("exchange"), int):
            decided.setdefault(e["exchange"], []).append(e)
    out.append(f"<h2>Exchanges ({len(exchanges)} uploads)</h2>")
    for n, events in enumerate(exchanges):
        names = ", ".join(f"{e['plan_type']} frame {e['frame']} command {e['command']}"
                          + (f" {e['probe']}" if e.get("probe") else "") + f": {e['class']}"
                          for e in decided.get(n, [])[:12])
        more = len(decided.get(n, [])) - 12
        out += [f'<section class="exchange" id="e{n}"><h3>upload {n + 1}</h3><p>{escape(names)}'
                f"{f' and {more} more' if more > 0 else ''}</p>",
                "<ol>" + "".join(_event(ev) for ev in events[:80]) + "</ol>" if events else "<p>no exchange kept</p>",
                "</section>"]
    return out
