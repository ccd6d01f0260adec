"""The ground station's part of the handover, beside its operator-control client (seed 003, 4.4-4.5).

"During a handover, ground control stations assume a passive role. They await the initial
request from the drone and subsequently take appropriate action." The agent plays both roles:

- partner: on the vehicle's invitation (MAV_CMD_REQUEST_OPERATOR_CONTROL addressed to us,
  param4 our own id, while we do not hold control) it requests control, with takeover
  disallowed and the invitation's param3 as its request timeout (steps 1-2). The connect
  notice after the grant is the same command while we hold control: the client's ACK of it
  is step 5, nothing else to do;
- commander: a request the vehicle forwards (the client's policy hook, `policy`) is allowed
  only from a known partner and only when the handover is expected: the vehicle's own
  telemetry puts it in the handover region of the two GCSs (geographic methods: within
  `slack_m` of the intersection, the telemetry at most `telemetry_max_age` old), or on a leg
  the partner owns (waypoint method: MISSION_CURRENT's target or the item before it). Once
  CONTROL_STATUS names the partner, it stops commanding and says so with a release (step 6),
  which the vehicle answers NOT_IN_CONTROL: the confirmation that it holds nothing any more.

Requests from GCSs that are not partners go to `fallback` (by default the operator decides).
Sans-IO like the client: `handle(frame, now, client)` / `poll(now, client)` return the
client's actions; the agent moves only through `AGENT_TRANSITIONS`.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from enum import Enum
from typing import Any, Mapping

from ..state_table import next_state
from ..wire.frame import Frame
from . import control_messages as cm
from .control_client import Action, ControlClient, Policy, always
from .control_results import Decision, TakeoverRequested
from .geo import GeoPoint
from .hysteresis import signed_distance_m
from .regions import Intersection, OwnedWaypoints

__all__ = ["AGENT_TRANSITIONS", "AgentEvent", "AgentState", "GcsHandoverConfig", "HandoverAgent"]


class AgentState(Enum):
    IDLE = "idle"
    REQUESTING = "invited: our request for control runs"
    AUTHORISED = "we allowed a partner's takeover: waiting for CONTROL_STATUS to name it"
    RELEASING = "the partner holds control: our release (step 6) queued or in flight"


class AgentEvent(Enum):
    INVITED = "the vehicle invited us (step 1): request control"
    REQUEST_ENDED = "our request finished (granted or not)"
    AUTHORISE = "a forwarded request from a partner, expected: allow takeover (step 3)"
    PARTNER_TOOK_OVER = "CONTROL_STATUS names the partner we allowed"
    LAPSED = "the partner did not take over in time"
    RELEASE_ENDED = "our release finished (step 6 sent), or could not be sent in time"


_A, _G = AgentState, AgentEvent
AGENT_TRANSITIONS: dict[tuple[AgentState, AgentEvent], AgentState] = {
    (_A.IDLE, _G.INVITED): _A.REQUESTING,
    (_A.REQUESTING, _G.REQUEST_ENDED): _A.IDLE,
    (_A.IDLE, _G.AUTHORISE): _A.AUTHORISED,
    (_A.AUTHORISED, _G.AUTHORISE): _A.AUTHORISED,     # a second forward (a resend past our dedup)
    (_A.AUTHORISED, _G.PARTNER_TOOK_OVER): _A.RELEASING,
    (_A.AUTHORISED, _G.LAPSED): _A.IDLE,
    (_A.RELEASING, _G.RELEASE_ENDED): _A.IDLE,
}


@dataclass(frozen=True)
class GcsHandoverConfig:
    """The GCS's copy of the mission's handover data (the thesis shares it as the "Mission"
    message): every GCS's coverage by system id, one region method, as the vehicle has it."""

    coverages: Any                       # Mapping[int, Coverage] in, sorted pairs kept
    slack_m: float = 100.0               # geographic: telemetry this far outside still counts
    telemetry_max_age: float = 5.0       # s: older telemetry says nothing
    takeover_wait: float = 15.0          # s after allowing to wait for the partner's grant
    disconnect: bool = True              # send step 6 (release) once the partner holds control

    def __post_init__(self) -> None:
        pairs = self.coverages.items() if isinstance(self.coverages, Mapping) else self.coverages
        object.__setattr__(self, "coverages", tuple(sorted((int(k), v) for k, v in pairs)))
        for name in ("slack_m", "telemetry_max_age", "takeover_wait"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")


class HandoverAgent:
    """One GCS's handover policy for one vehicle; plug `policy` into its ControlClient."""

    def __init__(self, system: int, config: GcsHandoverConfig, *, fallback: Policy = always(None)) -> None:
        self.system = system
        self.config = config
        self.fallback = fallback
        self.coverage = dict(config.coverages)
        self.partners = frozenset(self.coverage) - {system}
        self.state = AgentState.IDLE
        self.history: deque[tuple[AgentState, AgentEvent, AgentState]] = deque(maxlen=256)
        self.position: tuple[GeoPoint, float] | None = None   # the vehicle's, from GLOBAL_POSITION_INT
        self.mission_current: tuple[int, float] | None = None
        self.authorised_for = 0
        self.decisions: list[tuple[int, Decision, str]] = []  # (requester, decision, why), first 1000
        self._until: float | None = None       # the current state's deadline
        self._invited_until: float | None = None
        self._invite_timeout = cm.DEFAULT_REQUEST_TIMEOUT
        self._release_sent = False

    # --- the client's policy hook -----------------------------------------------------------
    def policy(self, request: TakeoverRequested) -> Decision | None:
        """Answer a request the vehicle forwarded to us, the commander."""
        if request.requester not in self.partners:
            return self.fallback(request)
        if request.allow_takeover:
            # An invited partner asks with takeover disallowed. Param 2 set is the partner's own
            # "allow takeover" re-request, resent after it lost control to us (its ACK was
            # lost): the manager reads it as a request, and allowing it would hand control back.
            expected, why = False, "param2 1: an owner's allow-takeover resent after it lost control"
        else:
            expected, why = self.expected(request.requester, request.at)
        decision = Decision.ALLOW if expected else Decision.REFUSE
        if len(self.decisions) < 1000:
            self.decisions.append((request.requester, decision, why))
        if expected and self.state in (AgentState.IDLE, AgentState.AUTHORISED):
            self._move(AgentEvent.AUTHORISE)
            self.authorised_for = request.requester
            self._until = request.at + self.config.takeover_wait
        return decision

    def expected(self, partner: int, now: float) -> tuple[bool, str]:
        """Whether the vehicle's telemetry says a handover to `partner` is due, and why."""
        mine = self.coverage.get(self.system)
        theirs = self.coverage.get(partner)
        if mine is None or theirs is None:
            return False, "no coverage known for this GCS or the partner"
        max_age = self.config.telemetry_max_age
        if isinstance(theirs, OwnedWaypoints):
            if self.mission_current is None or now - self.mission_current[1] > max_age:
                return False, "no recent MISSION_CURRENT"
            seq = self.mission_current[0]
            owned = theirs.owns(seq) or (seq > 0 and theirs.owns(seq - 1))
            return owned, f"leg to item {seq} {'is' if owned else 'is not'} the partner's"
        if self.position is None or now - self.position[1] > max_age:
            return False, "no recent GLOBAL_POSITION_INT"
        d = signed_distance_m(Intersection((mine, theirs)), self.position[0])
        ok = d <= self.config.slack_m
        return ok, f"{d:.0f} m from the handover region (slack {self.config.slack_m:g} m)"

    # --- events ---------------------------------------------------------------------------
    def handle(self, frame: Frame, now: float, client: ControlClient) -> list[Action]:
        """A frame from the target vehicle, after the client has seen it."""
        msg = frame.msg
        name = msg._type
        if name == "GLOBAL_POSITION_INT":
            self.position = (GeoPoint.from_e7(msg.lat, msg.lon), now)
        elif name == "MISSION_CURRENT":
            self.mission_current = (msg.seq, now)
        elif (cm.is_request_control(msg) and cm.addressed_to(msg, client.system, client.component)
              and msg.param1 == cm.ACTION_REQUEST and msg.param4 == self.system and not client.in_control):
            # step 1: the vehicle asks us to request control (param 3: the time we have)
            self._invite_timeout = cm.clamp_timeout(msg.param3)
            self._invited_until = now + self._invite_timeout
        return self._progress(now, client)

    def poll(self, now: float, client: ControlClient) -> list[Action]:
        return self._progress(now, client)

    def next_deadline(self) -> float | None:
        times = [t for t in (self._until, self._invited_until) if t is not None]
        return min(times) if times else None

    # --- internals ------------------------------------------------------------------------
    def _progress(self, now: float, client: ControlClient) -> list[Action]:
        out: list[Action] = []
        s = self.state
        if s is AgentState.REQUESTING and not client.busy:
            self._move(AgentEvent.REQUEST_ENDED)
        elif s is AgentState.AUTHORISED:
            if client.owner == self.authorised_for:
                self._move(AgentEvent.PARTNER_TOOK_OVER)
                self._release_sent = not self.config.disconnect
                self._until = now + self.config.takeover_wait
            elif now >= self._until:
                self._move(AgentEvent.LAPSED)
                self._until, self.authorised_for = None, 0
        if self.state is AgentState.RELEASING:
            if not self._release_sent and not client.busy:
                self._release_sent = True
                out += client.release_control(now)     # step 6: "commander disconnects"
            elif (self._release_sent and not client.busy) or now >= self._until:
                self._move(AgentEvent.RELEASE_ENDED)
                self._until, self.authorised_for = None, 0
        if self._invited_until is not None:
            if now >= self._invited_until or client.in_control:
                self._invited_until = None
            elif self.state is AgentState.IDLE and not client.busy:
                self._invited_until = None
                self._move(AgentEvent.INVITED)
                out += client.request_control(now, allow_takeover=False, timeout=self._invite_timeout, wait=True)
        return out

    def _move(self, event: AgentEvent) -> None:
        old = self.state
        self.state = next_state(AGENT_TRANSITIONS, old, event, "GCS handover agent")
        self.history.append((old, event, self.state))
