"""The job file: what a GCS under test is told to do, and what it says back.

A GCS is driven through an adapter (adapters.py): a command run once per operation
(`--gcs-cmd 'CMD {port} {op} {file}'`) or a Python object. Both get the same `Job`; a
command gets it as a JSON file, so an adapter can be a standalone script in any language,
in a venv of its own (MAVProxy's, MAVSDK's). docs/gcs-conformance.md gives the format.

    {"format": "mavconform-gcs-job/1", "op": "upload", "mission_type": "fence",
     "items": [{"seq": 0, "frame": 3, "command": 5001, ..., "x": 473977420, "y": 85455940, "z": 0.0}],
     "seq": null, "result": "/tmp/.../result.json", "timeout_s": 30.0}

The adapter writes the result file: `{"ok": bool, "said": "the GCS's own words",
"ended": bool, "items": [...]}` (items: download only; ended false: the GCS never ended the
operation by itself and the adapter stopped waiting).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mavconform.reference_impl.mission.items import MissionItem, MissionType

FORMAT = "mavconform-gcs-job/1"
OPS = ("upload", "download", "clear", "set-current")
TYPE_NAMES = {"mission": MissionType.MISSION, "fence": MissionType.FENCE, "rally": MissionType.RALLY}
_ITEM_FIELDS = ("seq", "frame", "command", "current", "autocontinue",
                "param1", "param2", "param3", "param4", "x", "y", "z")


@dataclass(frozen=True)
class Job:
    op: str
    mission_type: MissionType = MissionType.MISSION
    items: tuple[MissionItem, ...] = ()   # upload: the plan
    seq: int | None = None                # set-current: the item to make current
    timeout_s: float = 30.0

    def __post_init__(self) -> None:
        if self.op not in OPS:
            raise ValueError(f"unknown GCS operation {self.op!r}")

    def to_json(self, result: Path) -> dict[str, Any]:
        return {"format": FORMAT, "op": self.op, "mission_type": self.mission_type.label,
                "items": [item_to_json(i) for i in self.items], "seq": self.seq,
                "result": str(result), "timeout_s": self.timeout_s}

    def describe(self) -> str:
        what = {"upload": f"upload {len(self.items)} {self.mission_type.label} items",
                "download": f"download the {self.mission_type.label}",
                "clear": f"clear the {self.mission_type.label}",
                "set-current": f"set item {self.seq} current"}
        return what[self.op]


@dataclass
class JobResult:
    """What the GCS said when the operation ended (or what stopping it found)."""
    ok: bool
    said: str
    ended: bool = True            # False: the GCS never ended the operation by itself
    items: tuple[MissionItem, ...] | None = None   # download: what the GCS got
    at: float = 0.0               # when the harness learnt it (its clock)
    log: list[str] = field(default_factory=list)   # the adapter's last lines, for the report
    refused_job: bool = False     # the adapter exited 2 without a result: it never ran the GCS

    def line(self) -> str:
        how = "succeeded" if self.ok else "failed" if self.ended else "never ended"
        return f"the GCS {how}" + (f" ({self.said})" if self.said else "")


def item_to_json(item: MissionItem) -> dict[str, Any]:
    return {name: _finite(getattr(item, name)) for name in _ITEM_FIELDS}


def item_from_json(data: Any, mission_type: MissionType, where: str) -> MissionItem:
    """One item of a result file; a ValueError naming `where` if it is not one."""
    if not isinstance(data, dict):
        raise ValueError(f"{where}: an item must be an object, got {type(data).__name__}")
    missing = [k for k in ("seq", "frame", "command", "x", "y", "z") if k not in data]
    if missing:
        raise ValueError(f"{where}: item lacks {', '.join(missing)}")
    try:
        ints = {k: int(data.get(k, d)) for k, d in (("seq", 0), ("frame", 0), ("command", 0), ("current", 0),
                                                     ("autocontinue", 1), ("x", 0), ("y", 0))}
        floats = {k: float(data.get(k) if data.get(k) is not None else math.nan)
                  for k in ("param1", "param2", "param3", "param4", "z")}
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    return MissionItem(mission_type=mission_type, **ints, **floats)


def read_result(path: Path, mission_type: MissionType) -> JobResult:
    """The adapter's result file; a ValueError saying what is wrong with it."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"result file {path}: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("ok"), bool):
        raise ValueError(f"result file {path}: needs an object with a boolean \"ok\"")
    items = None
    if data.get("items") is not None:
        if not isinstance(data["items"], list):
            raise ValueError(f"result file {path}: \"items\" must be a list")
        items = tuple(item_from_json(d, mission_type, f"result file {path}, items[{i}]")
                      for i, d in enumerate(data["items"]))
    return JobResult(ok=data["ok"], said=str(data.get("said", ""))[:300], ended=data.get("ended", True) is not False,
                     items=items)


def _finite(value: Any) -> Any:
    """JSON has no NaN: a NaN param (the "use the default" value) is written as null."""
    return None if isinstance(value, float) and math.isnan(value) else value


def read_job(path: Path) -> tuple[Job, Path]:
    """A job file and the result path it names (what a Python adapter reads first); a
    ValueError naming the file and what is wrong."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"job file {path}: {exc}") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ValueError(f"job file {path}: not a {FORMAT} job")
    if data.get("mission_type") not in TYPE_NAMES or data.get("op") not in OPS or not data.get("result"):
        raise ValueError(f"job file {path}: needs op ({', '.join(OPS)}), mission_type "
                         f"({', '.join(TYPE_NAMES)}) and result")
    mt = TYPE_NAMES[data["mission_type"]]
    items = tuple(item_from_json(d, mt, f"job file {path}, items[{i}]") for i, d in enumerate(data.get("items") or []))
    seq = data.get("seq")
    if data["op"] == "set-current" and not isinstance(seq, int):
        raise ValueError(f"job file {path}: set-current needs an integer seq")
    return Job(data["op"], mt, items, seq, float(data.get("timeout_s", 30.0))), Path(data["result"])


def write_result(path: Path, result: JobResult) -> None:
    data: dict[str, Any] = {"ok": result.ok, "said": result.said, "ended": result.ended}
    if result.items is not None:
        data["items"] = [item_to_json(i) for i in result.items]
    path.write_text(json.dumps(data), encoding="utf-8")


def write_job(job: Job, path: Path, result: Path) -> None:
    path.write_text(json.dumps(job.to_json(result), indent=1), encoding="utf-8")
