"""A realistic run document: every outcome, both testers, notes, and hostile target text.

It is written as format 1 once did (times in place) and turned into the current format by
`upgrade_run`, with one measured number in a detail and in a note, as a run records them."""

from __future__ import annotations

import copy
from typing import Any

# What a target on the wire could put in a STATUSTEXT or a detail: markup, table and line
# breakers, control characters, a bidi override, a lone surrogate, NaN-like words.
HOSTILE = ('<script>alert("x")</script> | pipe\nnew line\r\n\x00\x07\x1b[31m '
           'NaN Infinity &amp; \u202eevil\ud800 ]]> `code` *bold*')


def event(t: float, direction: str, msg: str, peer: str = "tester", **fields: Any) -> dict:
    return {"t": t, "dir": direction, "peer": peer, "msg": msg, "fields": fields}


def clause(clause_id: str, outcome: str, exchange: list[dict], *, gating: bool = False,
           detail: str = "", expectation: str | None = None, level: str = "MUST") -> dict:
    return {"id": clause_id, "group": clause_id.split(".")[1], "level": level,
            "role": "vehicle", "title": f"{clause_id} in our words",
            "source": "seeds/000_e382b17b02933558.txt:535",
            "requirement": "The vehicle responds with MISSION_REQUEST_INT for each item.",
            "outcome": outcome, "gating": gating, "detail": detail,
            "expectation": expectation, "duration_s": 0.31, "exchange": exchange}


UPLOAD_OK = [
    event(0.0, "tx", "MISSION_COUNT", count=1, mission_type=0, target_system=1),
    event(0.001, "rx", "MISSION_REQUEST_INT", seq=0, mission_type=0),
    event(0.002, "tx", "MISSION_ITEM_INT", seq=0, x=473977418, y=85455939, z=10.0,
          param1="NaN", param4="Infinity", mission_type=0),
    event(0.003, "rx", "MISSION_ACK", type=0, mission_type=0, opaque_id=1234),
]

# tx 3, rx 2, note 2 (one from the tester, one about the second GCS)
FAILED_UPLOAD = [
    event(10.0, "tx", "MISSION_COUNT", count=3, mission_type=0, target_system=1),
    event(10.0012, "rx", "MISSION_REQUEST_INT", seq=0, mission_type=0),
    event(10.002, "tx", "MISSION_ITEM_INT", seq=0, mission_type=0),
    event(10.1, "tx", "MISSION_COUNT", peer="tester2", count=2, mission_type=0),
    event(10.101, "rx", "STATUSTEXT", peer="tester2", severity=6, text=HOSTILE),
    event(10.2, "note", "tester2 was refused as expected", peer="tester2"),
    event(11.5, "note", "expect MISSION_REQUEST_INT seq=1 within 1.5 s: nothing arrived"),
]
FAILED_ARROWS = 5


def run_document_1() -> dict[str, Any]:
    """The sample in the older format ("mavconform-run/1"), a fresh copy each call."""
    clauses = [
        clause("MIS.UP.01", "pass", UPLOAD_OK),
        clause("MIS.UP.07", "fail", FAILED_UPLOAD, gating=True,
               detail="expected MISSION_REQUEST_INT seq=1 within 1.5 s; got nothing | " + HOSTILE),
        clause("MIS.DL.02", "known-deviation", UPLOAD_OK[:2], level="SHOULD",
               detail="MISSION_ACK came with type=MAV_MISSION_ERROR",
               expectation="PX4 answers an empty download with an error <ack>"),
        clause("MIS.FENCE.01", "not-applicable", [], level="MAY",
               detail="target does not support fences"),
        clause("MIS.CLR.03", "skipped", [], detail="--clauses excluded it"),
        clause("MIS.CUR.04", "error", UPLOAD_OK[:1], gating=True,
               detail="runner: socket closed\nTraceback line"),
    ]
    doc = {
        "format": "mavconform-run/1",
        "tool": {"name": "mavconform", "version": "0.1.0"},
        "run": {"target": "udp:127.0.0.1:14550 <b>|", "started": "2026-11-22T10:00:00Z",
                "duration_s": 12.5, "seed": 0, "time_scale": 1.0, "strict": False,
                "clauses": "*", "expectations": None, "baseline": "base.json",
                "forced_wait_s": 9.1},
        "identity": {"system": 1, "component": 1, "type": 2, "autopilot": 4,
                     "mavlink_version": 2, "address": "127.0.0.1:40001"},
        "summary": {"total": 6, "pass": 1, "fail": 1, "known-deviation": 1,
                    "not-applicable": 1, "skipped": 1, "error": 1, "gating_failures": 2,
                    "verdict": "fail"},
        "gating": {"mode": "baseline", "regressions": ["MIS.UP.07"], "fixed": ["MIS.GONE.01"]},
        "restore": {"status": "restored", "detail": "mission of 4 items uploaded back"},
        "capture": "run 1.mcap",
        "clauses": clauses,
    }
    return copy.deepcopy(doc)


MEASURED_DETAIL = "got MISSION_REQUEST_INT{seq=0} after <delay> s; expected none"


def run_document() -> dict[str, Any]:
    """The sample in the current format, a fresh copy each call (tests may mutate it). The
    error clause's detail and the failed upload's last note carry a measured number."""
    from mavconform.reports.run_document import upgrade_run
    doc = upgrade_run(run_document_1())
    error = doc["clauses"][5]
    error["detail"] = MEASURED_DETAIL
    doc["volatile"]["clauses"][error["id"]]["detail"] = {"delay": "0.253"}
    failed = doc["clauses"][1]
    failed["exchange"][6]["msg"] = "expect MISSION_REQUEST_INT seq=1 within 1.5 s: nothing in <waited> s"
    doc["volatile"]["clauses"][failed["id"]]["notes"] = {"6": {"waited": "1.5002"}}
    return doc
