"""The reports of a handover scenario run: handover.json (the timeline), handover.html, the console lines.

`timeline(run)` is the canonical document (format `mavconform-handover-run/1`, sorted keys,
times in virtual seconds rounded to the microsecond, no wall-clock value anywhere), so the
same scenario and seed give the same bytes; docs/handover-scenarios.md describes every key.
The HTML page and the console summary are drawn from that document (and the scenario, for the
map), never from the live run, so what a reader sees is what the JSON says.

Verdict: `pass` when the flight ended within the run's bound and every handover COMPLETED;
otherwise `fail`, with one line per problem (a handover ABORTED or UNCONFIRMED, the flight not
ended, the setup not done). The command exits 0 / 1 on it.
"""

from __future__ import annotations

import json
from html import escape
from pathlib import Path
from typing import Any

from mavconform import __version__
from mavconform.reference_impl.handover.geo import GeoPoint, haversine_m
from mavconform.reference_impl.handover.scenario import Scenario, scenario_to_dict
from mavconform.reference_impl.handover.scenario_run import THESIS_STEPS, ScenarioRun
from mavconform.reports.handover_map import handover_map, owner_colours
from mavconform.reports.html import CSS as SEQUENCE_CSS
from mavconform.reports.sequence_svg import sequence_diagram
from mavconform.reports.write import write_texts

__all__ = ["FORMAT", "console_lines", "dump_timeline", "handover_html", "timeline", "write_handover_reports"]

FORMAT = "mavconform-handover-run/1"
PASS, FAIL = "pass", "fail"


# --- the timeline document ----------------------------------------------------------------------
def timeline(run: ScenarioRun) -> dict[str, Any]:
    """The run as plain data (see the module doc and docs/handover-scenarios.md, "The timeline")."""
    handovers = [_handover(run, h) for h in run.handovers]
    segments = _segments(run)
    return {
        "format": FORMAT,
        "tool": f"mavconform {__version__}",
        "scenario": scenario_to_dict(run.scenario),
        "run": {"seed": run.seed, "clock": "virtual", "stopped_by": run.stopped_by, "end_s": _t(run.end),
                "setup_failure": run.setup_failure,
                "mission_started_s": _opt(run.mission_started), "flight_ended_s": _opt(run.flight_ended),
                "flight_complete": run.flight_complete, "links": run.links, "signature_drops": run.rejections},
        "events": run.events,
        "handovers": handovers,
        "segments": segments,
        "track": [[t, lat, lon, owner] for t, lat, lon, owner in run.track],
        "summary": _summary(run, handovers, segments),
    }


TRACK_PLACEHOLDER = "\0track\0"


def dump_timeline(doc: dict[str, Any]) -> str:
    """The document as canonical JSON text (sorted keys, one trailing newline; the track one
    sample a line, so the file stays readable and diffable)."""
    text = json.dumps({**doc, "track": TRACK_PLACEHOLDER}, indent=1, sort_keys=True, ensure_ascii=False,
                      allow_nan=False)
    rows = ",\n  ".join(json.dumps(row, ensure_ascii=False, allow_nan=False) for row in doc["track"])
    track = "[\n  " + rows + "\n ]" if rows else "[]"
    return text.replace(json.dumps(TRACK_PLACEHOLDER), track, 1) + "\n"


def _handover(run: ScenarioRun, h: Any) -> dict[str, Any]:
    r = h.result
    return {"number": h.number, "commander": h.commander, "partner": h.partner, "region": h.region,
            "outcome": r.outcome.name, "started_s": _t(r.started), "finished_s": _t(r.finished),
            "duration_s": _t(r.duration), "owner_after": h.owner_after, "detail": r.detail,
            "position": list(h.position),
            "steps": [{"step": step, "message": THESIS_STEPS.get(step, ""), "t": _t(at), "after_s": _t(at - r.started)}
                      for step, at in r.steps],
            "exchange": run.exchange(h)}


def _segments(run: ScenarioRun) -> list[dict[str, Any]]:
    """The flight cut where the GCS in command changed: who commanded each stretch."""
    out: list[dict[str, Any]] = []
    track = run.track
    start = 0
    for i in range(1, len(track) + 1):
        if i < len(track) and track[i][3] == track[start][3]:
            continue
        end = min(i, len(track) - 1)          # a stretch ends where the next begins
        part = track[start:end + 1]
        metres = sum(haversine_m(GeoPoint(a[1], a[2]), GeoPoint(b[1], b[2])) for a, b in zip(part, part[1:]))
        out.append({"owner": track[start][3], "start_s": track[start][0], "end_s": track[end][0],
                    "distance_m": round(metres, 1), "from": [track[start][1], track[start][2]],
                    "to": [track[end][1], track[end][2]]})
        start = i
    return out


def _summary(run: ScenarioRun, handovers: list[dict[str, Any]], segments: list[dict[str, Any]]) -> dict[str, Any]:
    problems = []
    if run.setup_failure is not None:
        problems.append(f"setup failed: {run.setup_failure}")
    for h in handovers:
        if h["outcome"] != "COMPLETED":
            problems.append(f"handover {h['number']} {h['commander']}->{h['partner']} {h['outcome']}"
                            + (f": {h['detail']}" if h["detail"] else ""))
    if run.setup_failure is None and run.stopped_by != "flight-ended":
        limit = run.scenario.timeouts.max_duration_s
        problems.append(f"the flight did not end within max_duration_s ({limit:g} s)" if run.flight_ended is None
                        else f"a handover was still under way at max_duration_s ({limit:g} s)")
    counts = {o: sum(h["outcome"] == o for h in handovers) for o in ("COMPLETED", "UNCONFIRMED", "ABORTED")}
    return {"verdict": PASS if not problems else FAIL, "problems": problems, "handovers": len(handovers),
            "completed": counts["COMPLETED"], "unconfirmed": counts["UNCONFIRMED"], "aborted": counts["ABORTED"],
            "owners": [s["owner"] for s in segments],
            "emergencies": sum(e["kind"] == "emergency-started" for e in run.events),
            "flight_ended": run.flight_ended is not None, "flight_complete": run.flight_complete}


def _t(seconds: float) -> float:
    return round(seconds, 6)


def _opt(seconds: float | None) -> float | None:
    return None if seconds is None else _t(seconds)


# --- the console --------------------------------------------------------------------------------
def console_lines(doc: dict[str, Any], *, quiet: bool = False) -> list[str]:
    """A short summary: the handovers, owner per segment, the flight, the verdict's problems."""
    s, run, summary = doc["scenario"], doc["run"], doc["summary"]
    lines = []
    if not quiet:
        gcss = ", ".join(g["name"] + (" (parent)" if g["name"] == s["parent"] else "") for g in s["gcs"])
        lines.append(f"{s['name']}: {s['region_method']} coverage, GCSs {gcss}, seed {run['seed']} (virtual time)")
    hs = doc["handovers"]
    listed = ", ".join(f"{h['commander']}->{h['partner']} at {h['started_s']:.1f} s ({h['outcome']}, "
                       f"{h['duration_s']:.2f} s)" for h in hs)
    lines.append(f"{len(hs)} handover{'' if len(hs) == 1 else 's'}" + (f": {listed}" if hs else ""))
    if doc["segments"]:
        lines.append("owner per segment: " + ", ".join(
            f"{seg['owner'] or 'none'} {seg['start_s']:.1f}-{seg['end_s']:.1f} s" for seg in doc["segments"]))
    if not quiet:
        if run["flight_ended_s"] is not None:
            how = "at its last waypoint" if run["flight_complete"] else "before its last waypoint"
            lines.append(f"flight ended {how} at {run['flight_ended_s']:.1f} s")
        for e in doc["events"]:
            if e["kind"] in EMERGENCY_KINDS:
                lines.append(f"  {e['t']:.1f} s {e['kind']}: {_emergency_text(e)}")
    for problem in summary["problems"]:
        lines.append(f"FAIL {problem}")
    return lines


# --- the page -----------------------------------------------------------------------------------
PAGE_CSS = """
.verdict.pass { color: #1a7f37; } .verdict.fail { color: #cf222e; }
ul.problems li { color: #cf222e; }
.swatch { display: inline-block; width: .9em; height: .9em; border-radius: 2px; vertical-align: -.1em;
          margin-right: .3em; }
.map { overflow-x: auto; }
table.timeline td:first-child, table.steps td:first-child { white-space: nowrap; }
"""
OUTCOME_BADGES = {"COMPLETED": "pass", "UNCONFIRMED": "known-deviation", "ABORTED": "fail"}


def handover_html(doc: dict[str, Any], scenario: Scenario) -> str:
    """The run as one self-contained page: map, handovers, owner per segment, each handover's
    messages as a sequence diagram, and the timeline."""
    s, summary = doc["scenario"], doc["summary"]
    verdict = summary["verdict"]
    colours = owner_colours(scenario, [seg["owner"] for seg in doc["segments"]])
    title = f"handover run: {s['name']}"
    out = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           f"<title>{escape(verdict.upper())}: {escape(title)}</title>",
           f"<style>{SEQUENCE_CSS}{PAGE_CSS}</style>", "</head>", "<body>",
           f"<h1>{escape(title)}</h1>",
           f'<p class="verdict {verdict}">{verdict.upper()} <small>({_count(summary["handovers"], "handover")}: '
           f'{summary["completed"]} completed, {summary["unconfirmed"]} unconfirmed, {summary["aborted"]} aborted; '
           f'{_count(summary["emergencies"], "emergency", "emergencies")}; flight '
           f'{_ending(summary)})</small></p>']
    if summary["problems"]:
        out.append('<ul class="problems">' + "".join(f"<li>{escape(p)}</li>" for p in summary["problems"]) + "</ul>")
    if s.get("description"):
        out.append(f"<p>{escape(s['description'])}</p>")
    out += _facts(doc)
    track = [tuple(p) for p in doc["track"]]
    svg = handover_map(scenario, track, marks=_emergency_marks(doc), title=s["name"], id_prefix="run")
    out += ["<h2>Map</h2>", f'<div class="map">{svg}</div>']
    out += _segments_table(doc, colours)
    out += _handovers_table(doc)
    for h in doc["handovers"]:
        out += _handover_section(h)
    out += _timeline_table(doc)
    out += ["</body>", "</html>", ""]
    return "\n".join(out)


def _facts(doc: dict[str, Any]) -> list[str]:
    s, run = doc["scenario"], doc["run"]
    t = s["timeouts"]
    gcss = []
    for g in s["gcs"]:
        key = f", key {g['signing']['fingerprint']}" if "signing" in g else ", unsigned"
        link = ", link " + json.dumps(g["link"], sort_keys=True) if "link" in g else ""
        gcss.append(f"{g['name']} (system {g['sysid']}{key}{link})")
    rows = [("region method", s["region_method"]), ("ground stations", "; ".join(gcss)), ("parent", s["parent"]),
            ("flight", f"{len(s['flight'].get('path', []))} waypoints at {s['flight']['speed_m_s']:g} m/s"
             if "path" in s["flight"] else f"{s['flight']['plan']} at {s['flight']['speed_m_s']:g} m/s"),
            ("timeouts", f"dwell {t['dwell_s']:g} s, handover bound {t['handover_bound_s']:g} s, commander lost "
                         f"after {t['loss_timeout_s']:g} s, outside grace {t['outside_grace_s']:g} s, run bound "
                         f"{t['max_duration_s']:g} s"),
            ("seed", str(run["seed"])), ("clock", "virtual (same seed, same run)"),
            ("mission", f"started at {_s(run['mission_started_s'])}, ended at {_s(run['flight_ended_s'])}"
                        + (" (last waypoint reached)" if run["flight_complete"] else "")),
            ("run", f"stopped at {run['end_s']:.3f} s: {run['stopped_by']}"
                    + (f" ({run['setup_failure']})" if run["setup_failure"] else "")),
            ("links", "; ".join(f"{k}: {v['sent']} sent, {v['dropped']} lost, {v['duplicated']} duplicated, "
                                f"{v['reordered']} reordered" for k, v in run["links"].items())),
            ("dropped for their signature", "; ".join(
                f"by {k}: " + (", ".join(f"{n} {reason}" for reason, n in v.items()) or "none")
                for k, v in run["signature_drops"].items())),
            ("capture", "handover.mcap beside this page (every frame; markers at each handover)"),
            ("tool", doc["tool"])]
    return ['<table class="facts">'] + [f"<tr><th>{escape(k)}</th><td>{escape(v)}</td></tr>" for k, v in rows] + \
        ["</table>"]


def _segments_table(doc: dict[str, Any], colours: dict[str | None, str]) -> list[str]:
    out = ["<h2>Owner per segment</h2>", "<table><tr><th>#</th><th>GCS in command</th><th>from</th><th>to</th>"
           "<th>distance</th></tr>"]
    for i, seg in enumerate(doc["segments"], 1):
        swatch = f'<span class="swatch" style="background:{colours.get(seg["owner"], "#6e7781")}"></span>'
        out.append(f'<tr><td class="n">{i}</td><td>{swatch}{escape(seg["owner"] or "none")}</td>'
                   f'<td class="n">{seg["start_s"]:.3f} s</td><td class="n">{seg["end_s"]:.3f} s</td>'
                   f'<td class="n">{seg["distance_m"] / 1000:.2f} km</td></tr>')
    return out + ["</table>"]


def _handovers_table(doc: dict[str, Any]) -> list[str]:
    out = ["<h2>Handovers</h2>"]
    if not doc["handovers"]:
        return out + ["<p>No handover started.</p>"]
    out.append("<table><tr><th>#</th><th>from → to</th><th>region</th><th>started</th><th>duration</th>"
               "<th>outcome</th><th>in command after</th><th>detail</th></tr>")
    for h in doc["handovers"]:
        out.append(f'<tr><td class="n"><a href="#handover-{h["number"]}">{h["number"]}</a></td>'
                   f'<td>{escape(h["commander"])} → {escape(h["partner"])}</td><td>{escape(h["region"])}</td>'
                   f'<td class="n">{h["started_s"]:.3f} s</td><td class="n">{h["duration_s"]:.3f} s</td>'
                   f'<td>{_badge(h["outcome"])}</td><td>{escape(h["owner_after"] or "none")}</td>'
                   f'<td>{escape(h["detail"])}</td></tr>')
    return out + ["</table>"]


def _handover_section(h: dict[str, Any]) -> list[str]:
    out = [f'<section class="clause" id="handover-{h["number"]}">',
           f'<h3>{_badge(h["outcome"])} Handover {h["number"]}: {escape(h["commander"])} → {escape(h["partner"])} '
           f'<small>(region {escape(h["region"])}, {h["started_s"]:.3f} s, {h["duration_s"]:.3f} s)</small></h3>',
           '<table class="steps"><tr><th>step</th><th>thesis message</th><th>first seen</th><th>after start</th></tr>']
    for st in h["steps"]:
        out.append(f'<tr><td class="n">{st["step"]}</td><td><code>{escape(st["message"])}</code></td>'
                   f'<td class="n">{st["t"]:.3f} s</td><td class="n">+{st["after_s"]:.3f} s</td></tr>')
    out.append("</table>")
    if h["detail"]:
        out.append(f'<p class="detail">{escape(h["detail"])}</p>')
    out.append(f'<div class="diagram">{sequence_diagram(h["exchange"], target="vehicle")}</div>')
    out.append('<p class="decided-key">Every message sent between the vehicle and the GCSs from the start to the '
               'end of the handover (telemetry left out; a datagram a link lost is a note; handover.mcap has '
               'everything).</p>')
    return out + ["</section>"]


def _timeline_table(doc: dict[str, Any]) -> list[str]:
    out = ["<h2>Timeline</h2>", '<table class="timeline"><tr><th>time</th><th>event</th><th>what</th></tr>']
    for e in doc["events"]:
        out.append(f'<tr><td class="n">{e["t"]:.3f} s</td><td><code>{escape(e["kind"])}</code></td>'
                   f"<td>{escape(_event_text(e))}</td></tr>")
    return out + ["</table>"]


EMERGENCY_KINDS = ("owner-lost", "emergency-started", "emergency-ended", "emergency")


def _emergency_text(e: dict[str, Any]) -> str:
    """The sentences an emergency event carries (trigger, refuge, how it ended), else its fields."""
    f = e.get("fields", {})
    said = [part["reason"] for part in (f.get("trigger"), f.get("refuge")) if isinstance(part, dict) and "reason" in part]
    said += [f["how"]] if isinstance(f.get("how"), str) else []
    if e["kind"] == "owner-lost":
        return f"GCS {e['gcs']} silent for {e['silent_s']:g} s"
    return "; ".join(said) if said else _event_text(e)


def _emergency_marks(doc: dict[str, Any]) -> list[tuple[float, float, str]]:
    """Map marks: where each emergency started, and the refuge it chose."""
    marks = []
    for e in doc["events"]:
        f = e.get("fields", {})
        if e["kind"] != "emergency-started":
            continue
        if _is_point(f.get("position")):
            marks.append((f["position"]["lat"], f["position"]["lon"], f"emergency at {e['t']:.1f} s"))
        refuge = f.get("refuge")
        if isinstance(refuge, dict) and _is_point(refuge.get("point")):
            marks.append((refuge["point"]["lat"], refuge["point"]["lon"], "refuge"))
    return marks


def _is_point(value: Any) -> bool:
    return isinstance(value, dict) and isinstance(value.get("lat"), float) and isinstance(value.get("lon"), float)


def _event_text(e: dict[str, Any]) -> str:
    return ", ".join(f"{k} {json.dumps(v, sort_keys=True, ensure_ascii=False) if not isinstance(v, str) else v}"
                     for k, v in sorted(e.items()) if k not in ("t", "kind"))


def _badge(outcome: str) -> str:
    return f'<span class="badge o-{OUTCOME_BADGES.get(outcome, "error")}">{escape(outcome)}</span>'


def _count(n: int, one: str, many: str | None = None) -> str:
    return f"{n} {one if n == 1 else many or one + 's'}"


def _ending(summary: dict[str, Any]) -> str:
    if not summary["flight_ended"]:
        return "not ended"
    return "ended at its last waypoint" if summary["flight_complete"] else "ended before its last waypoint"


def _s(seconds: float | None) -> str:
    return "-" if seconds is None else f"{seconds:.3f} s"


# --- writing ------------------------------------------------------------------------------------
def write_handover_reports(doc: dict[str, Any], scenario: Scenario, directory: str | Path) -> dict[str, Path]:
    """handover.json and handover.html into `directory` (handover.mcap is written while the run
    happens). Both are rendered before either is written."""
    return write_texts(directory, {"json": ("handover.json", dump_timeline(doc)),
                                   "html": ("handover.html", handover_html(doc, scenario))})
