"""An exchange drawn as an inline SVG sequence diagram (testers on the sides, target between).

Drawn by hand, not by a library: the page must stay one self-contained file that reads
without scripts. The target sits between "tester" (left) and any second GCS (right), so
every arrow runs between neighbours and no label crosses a lifeline. Labels are cut to fit;
each arrow's full text is its <title> (a tooltip). Styling is by class (see html.py's CSS).
"""

from __future__ import annotations

from html import escape
from typing import Any

from mavconform.reports.run_document import NOTE, TX
from mavconform.reports.text import event_label, exchange_start, one_line, relative_time

MAX_EVENTS = 300  # drawn per diagram; the rest is summed up in a final note

TIME_MARGIN = 80  # left column for "+0.000 s"
GAP = 360  # between neighbouring lifelines
HEAD = 36  # lifeline name boxes above the first row
ROW = 24
CHAR_W = 6.7  # average width of a character at the label font size
ARROW_HEAD = 7


def sequence_diagram(exchange: list[dict[str, Any]], *, max_events: int = MAX_EVENTS) -> str:
    """The exchange as an <svg> element: one arrow (class "arrow") per tx/rx event, one note
    box (class "note") per note event; an empty exchange gets a "no messages" note."""
    testers = _testers(exchange)
    columns = [testers[0], None, *testers[1:]]  # None: the target
    x = {name: TIME_MARGIN + 70 + i * GAP for i, name in enumerate(columns)}
    left, right = min(x.values()), max(x.values())
    drawn = exchange[:max_events]
    hidden = len(exchange) - len(drawn)
    notes = [f"… {hidden} more events not drawn (see run.json or the capture)"] if hidden else []
    if not exchange:
        notes = ["no messages exchanged"]
    rows = len(drawn) + len(notes)
    width = right + 100
    height = HEAD + rows * ROW + 24
    label_chars = int((GAP - 24) / CHAR_W)
    note_chars = int((right - left + 120) / CHAR_W)

    out = [f'<svg class="sequence" xmlns="http://www.w3.org/2000/svg" width="{width}" '
           f'height="{height}" viewBox="0 0 {width} {height}" role="img" '
           f'aria-label="message sequence, {len(exchange)} events">']
    for name, cx in x.items():
        title = "target" if name is None else name
        out.append(f'<line class="lifeline" x1="{cx}" y1="{HEAD - 12}" x2="{cx}" '
                   f'y2="{height - 8}"/>')
        out.append(f'<rect class="actor" x="{cx - 60}" y="6" width="120" height="24" rx="4"/>'
                   f'<text class="actor" x="{cx}" y="22">{_text(title, 17)}</text>')
    t0 = exchange_start(exchange)
    y = HEAD
    for event in drawn:
        y += ROW
        out.append(f'<text class="time" x="{TIME_MARGIN - 6}" y="{y + 4}">'
                   f'{relative_time(event["t"], t0)}</text>')
        label = event_label(event)
        if event["dir"] == NOTE:
            out.append(_note(label, left, right, y, note_chars))
            continue
        peer_x = x[event["peer"]]
        start, end = (peer_x, x[None]) if event["dir"] == TX else (x[None], peer_x)
        tip = end - ARROW_HEAD if end > start else end + ARROW_HEAD
        out.append(f'<g class="arrow {event["dir"]}"><title>{escape(label)}</title>'
                   f'<line x1="{start}" y1="{y}" x2="{end}" y2="{y}"/>'
                   f'<polygon points="{end},{y} {tip},{y - 4} {tip},{y + 4}"/>'
                   f'<text x="{(start + end) / 2:g}" y="{y - 5}">{_text(label, label_chars)}'
                   f'</text></g>')
    for note in notes:
        y += ROW
        out.append(_note(note, left, right, y, note_chars))
    out.append("</svg>")
    return "".join(out)


def _testers(exchange: list[dict[str, Any]]) -> list[str]:
    """The tester lifelines: "tester" first, then other peers in order of appearance."""
    peers = ["tester"]
    for event in exchange:
        if event["dir"] != NOTE and event["peer"] not in peers:
            peers.append(event["peer"])
    return peers


def _note(text: str, left: int, right: int, y: int, chars: int) -> str:
    return (f'<g class="note"><title>{escape(text)}</title>'
            f'<rect x="{left - 60}" y="{y - 9}" width="{right - left + 120}" height="18"/>'
            f'<text x="{(left + right) / 2:g}" y="{y + 4}">{_text(text, chars)}</text></g>')


def _text(text: str, limit: int) -> str:
    return escape(one_line(text, limit))
