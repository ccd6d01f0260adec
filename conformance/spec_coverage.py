"""Which clause checks each requirement sentence of seed 000, or why none does: as data.

`mavconform clauses --coverage` renders this as docs/spec-coverage.md (a test regenerates
it and compares). Where ../shared/seeds is present, a test also applies the rule below to
seed 000 and checks that it finds exactly the sentences listed here, word for word.

The rule that makes a sentence a requirement sentence (`requirement_sentences`):
1. The part: seed 000 from its line "Mission Protocol" (where the restated MAVLink Mission
   Protocol begins) to the end; the first half is about other parts of the drone.
2. Each line is a paragraph. A paragraph splits into sentences after ".", "!" or "?"
   followed by white space, except after the abbreviations "e.g.", "i.e.", "etc." and "vs.".
   White space inside a sentence is collapsed to single spaces.
3. A sentence is a requirement sentence when it contains, as a whole word in any case,
   one of: must, shall, should, may, required, recommended, or "is expected" / "are
   expected". ("can" is not one: in this text it states what is possible, e.g. "can be used
   for any purpose"; the one "can" sentence that grants a permission, "An error can be
   signaled ...", is followed by the "must" sentence that binds it.)
A sentence is named L.n: line L of the seed file, n-th sentence of that line (from 1).

Sentences the rule does not find but a clause quotes (field definitions and step-by-step
sequences state requirements without a keyword) are listed from the catalogue, as are the
clauses from other sources (seed 001, the upstream XML).

Both roles' clauses are mapped: the vehicle's (`catalogue.CLAUSES`) and the GCS's
(MIS.G.*, `catalogue.GCS_CLAUSES`, judged by `mavconform run --role gcs`). Where seed 000
binds both sides, a sentence lists both. MIS.GCS.* are vehicle clauses (how a vehicle treats
a second GCS), not the GCS's side.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .catalogue import BY_ID, CLAUSES, GCS_CLAUSES, MSP_CLAUSES
from .clause import SEED_000, Clause, Role

PART_HEADING = "Mission Protocol"
KEYWORDS = re.compile(r"\b(must|shall|should|may|required|recommended|(?:is|are) expected)\b",
                      re.IGNORECASE)
_BREAK = re.compile(r"(?<=[.!?])\s+")
_ABBREVIATION = re.compile(r"\b(e\.g|i\.e|etc|vs)\.$", re.IGNORECASE)

# Why a sentence is checked by no clause: one of these, then a few words of particulars.
GCS_SIDE = "GCS-side, not observable on the wire"
INFORMATIVE = "informative"
NOT_OVER_THE_WIRE = "not checkable over the wire"


@dataclass(frozen=True)
class Sentence:
    id: str     # "L.n"
    text: str

    @property
    def line(self) -> int:
        return int(self.id.split(".")[0])


@dataclass(frozen=True)
class Entry:
    id: str                          # "L.n", as `requirement_sentences` names it
    text: str                        # the sentence, word for word
    clauses: tuple[str, ...] = ()    # the clauses that check it
    why: str = ""                    # why no clause checks it, or a note on how they do

    @property
    def line(self) -> int:
        return int(self.id.split(".")[0])


def split_sentences(paragraph: str) -> list[str]:
    out: list[str] = []
    pending = ""
    for part in _BREAK.split(paragraph.strip()):
        pending = f"{pending} {part}" if pending else part
        if _ABBREVIATION.search(pending):
            continue
        out.append(" ".join(pending.split()))
        pending = ""
    if pending:
        out.append(" ".join(pending.split()))
    return [s for s in out if s]


def requirement_sentences(seed_text: str) -> list[Sentence]:
    """Every requirement sentence of seed 000's Mission Protocol part, in order (the rule in
    this module's docstring)."""
    lines = seed_text.splitlines()
    start = next((i for i, line in enumerate(lines) if line.strip() == PART_HEADING), None)
    if start is None:
        raise ValueError(f"no line {PART_HEADING!r} in the seed text")
    found = []
    for i in range(start, len(lines)):
        for n, sentence in enumerate(split_sentences(lines[i]), 1):
            if KEYWORDS.search(sentence):
                found.append(Sentence(f"{i + 1}.{n}", sentence))
    return found


def _e(id: str, text: str, clauses: str = "", why: str = "") -> Entry:
    return Entry(id, text, tuple(c.strip() for c in clauses.split(",") if c.strip()), why)


# The map. Clause ids first; `why` for a sentence no clause checks (or a note on how they do).
COVERAGE: tuple[Entry, ...] = (
    _e("271.3", "The mission types must be stored and handled separately/independently.",
       "MIS.CLR.03, MIS.TYP.01, MIS.TYP.05, MIS.G.TY.02, MIS.G.TY.03, MIS.G.TY.04",
       why="the GCS's side (MIS.G.TY.*): another type's request, ACK or item during an operation is not "
           "taken for the running one"),
    _e("333.1", "PX4 support global frames in MAVLink commands (local frames may be supported if the same "
       "command is sent via the command protocol).",
       why=f"{INFORMATIVE}: what PX4 supports (VARIANTS P14); the protocol sets no frame requirement"),
    _e("345.1", "Protocol implementations must allow both message types in supported operations (along with "
       "the corresponding MISSION_REQUEST and MISSION_REQUEST_INT message types).",
       "MIS.UP.14, MIS.DN.02, MIS.DN.03, MIS.G.UP.03",
       why="the GCS's side (MIS.G.UP.03): it answers MISSION_REQUEST; whether a GCS takes MISSION_ITEM in a "
           "download is not checked (the scripted vehicle answers in the form requested)"),
    _e("347.1", "MAVLink users should always prefer MISSION_ITEM_INT because it allows latitude/longitude to be "
       "encoded without the loss of precision that can come from using MISSION ITEM.",
       "MIS.UP.15, MIS.G.DN.09",
       why="each side's requests: the vehicle's in an upload (MIS.UP.15), the GCS's in a download "
           "(MIS.G.DN.09), with MISSION_REQUEST_INT"),
    _e("400.1", "Mission update must be robust!", "MIS.UP.05, MIS.GCS.02"),
    _e("400.2", "A new mission should be fully uploaded and accepted before the old mission is replaced/removed.",
       "MIS.UP.05, MIS.GCS.02"),
    _e("408.1", "A timeout must be started for the GCS to wait on the response from Drone (MISSION_REQUEST_INT).",
       "MIS.G.UP.06, MIS.G.TO.01",
       why="seen through its effect: MISSION_COUNT resent when it expires (MIS.G.UP.06), about 1500 ms "
           "later (MIS.G.TO.01)"),
    _e("412.1", "A timeout must be started for the Drone to wait on the MISSION_ITEM_INT response from GCS.",
       "MIS.UP.06, MIS.UP.07", why="seen through its effect: the request resent when it expires"),
    _e("420.1", "The drone should set the new mission to be the current mission, discarding the original data.",
       "MIS.UP.04"),
    _e("428.2", "If the timeout expires without a response being received then the request must be resent.",
       "MIS.UP.06, MIS.G.UP.04, MIS.G.UP.05, MIS.G.UP.06",
       why="the vehicle resends its requests (MIS.UP.06); the GCS resends MISSION_COUNT (MIS.G.UP.06) and the "
           "last item when the final ACK is lost (MIS.G.UP.05), and answers a resent request (MIS.G.UP.04)"),
    _e("430.1", "Mission items must be received in order.", "MIS.UP.02, MIS.UP.10"),
    _e("430.2", "If an item is received out-of-sequence the expected item should be re-requested by the vehicle "
       "(the out-of-sequence item is dropped).", "MIS.UP.10"),
    _e("432.2", "This must cancel the operation and restore the mission to its previous state.",
       "MIS.UP.12, MIS.UP.13, MIS.CAN.02, MIS.G.UP.08",
       why="the GCS's side (MIS.G.UP.08): no item after the vehicle's error ACK, the upload reported failed; "
           "restoring the mission is the vehicle's"),
    _e("434.2", "Protocol implementations must also support MISSION_ITEM and MISSION_REQUEST in the same way.",
       "MIS.UP.14, MIS.G.UP.03"),
    _e("453.2", "If the timeout expires without a response being received then the request must be resent.",
       "MIS.DN.06, MIS.G.DN.03, MIS.G.DN.04",
       why="the GCS resends MISSION_REQUEST_LIST (MIS.G.DN.03) and an item request (MIS.G.DN.04); the vehicle "
           "answers the resent request (MIS.DN.06)"),
    _e("455.1", "Mission items must be received in order.", "MIS.G.DN.02, MIS.G.DN.07",
       why="in a download the GCS receives the items: it requests them in order (MIS.G.DN.02) and does not "
           "take one out of sequence (MIS.G.DN.07)"),
    _e("455.2", "If an item is received out-of-sequence the expected item should be re-requested by the GCS "
       "(the out-of-sequence item is dropped).", "MIS.G.DN.07"),
    _e("457.2", "This must cancel the operation.", "MIS.DN.05, MIS.DN.08, MIS.G.DN.08",
       why="an error ACK from either side: the GCS's ends the vehicle's download (MIS.DN.08); the vehicle's "
           "(MIS.DN.05 sends one) ends the GCS's, nothing requested after it (MIS.G.DN.08)"),
    _e("460.2", "Protocol implementations must also support MISSION_ITEM and MISSION_REQUEST in the same way.",
       "MIS.DN.03"),
    _e("476.1", "On success, the Drone must broadcast a MISSION_CURRENT message containing the current sequence "
       "number (seq).", "MIS.CUR.01, MIS.CUR.04"),
    _e("478.1", "On failure, the Drone must broadcast a STATUSTEXT with a MAV_SEVERITY and a string stating the "
       "problem.", "MIS.CUR.02"),
    _e("478.2", "This may be displayed in the UI of receiving systems.",
       why=f"{GCS_SIDE}: what a receiving GCS shows in its UI"),
    _e("491.1", "The vehicle must broadcast a MISSION_ITEM_REACHED message whenever a new mission item is reached.",
       "MIS.PRG.01"),
    _e("493.1", "The vehicle must also broadcast a MISSION_CURRENT message if the current mission item is changed.",
       "MIS.PRG.02"),
    _e("517.2", "If the timeout expires without a response being received then the request must be resent.",
       "MIS.CLR.05, MIS.G.CL.02",
       why="the GCS resends MISSION_CLEAR_ALL (MIS.G.CL.02); the vehicle answers the resent one (MIS.CLR.05)"),
    _e("519.2", "This must cancel the operation.", "MIS.G.CL.03",
       why="the GCS's side: a refused clear is reported failed (MIS.G.CL.03); the vehicle's side is "
           f"{NOT_OVER_THE_WIRE}: no standard message makes a conforming vehicle refuse a clear of a type it "
           "stores (ArduPilot refuses while flying in Auto, A12); a refused type is MIS.TYP.04"),
    _e("519.3", "The GCS record of the mission (if any) should be retained.",
       why=f"{GCS_SIDE}: the GCS's own copy of the plan (MIS.G.CL.03 sees the clear fail, not what the GCS "
           "keeps)"),
    _e("523.1", "The above mission operations may be canceled by responding to any request (e.g. "
       "MISSION_REQUEST_INT) with a MISSION_ACK message containing the MAV_MISSION_OPERATION_CANCELLED error.",
       "MIS.CAN.01, MIS.CAN.03, MIS.G.CN.01",
       why="either side cancels: the GCS (MIS.CAN.01, MIS.CAN.03) or the vehicle, answering the GCS's item "
           "request (MIS.G.CN.01)"),
    _e("525.1", "Both systems should then return themselves to the idle state (if the system does not receive the "
       "cancellation message it will resend the request; the recipient will then be in the idle state and may "
       "respond with an appropriate error for that state).", "MIS.CAN.03, MIS.CAN.04, MIS.IDL.01, MIS.G.CN.01",
       why="the GCS's side (MIS.G.CN.01): after the vehicle's OPERATION_CANCELLED it sends nothing more for "
           "the download and reports it failed"),
    _e("529.1", "A timeout should be set for all messages that require a response.",
       "MIS.UP.06, MIS.G.UP.05, MIS.G.UP.06, MIS.G.DN.03, MIS.G.DN.04, MIS.G.CL.02, MIS.G.SC.03",
       why="seen through its effect, the message resent when it expires: the vehicle's requests during an "
           "upload (MIS.UP.06); the GCS's last item, MISSION_COUNT, MISSION_REQUEST_LIST, item requests, "
           "MISSION_CLEAR_ALL and set-current (MIS.G.*; set-current has no specific timeout, 482, so any "
           "the GCS has will do)"),
    _e("529.2", "If the expected response is not received before the timeout then the message must be resent.",
       "MIS.UP.06, MIS.G.UP.05, MIS.G.UP.06, MIS.G.DN.03, MIS.G.DN.04, MIS.G.CL.02, MIS.G.SC.03"),
    _e("529.3", "If no response is received after a number of retries then the client must cancel the operation "
       "and return to an idle state.", "MIS.UP.08, MIS.G.UP.07, MIS.G.DN.10, MIS.G.TO.03",
       why="the GCS gives a silent vehicle up, upload (MIS.G.UP.07) and download (MIS.G.DN.10), but not before "
           "the retries could have run (MIS.G.TO.03, judged against the values of 531.1)"),
    _e("531.1", "The recommended timeout values before resending, and the number of retries are:",
       "MIS.UP.07, MIS.UP.09, MIS.G.TO.01, MIS.G.TO.02, MIS.G.TO.03",
       why="the list that follows: the vehicle's 250 ms for items (MIS.UP.07) and 5 retries (MIS.UP.09); the "
           "GCS's 1500 ms default before resending MISSION_COUNT (MIS.G.TO.01) and 5 retries (MIS.G.TO.02), "
           "an upload kept open that long (MIS.G.TO.03)"),
    _e("543.1", "On successful completion, the message must contain type of MAV_MISSION_ACCEPTED; this is sent by "
       "the system that is receiving the command/data (e.g. the drone for mission upload or the GCS for mission "
       "download).", "MIS.UP.03, MIS.DN.07, MIS.GCS.04, MIS.G.DN.05, MIS.G.DN.06",
       why="the vehicle's ACK ends an upload (MIS.UP.03); the GCS's ACK ACCEPTED ends a download, empty or not "
           "(MIS.G.DN.05, MIS.G.DN.06); the vehicle takes that GCS's ACK as the end (MIS.DN.07) and no other "
           "GCS's (MIS.GCS.04)"),
    _e("545.1", "An operation may also complete with an error - MISSION_ACK.type set to MAV_MISSION_ERROR or some "
       "other error code in MAV_MISSION_RESULT.", "MIS.ERR.01, MIS.UP.13, MIS.UP.17, MIS.DN.05"),
    _e("547.2", "In an error is sent, both ends of the system should reset themselves to the idle state and the "
       "current state of the mission on the vehicle should be unaltered.",
       "MIS.UP.17, MIS.ERR.02, MIS.G.UP.08, MIS.G.DN.08",
       why="the GCS's end (MIS.G.UP.08, MIS.G.DN.08): nothing more sent for the operation after the "
           "vehicle's error ACK"),
    _e("601.3", "Instead it may be a mix of the original and new mission.",
       why=f"{INFORMATIVE}: ArduPilot's non-atomic upload (VARIANTS A2), a departure MIS.UP.05, "
           "MIS.UP.12, MIS.UP.17 and MIS.CAN.02 report"),
    _e("603.1", "Even if upload is successful, the vehicle mission may not match the version on the uploading "
       "system (and if the mission is then downloaded it will differ from the original).",
       why=f"{INFORMATIVE}: ArduPilot's home in slot 0 and rounded storage (VARIANTS A1, A13); plans are "
           "compared in the target's stored form"),
)

BY_SENTENCE: dict[str, Entry] = {e.id: e for e in COVERAGE}
assert len(BY_SENTENCE) == len(COVERAGE), "a sentence is listed twice"

# A clause whose quoted requirement takes in a listed sentence it does not check (it quotes the
# whole paragraph as context): (clause, sentence) -> why it is not mapped there. Any other
# clause that quotes a listed sentence is listed with it (a test checks both ways).
QUOTED_NOT_CHECKED: dict[tuple[str, str], str] = {
    ("MIS.G.TO.03", "529.1"): "it passes a GCS that waits without a timeout; it checks only that the upload "
                              "is not given up early",
    ("MIS.G.TO.03", "529.2"): "it passes a GCS that never resends; it checks only that the upload is not "
                              "given up early",
}

ALL_CLAUSES: tuple[Clause, ...] = CLAUSES + GCS_CLAUSES + MSP_CLAUSES


def _normal(text: str) -> str:
    return " ".join(text.split())


def quotes(clause: Clause, entry: Entry) -> bool:
    """Whether the clause's quoted requirement is (or contains) the sentence."""
    path, _, line = clause.source.rpartition(":")
    if path != SEED_000 or int(line) != entry.line:
        return False
    a, b = _normal(clause.requirement), _normal(entry.text)
    return b in a or a in b


def unlisted_seed_clauses() -> list[Clause]:
    """Clauses of either role that cite seed 000 but quote none of the listed sentences."""
    return [c for c in ALL_CLAUSES if c.source.startswith(SEED_000 + ":")
            and not any(quotes(c, e) for e in COVERAGE)]


def other_source_clauses() -> list[Clause]:
    return [c for c in ALL_CLAUSES if not c.source.startswith(SEED_000 + ":")]


def _side(entry: Entry) -> str:
    roles = {BY_ID[c].role for c in entry.clauses}
    gcs = Role.GCS in roles
    return "both" if gcs and len(roles) > 1 else "gcs" if gcs else "vehicle"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def render_markdown() -> str:
    checked = [e for e in COVERAGE if e.clauses]
    reasons: dict[str, int] = {}
    for e in COVERAGE:
        if not e.clauses:
            kind = e.why.split(":")[0]
            reasons[kind] = reasons.get(kind, 0) + 1
    out = [
        "# Seed 000 requirement sentences and the clauses that check them",
        "",
        "Generated by `mavconform clauses --coverage --output docs/spec-coverage.md` from "
        "`conformance/spec_coverage.py`; a test regenerates it and compares. Source: "
        f"`../shared/{SEED_000}`, its Mission Protocol part.",
        "",
        "## The rule",
        "",
        "1. The part: seed 000 from its line \"Mission Protocol\" (where the restated Mission Protocol "
        "begins) to the end.",
        "2. Each line is a paragraph; a paragraph splits into sentences after `.`, `!` or `?` followed by "
        "white space, except after the abbreviations \"e.g.\", \"i.e.\", \"etc.\" and \"vs.\".",
        "3. A requirement sentence contains, as a whole word in any case: must, shall, should, may, required, "
        "recommended, or \"is expected\" / \"are expected\". (\"can\" is not a keyword: in this text it states "
        "what is possible; the one \"can\" sentence that grants a permission, \"An error can be signaled ...\", "
        "is bound by the \"must\" sentence after it.)",
        "",
        "A sentence is named L.n: line L of the seed file, n-th sentence of that line.",
        "",
        "The clauses are both roles': the vehicle's, and the GCS's (MIS.G.*, role gcs, judged by "
        "`mavconform run --role gcs`). MIS.GCS.* are vehicle clauses (how a vehicle treats a second GCS).",
        "",
        f"## Requirement sentences ({len(COVERAGE)}: {len(checked)} checked by clauses, "
        f"{len(COVERAGE) - len(checked)} not)",
        "",
    ]
    sides = {side: sum(1 for e in checked if _side(e) == side) for side in ("vehicle", "gcs", "both")}
    out += [f"Checked: {sides['vehicle']} on the vehicle's side only, {sides['gcs']} on the GCS's side only, "
            f"{sides['both']} on both sides.", ""]
    if reasons:
        out += ["Not checked: " + "; ".join(f"{n} {kind}" for kind, n in reasons.items()) + ".", ""]
    out += ["| sentence | text | checked by |", "|---|---|---|"]
    for e in COVERAGE:
        if e.clauses:
            cell = ", ".join(f"{c} ({BY_ID[c].level.value})" for c in e.clauses)
            if e.why:
                cell += f"; {e.why}"
        else:
            cell = f"none: {e.why}"
        out.append(f"| {e.id} | {_cell(e.text)} | {_cell(cell)} |")
    unlisted = unlisted_seed_clauses()
    out += [
        "",
        f"## Other seed 000 sentences the clauses check ({len(unlisted)} clauses)",
        "",
        "Sentences without a keyword that still state what a vehicle or a GCS does (field definitions, the "
        "step-by-step sequences, the recommended values): the clauses that quote them.",
        "",
        "| clause | role | level | line | quoted sentence |",
        "|---|---|---|---|---|",
    ]
    for c in sorted(unlisted, key=lambda c: (int(c.source.rpartition(":")[2]), c.id)):
        out.append(f"| {c.id} | {c.role.value} | {c.level.value} | {c.source.rpartition(':')[2]} "
                   f"| {_cell(c.requirement)} |")
    if QUOTED_NOT_CHECKED:
        out += [
            "",
            f"## Sentences a clause quotes but does not check ({len(QUOTED_NOT_CHECKED)})",
            "",
            "The clause quotes the whole paragraph as context; it checks other sentences of it.",
            "",
            "| clause | sentence | why not |",
            "|---|---|---|",
        ]
        for (clause, sentence), why in QUOTED_NOT_CHECKED.items():
            out.append(f"| {clause} | {sentence} | {_cell(why)} |")
    others = other_source_clauses()
    out += [
        "",
        f"## Clauses from other sources ({len(others)})",
        "",
        "Where seed 000 is silent: framing and routing from seed 001, message definitions from the "
        "upstream XML; an MSP flight controller's waypoint store (MSP.*) from seed 004 and INAV 9.1's "
        "docs and source (`inav-9.1/...`).",
        "",
        "| clause | role | level | source | title |",
        "|---|---|---|---|---|",
    ]
    for c in others:
        out.append(f"| {c.id} | {c.role.value} | {c.level.value} | {c.source} | {_cell(c.title)} |")
    return "\n".join(out) + "\n"
