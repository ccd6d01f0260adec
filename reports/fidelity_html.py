"""fidelity.html: the frame matrix as a page (issue 26): frames × plan-type item kinds, a colour
per class, a mark where the profile predicted otherwise, and each cell's upload and download
one click away (the messages of the exchange that decided it)."""

from __future__ import annotations

from html import escape
from typing import Any

from mavconform.conformance.fidelity.cells import FRAME_NAMES
from mavconform.conformance.fidelity.classify import UPSTREAM_RESERVED
from mavconform.conformance.fidelity.table import COLUMNS, short

STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em; color: #1f2328; }
table.matrix { border-collapse: collapse; font-size: .85em; }
table.matrix th, table.matrix td { border: 1px solid #d0d7de; padding: .25em .45em; vertical-align: top; }
td.exact { background: #dafbe1; } td.int_twin { background: #eef9f0; } td.refused { background: #eaeef2; }
td.changed { background: #fff8c5; } td.changed.ruleless { background: #ffebe9; }
td.unlike { outline: 3px solid #cf222e; outline-offset: -3px; }
td a { color: inherit; text-decoration: none; } .predicted { display: block; color: #cf222e; font-size: .85em; }
section.exchange { margin-top: 1em; } section.exchange ol { font-family: ui-monospace, monospace; font-size: .8em; }
"""


def _kind(cls: str) -> str:
    head = cls.split(":")[0]
    if head == "changed":
        return "changed" + ("" if "(rule:" in cls else " ruleless")
    return head if head in ("exact", "int_twin", "refused") else "refused"


def _cell(entry: dict[str, Any]) -> str:
    unlike = entry.get("as_predicted") is False
    classes = _kind(entry["class"]) + (" unlike" if unlike else "")
    anchor = f"x{entry['plan_type']}-{entry['frame']}-{entry['command']}"
    text = escape(short(entry["class"]).replace(f"(rule: {UPSTREAM_RESERVED})", "(rule: upstream)"))
    if unlike:
        text += f'<span class="predicted">profile: {escape(short(entry["predicted"]))}</span>'
    return f'<td class="{classes}" title="{escape(entry["class"])}"><a href="#{anchor}">{text}</a></td>'


def _event(event: dict[str, Any]) -> str:
    fields = ", ".join(f"{k}={v}" for k, v in event.get("fields", {}).items()
                       if k in ("seq", "count", "type", "frame", "command", "x", "y", "z", "param1", "autocontinue",
                                "text"))
    return f"<li>{event['t']:.3f} {escape(event['dir'])} {escape(event['msg'])} {escape(fields)}</li>"


def fidelity_html(doc: dict[str, Any]) -> str:
    fid = doc["fidelity"]
    cells = fid["cells"]
    by = {(e["plan_type"], e["frame"], e["command"]): e for e in cells}
    frames = sorted({e["frame"] for e in cells})
    unlike = sum(1 for e in cells if e.get("as_predicted") is False)
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           f"<title>fidelity: {escape(str(doc['run']['target']))}</title><style>{STYLE}</style></head><body>",
           f"<h1>What {escape(str(doc['run']['target']))} keeps of each frame and plan type</h1>",
           f"<p>{len(cells)} cells in {fid['uploads']} uploads; profile {escape(str(fid['profile']))} "
           f"({escape(str(fid.get('basis') or ''))}): <b>{unlike}</b> cell(s) unlike its prediction (outlined). "
           "Green: exact or INT twin; grey: refused; yellow: changed, a documented rule explains it; red: "
           "changed, no rule does. A cell links to its exchange.</p>",
           '<table class="matrix"><tr><th>frame</th>' + "".join(f"<th>{escape(t)}</th>" for _, _, t in COLUMNS) + "</tr>"]
    for f in frames:
        row = "".join(_cell(by[(pt, f, cmd)]) if (pt, f, cmd) in by else "<td></td>" for pt, cmd, _ in COLUMNS)
        out.append(f"<tr><th>{f} {escape(FRAME_NAMES.get(f, ''))}</th>{row}</tr>")
    out.append("</table>")
    exchanges = fid.get("exchanges", [])
    for e in cells:
        anchor = f"x{e['plan_type']}-{e['frame']}-{e['command']}"
        events = exchanges[e["exchange"]] if isinstance(e.get("exchange"), int) and e["exchange"] < len(exchanges) else []
        out += [f'<section class="exchange" id="{anchor}"><h3>{escape(e["plan_type"])} frame {e["frame"]} '
                f"command {e['command']}: {escape(e['class'])}</h3>",
                "<ol>" + "".join(_event(ev) for ev in events[:60]) + "</ol>" if events else "<p>no exchange kept</p>",
                "</section>"]
    out += ["</body></html>", ""]
    return "\n".join(out)
