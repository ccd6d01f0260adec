"""An exchange drawn as an inline SVG sequence diagram, for conformance and fuzz reports alike.

Drawn by hand, not by a library: the page must stay one self-contained file that reads
without scripts. The lanes are the exchange's own peers (each event's `peer`) and the
target: "tester" leftmost when it is there, the target next, any other peer (a second GCS)
to the right, so no arrow crosses a label. Every label shows every field, wrapped onto as
many lines as it needs (see message_label), because a verdict cites field values and a cut
label hid them; the one-line text is also each arrow's <title>. The event that decided the
verdict (see deciding) sits on a highlighted band. Times are relative to the first event;
an exchange whose events all share one time (a replay in virtual time, links without delay)
is numbered in order instead of reading "+0.000 s" on every row. Styling is by class (see
html.py's CSS).
"""

from __future__ import annotations

from html import escape
from typing import Any

from mavconform.reports.message_label import field_tokens, full_label, wrap
from mavconform.reports.run_document import NOTE, TX
from mavconform.reports.text import exchange_start, one_line, relative_time

MAX_EVENTS = 300    # drawn per diagram; the rest is summed up in a final note
MAX_LINES = 12      # label lines per event; a longer one ends in "…" (the <title> has it all)

TIME_MARGIN = 100   # left column: "+0.000 s" and the "decided" mark
LANE_HALF = 75      # half a lane's name box, and the margin beyond the outer lanes
MAX_GAP, MIN_GAP = 620, 240   # between neighbouring lifelines
FIT_WIDTH = 1150    # what the page's column holds: lanes are spaced to fit it
MIN_WIDTH = 520     # a diagram with only the target's lane still has room for notes
HEAD = 40           # lane name boxes above the first row
LINE = 13           # one label line
PAD = 6             # above a row's label and below its arrow
CHAR_W = 6.7        # average width of a character at the label font size
ARROW_HEAD = 7
TARGET_ALIASES = ("target",)   # peer names that mean the target itself (mislabelled events)


def sequence_diagram(exchange: list[dict[str, Any]], *, max_events: int = MAX_EVENTS,
                     decided: int | None = None, target: str = "target") -> str:
    """The exchange as an <svg> element: one arrow (<g class="arrow tx|rx">) per message, one
    note box (<g class="note">) per note; an empty exchange gets a "no messages" note.
    `decided`: index of the event to highlight (class "decided"); `target`: its lane's name."""
    aliases = {target, *TARGET_ALIASES}
    peers = _peers(exchange, aliases)
    lanes = _lane_order(peers, target)
    gap = _gap(len(lanes))
    x = {name: TIME_MARGIN + LANE_HALF + i * gap for i, name in enumerate(lanes)}
    width = max(x[lanes[-1]] + LANE_HALF + 10, MIN_WIDTH)
    left, right = TIME_MARGIN + 4, width - 6
    label_chars = int((gap - 24) / CHAR_W)
    note_chars = int((right - left - 16) / CHAR_W)

    drawn = exchange[:max_events]
    hidden = len(exchange) - len(drawn)
    closing = ([f"… {hidden} more events not drawn (see run.json or the capture)"] if hidden
               else [] if exchange else ["no messages exchanged"])
    t0 = exchange_start(exchange)
    timed = len({event["t"] for event in drawn}) > 1 or len(drawn) < 2

    rows: list[str] = []
    y = HEAD
    last_peer = peers[0] if peers else target
    for index, event in enumerate(drawn):
        stamp = relative_time(event["t"], t0) if timed else f"#{index + 1}"
        is_decided = index == decided
        if event["dir"] == NOTE:
            lines = _lines([one_line(event["msg"])], note_chars)
            height = PAD + len(lines) * LINE + PAD
            if is_decided:
                rows.append(_band(y, height, width))
            rows.append(_note(full_label(event), lines, left, right, y, is_decided))
            rows.append(_stamp(stamp, y + PAD + LINE - 3, is_decided))
            y += height
            continue
        sender, receiver = _ends(event, aliases, target, last_peer)
        direction = "rx" if sender == target else "tx"
        last_peer = receiver if sender == target else sender
        lines = _lines([one_line(event["msg"]), *field_tokens(event)], label_chars)
        arrow_y = y + PAD + len(lines) * LINE + 4
        height = arrow_y - y + PAD + 2
        if is_decided:
            rows.append(_band(y, height, width))
        peer_x, target_x = x[last_peer], x[target]
        side = 1 if peer_x > target_x else -1
        text_x = min(target_x, target_x + side * gap) + 12
        rows.append(_arrow(direction, full_label(event), lines, x[sender], x[receiver], arrow_y,
                           text_x, y + PAD + LINE - 3, is_decided))
        rows.append(_stamp(stamp, arrow_y + 4, is_decided))
        y += height
    for text in closing:
        lines = _lines([text], note_chars)
        rows.append(_note(text, lines, left, right, y, False))
        y += PAD + len(lines) * LINE + PAD
    height = y + 12

    out = [f'<svg class="sequence" xmlns="http://www.w3.org/2000/svg" width="{width}" '
           f'height="{height}" viewBox="0 0 {width} {height}" role="img" '
           f'aria-label="message sequence, {len(exchange)} events, lanes: '
           f'{escape(", ".join(one_line(lane) for lane in lanes))}">',
           f'<text class="time head" x="{TIME_MARGIN - 8}" y="22">'
           f'{"time" if timed else "order"}</text>']
    if not timed:
        out.append(f'<text class="time head" x="{TIME_MARGIN - 8}" y="34">'
                   f'(all {relative_time(t0, t0)})</text>')
    for name in lanes:
        cx = x[name]
        kind = "actor target" if name == target else "actor"
        shown = f"{name} (target)" if name == target and name not in TARGET_ALIASES else name
        out.append(f'<line class="lifeline" x1="{cx}" y1="{HEAD - 10}" x2="{cx}" '
                   f'y2="{height - 6}"/>')
        out.append(f'<rect class="{kind}" x="{cx - LANE_HALF + 5}" y="6" '
                   f'width="{2 * LANE_HALF - 10}" height="24" rx="4"/>'
                   f'<text class="{kind}" x="{cx}" y="22">{escape(one_line(shown, 20))}</text>')
    out += rows
    out.append("</svg>")
    return "".join(out)


def _peers(exchange: list[dict[str, Any]], aliases: set[str]) -> list[str]:
    """The peers the events name, in order of appearance, the target's aliases left out."""
    peers: list[str] = []
    for event in exchange:
        peer = event["peer"]
        if event["dir"] != NOTE and peer not in aliases and peer not in peers:
            peers.append(peer)
    return peers


def _lane_order(peers: list[str], target: str) -> list[str]:
    """"tester" (or the first peer) left of the target, every other peer to its right."""
    if not peers:
        return [target]
    first = "tester" if "tester" in peers else peers[0]
    return [first, target, *(p for p in peers if p != first)]


def _gap(lanes: int) -> int:
    if lanes < 2:
        return MAX_GAP
    fit = (FIT_WIDTH - TIME_MARGIN - 2 * LANE_HALF - 10) // (lanes - 1)
    return max(MIN_GAP, min(MAX_GAP, fit))


def _ends(event: dict[str, Any], aliases: set[str], target: str,
          last_peer: str) -> tuple[str, str]:
    """(sender lane, receiver lane). tx: the peer sent it to the target; rx: the target sent
    it to the peer. An event whose peer is the target itself (an exchange that labelled the
    sender, not the tester's side) is drawn from the target to the peer last in touch."""
    peer = event["peer"]
    if peer in aliases:
        return target, last_peer
    return (peer, target) if event["dir"] == TX else (target, peer)


def _lines(tokens: list[str], chars: int) -> list[str]:
    lines = wrap(tokens, chars)
    if len(lines) > MAX_LINES:
        lines = lines[:MAX_LINES - 1] + ["… (the full text is the tooltip)"]
    return lines


def _tspans(lines: list[str], x: float, first_class: str | None = None) -> str:
    spans = []
    for i, line in enumerate(lines):
        cls = f' class="{first_class}"' if i == 0 and first_class else ""
        dy = "0" if i == 0 else str(LINE)
        spans.append(f'<tspan x="{x:g}" dy="{dy}"{cls}>{escape(line)}</tspan>')
    return "".join(spans)


def _arrow(direction: str, title: str, lines: list[str], start: float, end: float,
           y: float, text_x: float, text_y: float, decided: bool) -> str:
    tip = end - ARROW_HEAD if end > start else end + ARROW_HEAD
    cls = f"arrow {direction}" + (" decided" if decided else "")
    return (f'<g class="{cls}"><title>{escape(title)}</title>'
            f'<line x1="{start}" y1="{y}" x2="{end}" y2="{y}"/>'
            f'<polygon points="{end},{y} {tip},{y - 4} {tip},{y + 4}"/>'
            f'<text x="{text_x:g}" y="{text_y}">{_tspans(lines, text_x, "msg")}</text></g>')


def _note(title: str, lines: list[str], left: float, right: float, y: float,
          decided: bool) -> str:
    cls = "note decided" if decided else "note"
    height = len(lines) * LINE + 2 * PAD - 4
    return (f'<g class="{cls}"><title>{escape(title)}</title>'
            f'<rect x="{left}" y="{y + 2}" width="{right - left}" height="{height}"/>'
            f'<text x="{left + 8}" y="{y + PAD + LINE - 3}">{_tspans(lines, left + 8)}</text></g>')


def _band(y: float, height: float, width: float) -> str:
    return f'<rect class="decided-band" x="0" y="{y}" width="{width}" height="{height}"/>'


def _stamp(text: str, y: float, decided: bool) -> str:
    if decided:
        return (f'<text class="time decided-mark" x="{TIME_MARGIN - 8}" y="{y}">'
                f"▶ {escape(text)}</text>")
    return f'<text class="time" x="{TIME_MARGIN - 8}" y="{y}">{escape(text)}</text>'
