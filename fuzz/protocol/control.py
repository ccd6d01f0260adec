"""Operator control under fuzzing (`--operator-control`): the rules the vehicle is held to, and the judges.

The vehicle is its own system manager (MAVLink development.xml, MAV_CMD_REQUEST_OPERATOR_CONTROL
and CONTROL_STATUS; `reference_impl/handover/control_manager.py`). The fuzzer's GCSs request,
release and hand over control, fall silent, and keep doing mission operations, which now meet
the control filter. The safety properties (`CONTROL_INVARIANTS`) are judged by one of two
judges, chosen by transport:

- `ControlWatch` (in-process targets): a `DatagramNode` proxy around the vehicle. It sees every
  frame the vehicle accepted (its endpoint's `receive`), every message it sends (its endpoint's
  `send`) and, after every call (a datagram or a poll), who owns control, the takeover flag,
  the stored plans, the current item and whether it flies. Each change is judged in the call
  that made it, against the frames that came in during that call: a change with no cause in
  that call (a request, a release, a write from the GCS allowed to make it) had no cause.
  Times are the vehicle's own (virtual), so the bounds are exact.
- `WireControl` (wire_control.py; external targets: udp:, tcp:, serial:): only what the wire
  shows. Which GCSs may own control follows from the answers our GCSs got (ACCEPTED to a
  request: that GCS; to a release: nobody; an unanswered one: either), widened wherever the target could have dropped a silent
  owner; after every step the probe waits (bounded, on a clean link) for a CONTROL_STATUS,
  whose gcs_main must be one of them. A mission write ACCEPTED while only another GCS can be
  in control was executed for a non-owner. The owner-loss timeout of a remote target is not
  known, so a silent owner kept too long is judged in-process only.

The rules are those the fuzzer asked the vehicle to keep (`HANDOVER_CONTROL`, the suite's own
system manager: CONTROL_STATUS every 1 s, owner lost after 5 s without HEARTBEAT, a 10 s
takeover window, open to every GCS while nobody is in control), not the ones a mutant's
configuration says, so a mutant that streams slower or keeps owners longer is caught.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable

from mavconform.conformance.target_uri import SUITE_CONTROL
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_client import ClientConfig
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.control_transitions import ControlState
from mavconform.reference_impl.mission.items import PLAN_TYPES
from mavconform.reference_impl.wire.dialect import mavlink as _d

CONTROL_INVARIANTS: dict[str, str] = {
    "two-owners": "Never two GCSs in control at once: a GCS the vehicle told it holds control "
                  "(COMMAND_ACK ACCEPTED to its request) is the owner afterwards, and CONTROL_STATUS "
                  "names one gcs_main and no gcs_secondary (single-owner mode).",
    "non-owner-executed": "No mission write or command from a GCS not in control takes effect: the "
                          "stored plans change only through the owner's upload or clear (anyone's "
                          "while nobody is in control, the vehicle being open then), and a "
                          "MISSION_START or set-current from a non-owner never moves the vehicle.",
    "owner-without-request": "Control changes hands only by a grant to a GCS that asked for it while "
                             "nobody was in control or takeover was allowed, by the owner's release, "
                             "or by owner loss once its HEARTBEATs stopped for the loss timeout; the "
                             "takeover flag is set only by the owner. Never spontaneously.",
    "control-answer-lies": "A COMMAND_ACK to MAV_CMD_REQUEST_OPERATOR_CONTROL means what it says: "
                           "ACCEPTED to a release leaves the GCS out of control, ACCEPTED to the "
                           "owner's re-request sets the takeover flag it asked for, and a well-formed "
                           "request is refused (FAILED, never another code) only while another GCS "
                           "is in control without allowing takeover.",
    "control-status-lies": "The vehicle's last CONTROL_STATUS names its owner and takeover flag "
                           "within one status period (+25%) of any change, and one comes at least "
                           "every status period (+25%).",
    "handover-unbounded": "Every control request the vehicle receives gets exactly one final "
                          "COMMAND_ACK within 1.5 s (a GCS's ack timeout); a request forwarded to "
                          "the owner ends within its timeout (param 3) and a takeover window within "
                          "10 s; every control operation of our GCSs ends with one result within "
                          "the client's bound (its retries, plus the request's timeout when it "
                          "waits for the owner).",
    "silent-owner-kept": "A GCS silent (no HEARTBEAT, no control command) for longer than the "
                         "owner-loss timeout plus one status period is no longer in control.",
}

# The system manager a --operator-control vehicle runs: the suite's (`builtin:spec` under `mavconform
# run`), whose 5 s owner loss a wait step (up to 20 s) reaches.
HANDOVER_CONTROL = SUITE_CONTROL
STATUS_SLACK = 0.25      # of a status period: a real vehicle's timer jitter
EPS = 1e-6               # s: virtual time is exact; this only absorbs float rounding
CLIENT = ClientConfig()  # our GCSs' control client (ack timeout, retries, request timeout)
ANSWER_BOUND = CLIENT.ack_timeout   # s for the vehicle's COMMAND_ACK: a GCS resends after it
WIRE_STATUS_WAIT = 2.0   # s the probe waits for a CONTROL_STATUS over UDP (1 Hz nominal, +1 s)
WIRE_STATUS_GRACE = 0.5  # s after an answer before a CONTROL_STATUS is taken to reflect it (UDP:
                         # more than a faults step's reorder delay, delay and jitter together)


@dataclass(frozen=True)
class ControlRules:
    """The numbers the judges hold the vehicle to: the system manager's own (`of`)."""

    status_period: float
    owner_loss_timeout: float
    takeover_window: float
    open_when_unowned: bool
    answer_bound: float = ANSWER_BOUND

    @classmethod
    def of(cls, config: ManagerConfig) -> "ControlRules":
        """The rules of the system manager we asked the vehicle to be."""
        return cls(config.status_period, config.owner_loss_timeout, config.takeover_window,
                   config.open_when_unowned)

    @property
    def status_bound(self) -> float:
        return self.status_period * (1 + STATUS_SLACK)


def operation_bound(timeout: float, wait: bool, config: ClientConfig = CLIENT) -> float:
    """How long our control client may take for one operation: an answer of its own it may
    be queued behind, every resend of the command, and with `wait` the request's own timeout
    for the owner's answer, then every resend of the request again (`ControlClient.poll`)."""
    sends = (config.max_retries + 1) * config.ack_timeout
    return 2 * sends + (timeout + config.ack_timeout + sends if wait else 0.0)


def is_request(msg: Any) -> bool:
    """MAV_CMD_REQUEST_OPERATOR_CONTROL (COMMAND_LONG or COMMAND_INT): a request or a release."""
    return cm.is_request_control(msg)


def well_formed(msg: Any, sender: int) -> bool:
    """A request the XML gives a meaning to: param 1 release/request, param 2 0/1, param 4 0
    or the sender's own id (single-owner mode)."""
    return (sender != 0 and msg.param1 in (0.0, 1.0) and msg.param2 in (0.0, 1.0)
            and msg.param4 in (0.0, float(sender)))


def result_name(result: int) -> str:
    """MAV_RESULT by name, so a finding reads without the XML at hand."""
    enum = _d.enums.get("MAV_RESULT", {})
    entry = enum.get(result)
    return entry.name if entry is not None else str(result)


@dataclass
class Broken:
    """A violation the judge saw, with the vehicle's time."""

    invariant: str
    detail: str
    at: float


# --- in-process ------------------------------------------------------------------------------

@dataclass
class _Snapshot:
    owner: int
    allowed: bool
    state: ControlState
    version: int
    plans: tuple
    seq: int
    flying: bool


@dataclass
class _Call:
    """What one call of the vehicle received and sent."""

    now: float
    polled: bool
    frames: list[Any] = field(default_factory=list)
    acks: list[tuple[int, int]] = field(default_factory=list)   # (requester, MAV_RESULT) of 32100


class ControlWatch:
    """A `DatagramNode` proxy around an in-process vehicle with operator control, judging
    every change of control, plan, current item and flight in the call that made it."""

    def __init__(self, vehicle: Any, rules: ControlRules,
                 names: Callable[[int], str] = lambda s: f"GCS {s}") -> None:
        if vehicle.control is None:
            raise ValueError("ControlWatch needs a vehicle with operator control")
        self.vehicle = vehicle
        self.manager = vehicle.control
        self.rules = rules
        self.name = names
        self.system = vehicle.config.system
        self.component = vehicle.config.component
        self.broken: list[Broken] = []
        self.error: BaseException | None = None      # an exception of ours, not the vehicle's
        self.last_beat: dict[int, float] = {}        # sysid -> its last HEARTBEAT the vehicle got
        self.last_alive: dict[int, float] = {}       # ... or control command / ACK
        self.pending: dict[int, deque[tuple[float, Any]]] = {}   # requests awaiting their answer
        self.status: tuple[float, int, bool] | None = None       # time, gcs_main, takeover flag
        self.granted_at = 0.0
        self.disagree_since: float | None = None
        self.window_since: float | None = None
        self.forward_until: float | None = None     # a forwarded request's param 3 runs out
        self.requests_seen = 0
        self._call: _Call | None = None
        endpoint = vehicle.endpoint
        self._receive, self._send = endpoint.receive, endpoint.send
        endpoint.receive, endpoint.send = self._received, self._sent
        self._state = self._snapshot()

    # --- DatagramNode ---------------------------------------------------------------------
    def datagram_received(self, data: bytes, source: Any, now: float) -> None:
        self._call = _Call(now, polled=False)
        self.vehicle.datagram_received(data, source, now)   # raises: the guard keeps it (a crash)
        self._judged(now)

    def poll(self, now: float) -> None:
        self._call = _Call(now, polled=True)
        self.vehicle.poll(now)
        self._judged(now)

    def next_deadline(self) -> float | None:
        return self.vehicle.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Any]]:
        return self.vehicle.take_outgoing()

    # --- between steps --------------------------------------------------------------------
    def tick(self, now: float) -> None:
        """The time-bound checks at `now` (between steps, when the vehicle may not be called)."""
        self._guarded(lambda: self._timed(now))

    @property
    def first(self) -> Broken | None:
        return self.broken[0] if self.broken else None

    # --- hooks on the vehicle's endpoint ---------------------------------------------------
    def _received(self, data: bytes, source: Any) -> list[Any]:
        frames = self._receive(data, source)
        call = self._call
        if call is not None and frames:
            self._guarded(lambda: self._note_frames(frames, call))
        return frames

    def _sent(self, msg: Any, to: Any = None) -> None:
        self._send(msg, to)
        call = self._call
        if call is not None:
            self._guarded(lambda: self._note_sent(msg, call))

    def _note_frames(self, frames: list[Any], call: _Call) -> None:
        now = call.now
        for frame in frames:
            call.frames.append(frame)
            msg, sysid = frame.msg, frame.src_system
            name = msg._type
            if name == "HEARTBEAT":
                self.last_beat[sysid] = self.last_alive[sysid] = now
            elif is_request(msg) and cm.addressed_to(msg, self.system, self.component):
                self.last_alive[sysid] = now
                self.requests_seen += 1
                self.pending.setdefault(sysid, deque()).append((now, msg))
            elif name == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL:
                self.last_alive[sysid] = now

    def _note_sent(self, msg: Any, call: _Call) -> None:
        name = msg._type
        if name == "CONTROL_STATUS":
            self.status = (call.now, msg.gcs_main, bool(msg.flags & cm.FLAG_TAKEOVER_ALLOWED))
            others = [s for s in msg.gcs_secondary if s]
            if others:
                self._break("two-owners", (
                    f"CONTROL_STATUS names GCS {msg.gcs_main} as gcs_main and {others} as secondary "
                    "owners: more than one GCS in control (single-owner mode keeps gcs_secondary zero)"),
                    call.now)
        elif name == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL:
            call.acks.append((msg.target_system, msg.result))
        elif is_request(msg) and msg.confirmation == 0:
            # a refused request forwarded to the owner: its param 3 bounds how long it may wait
            self.forward_until = call.now + cm.clamp_timeout(msg.param3)

    # --- judging --------------------------------------------------------------------------
    def _judged(self, now: float) -> None:
        call, self._call = self._call, None
        if call is not None:
            self._guarded(lambda: self._judge(call))

    def _guarded(self, body: Callable[[], None]) -> None:
        """Our code inside the vehicle's call: an exception here is a tool error, never a
        target crash (the guard around us would take it for one)."""
        if self.error is not None:
            return
        try:
            body()
        except Exception as exc:   # noqa: BLE001 - ours, kept for Runner to raise
            self.error = exc

    def _snapshot(self) -> _Snapshot:
        v, mgr = self.vehicle, self.manager
        store = v.store
        return _Snapshot(mgr.owner, mgr.takeover_allowed, mgr.state, store.version,
                         tuple(store.items(t) for t in PLAN_TYPES), v.server.progress.seq, v.flight.flying)

    def _judge(self, call: _Call) -> None:
        before, after = self._state, self._snapshot()
        self._state = after
        now = call.now
        self._answers(call, before, after)
        if (before.owner, before.allowed) != (after.owner, after.allowed):
            self._control_change(call, before, after)
        if not call.polled:
            self._effects(call, before, after)
        if after.state is ControlState.WINDOW_OPEN:
            if before.state is not ControlState.WINDOW_OPEN:
                self.window_since = now
        else:
            self.window_since = None
        self._timed(now)

    def _answers(self, call: _Call, before: _Snapshot, after: _Snapshot) -> None:
        """Exactly one final answer per request, and what each answer means."""
        for requester, result in call.acks:
            if result == _d.MAV_RESULT_IN_PROGRESS:
                continue
            queue = self.pending.get(requester)
            who = self.name(requester)
            if not queue:
                self._break("handover-unbounded", (
                    f"the vehicle sent {who} a second COMMAND_ACK ({result_name(result)}) to "
                    "MAV_CMD_REQUEST_OPERATOR_CONTROL: every request gets exactly one final answer"),
                    call.now)
                continue
            _, msg = queue.popleft()
            if well_formed(msg, requester):
                self._meaning(requester, msg, result, before, after, call.now)

    def _meaning(self, x: int, msg: Any, result: int, before: _Snapshot, after: _Snapshot,
                 now: float) -> None:
        who = self.name(x)
        if msg.param1 == cm.ACTION_REQUEST:
            if result == _d.MAV_RESULT_ACCEPTED:
                if after.owner != x:
                    if after.owner:
                        self._break("two-owners", (
                            f"the vehicle told {who} its request for control was ACCEPTED, yet "
                            f"{self.name(after.owner)} is still in control: both believe they command it"),
                            now)
                    else:
                        self._break("control-answer-lies", (
                            f"the vehicle ACCEPTED {who}'s request for control, yet nobody is in control"),
                            now)
                elif after.allowed != (msg.param2 == 1.0):
                    self._break("control-answer-lies", (
                        f"the vehicle ACCEPTED {who}'s request with takeover "
                        f"{'allowed' if msg.param2 == 1.0 else 'disallowed'} (param 2), yet its takeover "
                        f"flag is {'set' if after.allowed else 'clear'}"), now)
            elif result == _d.MAV_RESULT_FAILED:
                if before.owner in (0, x) or before.allowed:
                    why = ("nobody was in control" if before.owner == 0 else
                           f"{who} was itself in control" if before.owner == x else
                           f"{self.name(before.owner)} allowed takeover")
                    self._break("control-answer-lies", (
                        f"the vehicle refused {who}'s request for control (FAILED) although {why}: "
                        "a request is refused only while another GCS holds control without allowing "
                        "takeover"), now)
            else:
                self._break("control-answer-lies", (
                    f"the vehicle answered {who}'s well-formed request for control with "
                    f"{result_name(result)}; the XML's answers are ACCEPTED (granted) and FAILED "
                    "(takeover needs the owner's permission)"), now)
        elif result == _d.MAV_RESULT_ACCEPTED and after.owner == x:
            self._break("control-answer-lies", (
                f"the vehicle ACCEPTED {who}'s release of control, yet {who} is still in control"), now)

    def _control_change(self, call: _Call, before: _Snapshot, after: _Snapshot) -> None:
        now = call.now
        asked = {f.src_system: f.msg for f in call.frames if is_request(f.msg)
                 and cm.addressed_to(f.msg, self.system, self.component)}
        if after.owner != before.owner:
            where = self._where(call)
            if after.owner:
                new = self.name(after.owner)
                msg = asked.get(after.owner)
                if msg is None or msg.param1 != cm.ACTION_REQUEST:
                    self._break("owner-without-request", (
                        f"{new} became the owner (was {self._owner(before.owner)}) {where}, without "
                        "having asked for control"), now)
                elif before.owner and not before.allowed:
                    self._break("owner-without-request", (
                        f"{new} took control from {self.name(before.owner)}, which had not allowed "
                        "takeover (the request should have been refused and forwarded to it)"), now)
                self.granted_at = now
            else:
                old = before.owner
                msg = asked.get(old)
                if msg is None or msg.param1 != cm.ACTION_RELEASE:
                    since = self.last_beat.get(old, self.granted_at)
                    silent = now - since
                    if silent < self.rules.owner_loss_timeout - EPS:
                        self._break("owner-without-request", (
                            f"{self.name(old)} lost control {where} after only {silent:.2f} s without "
                            f"a HEARTBEAT (the loss timeout is {self.rules.owner_loss_timeout:g} s), "
                            "and it had not released it"), now)
        elif after.owner and after.allowed and not before.allowed:
            msg = asked.get(after.owner)
            if msg is None or msg.param2 != 1.0:
                self._break("owner-without-request", (
                    f"the takeover flag of {self.name(after.owner)} was set {self._where(call)}, "
                    "though the owner did not ask for it"), now)

    def _effects(self, call: _Call, before: _Snapshot, after: _Snapshot) -> None:
        """A plan, the current item or the flight changed while handling this datagram: some
        sender in it must have been allowed to change the vehicle's state."""
        if after.version != before.version:
            changed = [t.label for t, a, b in zip(PLAN_TYPES, after.plans, before.plans) if a != b]
            what = (f"changed its {' and '.join(changed)} plan" if changed
                    else "committed a write (that left its plans as they were)")
        elif after.seq != before.seq:
            what = f"moved its current mission item ({before.seq} -> {after.seq})"
        elif after.flying and not before.flying:
            what = "started flying the mission"
        else:
            return
        senders = {f.src_system for f in call.frames}
        if any(self._may_command(s, before.owner) for s in senders):
            return
        sent = ", ".join(sorted({f.msg._type + (f" {f.msg.command}" if f.msg._type.startswith("COMMAND_") else "")
                                 for f in call.frames})) or "nothing"
        self._break("non-owner-executed", (
            f"the vehicle {what} on {sent} from "
            f"{', '.join(self.name(s) for s in sorted(senders)) or 'nobody'}, not in control "
            f"({self._owner(before.owner)} was)"), call.now)

    def _may_command(self, sysid: int, owner: int) -> bool:
        if sysid == self.system:
            return True
        return sysid == owner if owner else self.rules.open_when_unowned

    def _timed(self, now: float) -> None:
        rules = self.rules
        st = self.status
        if st is None:
            if now > rules.status_bound + EPS:
                self._break("control-status-lies", f"no CONTROL_STATUS in the first {now:.2f} s", now)
        else:
            age = now - st[0]
            if age > rules.status_bound + EPS:
                self._break("control-status-lies", (
                    f"the last CONTROL_STATUS was {age:.2f} s ago; it should come every "
                    f"{rules.status_period:g} s"), now)
            owner, allowed = self.manager.owner, self.manager.takeover_allowed
            if (st[1], st[2]) != (owner, allowed):
                if self.disagree_since is None:
                    self.disagree_since = now
                elif now - self.disagree_since > rules.status_bound + EPS:
                    self._break("control-status-lies", (
                        f"for {now - self.disagree_since:.2f} s the vehicle's owner has been "
                        f"{self._owner(owner)} (takeover {'allowed' if allowed else 'disallowed'}) while "
                        f"its last CONTROL_STATUS says {self._owner(st[1])} (takeover "
                        f"{'allowed' if st[2] else 'disallowed'})"), now)
            else:
                self.disagree_since = None
        owner = self.manager.owner
        if owner:
            alive = max(self.last_alive.get(owner, -math.inf), self.granted_at)
            if now - alive > rules.owner_loss_timeout + rules.status_period + EPS:
                self._break("silent-owner-kept", (
                    f"{self.name(owner)} has sent no HEARTBEAT (nor control command) for "
                    f"{now - alive:.2f} s and is still in control; the owner-loss timeout is "
                    f"{rules.owner_loss_timeout:g} s (+ one status period)"), now)
        for sysid, queue in self.pending.items():
            if queue and now - queue[0][0] > rules.answer_bound + EPS:
                self._break("handover-unbounded", (
                    f"a request for operator control from {self.name(sysid)} got no final COMMAND_ACK "
                    f"within {rules.answer_bound:g} s"), now)
        state = self.manager.state
        if (state is ControlState.REQUEST_PENDING and self.forward_until is not None
                and now > self.forward_until + EPS):
            self._break("handover-unbounded", (
                f"a request forwarded to the owner is still pending {now - self.forward_until:.2f} s "
                "after its timeout (param 3)"), now)
        if self.window_since is not None and now - self.window_since > rules.takeover_window + EPS:
            self._break("handover-unbounded", (
                f"the takeover window has been open {now - self.window_since:.2f} s; it lasts "
                f"{rules.takeover_window:g} s"), now)

    def _where(self, call: _Call) -> str:
        if call.polled:
            return "on a timer (no message came in)"
        frames = call.frames
        if not frames:
            return "on a datagram with no valid frame"
        f = frames[0]
        return f"on a {f.msg._type} from {self.name(f.src_system)}"

    def _owner(self, sysid: int) -> str:
        return self.name(sysid) if sysid else "nobody"

    def _break(self, invariant: str, detail: str, at: float) -> None:
        if len(self.broken) < 16:
            self.broken.append(Broken(invariant, detail, at))
