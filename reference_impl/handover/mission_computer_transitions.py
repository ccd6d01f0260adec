"""Transition tables of the mission computer: state -> event -> new state, as data (seed 003, ch. 4).

Three tables. `MC_TRANSITIONS` is the thesis's three states (4.3: on_load, on_mission,
on_handover). `EMERGENCY_TRANSITIONS` adds the fourth, `on_emergency`, which the thesis leaves
to future work (4.7: "RTL or the nearest rally point"; emergency_procedure.py): entered from a
flight, left only by landing at the refuge or by a known GCS taking control back. The mission
computer moves through `MC_TABLE`, the two together; they are kept apart so a test can walk
each (a normal flight takes every move of the first and none of the second).
`PHASE_TRANSITIONS` is the progress of one handover through the six steps of 4.5, as the
vehicle observes them over MAVLink operator control (docs/handover.md has the mapping). The
engine moves only through these tables; `render_markdown` draws them for the docs, and a test
keeps docs/handover.md equal to it.

The phase table is total over the observations: under loss, duplication and reordering a
step may be seen twice, late, or after a later one, and such an observation leaves the phase
where it is (listed as such, not ignored by code), so the only error left is a real bug.
"""

from __future__ import annotations

from enum import Enum


class McState(Enum):
    """The mission computer's three central states (4.3)."""

    ON_LOAD = "on_load"          # waiting for the mission to start (4.3.1)
    ON_MISSION = "on_mission"    # flying; the region check runs every check period (4.3.2)
    ON_HANDOVER = "on_handover"  # the handover sequence toward one partner runs (4.3.3)
    ON_EMERGENCY = "on_emergency"  # flying to the refuge, no GCS in control (4.7)


class McEvent(Enum):
    MISSION_STARTED = "the flight started (MAV_CMD_MISSION_START accepted)"
    MISSION_ENDED = "the flight ended"
    HANDOVER_DUE = "a handover region was entered (after the dwell): step 1 sent"
    CONTROL_MOVED = "gcs_main changed outside a handover (the manager's word is followed)"
    COMPLETED = "all six steps observed within the bound"
    UNCONFIRMED = "control moved to the partner, but step 5 or 6 was not seen within the bound"
    ABORTED = "control did not move to the partner in time, or the region was left first"
    EMERGENCY = ("a trigger fired (commander lost; outside every coverage past the grace): refuge chosen, "
                 "control dropped")
    TAKEN_BACK = "a known GCS whose coverage holds the vehicle was granted control (the refuge flight goes on)"
    LANDED = "the vehicle landed at the refuge (the flight ended)"


_S, _E = McState, McEvent
MC_TRANSITIONS: dict[tuple[McState, McEvent], McState] = {
    (_S.ON_LOAD, _E.MISSION_STARTED): _S.ON_MISSION,
    (_S.ON_LOAD, _E.CONTROL_MOVED): _S.ON_LOAD,
    (_S.ON_MISSION, _E.CONTROL_MOVED): _S.ON_MISSION,
    (_S.ON_MISSION, _E.HANDOVER_DUE): _S.ON_HANDOVER,
    (_S.ON_MISSION, _E.MISSION_ENDED): _S.ON_LOAD,
    # "The same procedure repeats on the trip back": every ending returns to on_mission
    (_S.ON_HANDOVER, _E.COMPLETED): _S.ON_MISSION,
    (_S.ON_HANDOVER, _E.UNCONFIRMED): _S.ON_MISSION,
    (_S.ON_HANDOVER, _E.ABORTED): _S.ON_MISSION,
}

# The emergency procedure (4.7). No GCS command leaves on_emergency: the vehicle refuses every
# state-changing command while in it; only a control request from a known GCS whose coverage
# holds the vehicle gets through (docs/handover.md, "Emergency procedure").
EMERGENCY_TRANSITIONS: dict[tuple[McState, McEvent], McState] = {
    (_S.ON_MISSION, _E.EMERGENCY): _S.ON_EMERGENCY,
    # a handover under way ends first (its result says why), in the same step
    (_S.ON_HANDOVER, _E.EMERGENCY): _S.ON_EMERGENCY,
    (_S.ON_EMERGENCY, _E.TAKEN_BACK): _S.ON_MISSION,
    (_S.ON_EMERGENCY, _E.LANDED): _S.ON_LOAD,
}
MC_TABLE: dict[tuple[McState, McEvent], McState] = {**MC_TRANSITIONS, **EMERGENCY_TRANSITIONS}


class HandoverPhase(Enum):
    """How far one handover has come (thesis steps of 4.5 in brackets)."""

    INVITING = "[1] partner invited to request control"
    REQUESTED = "[2] partner's request refused and forwarded to the commander"
    AUTHORISED = "[3] commander allowed takeover (or released control)"
    CONNECTED = "[4] control granted to the partner: the commit"
    CONFIRMED = "[5] partner acknowledged the connect notice"
    DISCONNECTED = "[6] old commander said it let go"
    DONE = "[5] and [6] both seen"


class PhaseEvent(Enum):
    PARTNER_REQUESTED = "the partner's MAV_CMD_REQUEST_OPERATOR_CONTROL reached the vehicle"
    COMMANDER_ALLOWED = "CONTROL_STATUS: the commander set takeover allowed"
    COMMANDER_RELEASED = "CONTROL_STATUS: no owner (the commander released or was lost)"
    GRANTED = "CONTROL_STATUS: gcs_main is the partner"
    PARTNER_CONFIRMED = "the partner's COMMAND_ACK of the connect notice"
    COMMANDER_DISCONNECTED = "the old commander's release (param1 0) after the grant"


_H, _V = HandoverPhase, PhaseEvent
_BEFORE_COMMIT = (_H.INVITING, _H.REQUESTED, _H.AUTHORISED)
_AFTER_COMMIT = (_H.CONNECTED, _H.CONFIRMED, _H.DISCONNECTED, _H.DONE)

PHASE_TRANSITIONS: dict[tuple[HandoverPhase, PhaseEvent], HandoverPhase] = {
    # stale, repeated or out-of-order observations first: they leave the phase as it is
    **{(p, e): p for p in HandoverPhase for e in PhaseEvent},
    (_H.INVITING, _V.PARTNER_REQUESTED): _H.REQUESTED,
    # a commander that allows before any forward (its own takeover flag) skips step 2
    (_H.INVITING, _V.COMMANDER_ALLOWED): _H.AUTHORISED,
    (_H.REQUESTED, _V.COMMANDER_ALLOWED): _H.AUTHORISED,
    # releasing answers the forward too ("may choose to release control")
    (_H.INVITING, _V.COMMANDER_RELEASED): _H.AUTHORISED,
    (_H.REQUESTED, _V.COMMANDER_RELEASED): _H.AUTHORISED,
    # the commit, whatever way the partner got there (window, released, owner lost)
    **{(p, _V.GRANTED): _H.CONNECTED for p in _BEFORE_COMMIT},
    (_H.CONNECTED, _V.PARTNER_CONFIRMED): _H.CONFIRMED,
    (_H.CONNECTED, _V.COMMANDER_DISCONNECTED): _H.DISCONNECTED,
    (_H.CONFIRMED, _V.COMMANDER_DISCONNECTED): _H.DONE,
    (_H.DISCONNECTED, _V.PARTNER_CONFIRMED): _H.DONE,
}

# the step each phase stands for (the thesis's numbering), for results and reports
PHASE_STEP: dict[HandoverPhase, int] = {
    _H.INVITING: 1, _H.REQUESTED: 2, _H.AUTHORISED: 3, _H.CONNECTED: 4,
    _H.CONFIRMED: 5, _H.DISCONNECTED: 6, _H.DONE: 6,
}
COMMITTED = frozenset(_AFTER_COMMIT)


class HandoverOutcome(Enum):
    COMPLETED = "completed"        # owner is the partner; steps 5 and 6 seen
    UNCONFIRMED = "unconfirmed"    # owner is the partner; step 5 or 6 missing at the bound
    ABORTED = "aborted"            # no commit: the old commander kept control (or lost it)


def render_markdown() -> str:
    """Both tables as Markdown (docs/handover.md includes exactly this text)."""
    lines = ["| state | event | new state |", "|---|---|---|"]
    for (s, e), n in MC_TABLE.items():
        lines.append(f"| `{s.value}` | {e.name} ({e.value}) | `{n.value}` |")
    lines += ["", "| phase | event | new phase |", "|---|---|---|"]
    for (p, e), n in PHASE_TRANSITIONS.items():
        if n is not p:
            lines.append(f"| {p.name} | {e.name} | {n.name} |")
    lines += ["", "Every other (phase, event) pair leaves the phase as it is: a repeated, late or "
              "out-of-order observation."]
    return "\n".join(lines) + "\n"
