"""The frame matrix for people: a Markdown table (frames × plan-type item kinds) a maintainer can
paste into an issue, and the same rows for the terminal."""

from __future__ import annotations

from typing import Any

from .cells import FENCE_CIRCLE, FENCE_RETURN, FENCE_VERTEX, FRAME_NAMES, RALLY_POINT

COLUMNS = (("mission", 16, "mission waypoint"), ("fence", FENCE_VERTEX, "fence vertex"),
           ("fence", FENCE_CIRCLE, "fence circle"), ("fence", FENCE_RETURN, "fence return point"),
           ("rally", RALLY_POINT, "rally point"))


def short(cls: str | None) -> str:
    if cls is None:
        return "-"
    if cls.startswith("refused:"):
        return "refused " + cls.removeprefix("refused:")
    return cls.replace("changed:", "changed: ").replace("int_twin", "INT twin")


def cell_text(entry: dict[str, Any]) -> str:
    text = short(entry["class"])
    if entry.get("as_predicted") is False:
        text += f" ⚠ profile: {short(entry['predicted'])}"
    return text


def markdown(fidelity: dict[str, Any]) -> str:
    by = {(e["plan_type"], e["frame"], e["command"]): e for e in fidelity["cells"]}
    frames = sorted({e["frame"] for e in fidelity["cells"]})
    unlike = sum(1 for e in fidelity["cells"] if e.get("as_predicted") is False)
    out = [f"### Frames × plan types ({len(fidelity['cells'])} cells, {fidelity['uploads']} uploads; profile "
           f"{fidelity['profile']}: {unlike} cell(s) unlike its prediction)", "",
           "| frame | " + " | ".join(title for _, _, title in COLUMNS) + " |",
           "|---|" + "---|" * len(COLUMNS)]
    for f in frames:
        row = [cell_text(by[(pt, f, cmd)]) if (pt, f, cmd) in by else "" for pt, cmd, _ in COLUMNS]
        out.append(f"| {f} {FRAME_NAMES.get(f, '')} | " + " | ".join(c.replace("|", "\\|") for c in row) + " |")
    return "\n".join(out) + "\n"
