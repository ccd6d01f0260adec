"""Protocol fuzz steps: what each one does to the world, and the invariants after it.

A step is a JSON-safe dict; the Hypothesis machine draws them and a saved case replays
them, both through `Runner.apply` then `Runner.check`, so a case replays exactly what the
search ran. The vocabulary (drawn by `fuzz.strategies`):

  {"op": "upload", "type": T, "items": [WIRE_ITEM...], "float": bool?}   GCS A, to its result
  {"op": "download", "type": T} / {"op": "clear", "type": T|255}
  {"op": "set_current", "seq": N, "command": bool}
  {"op": "cancel", "of": OP, "after": S}          start OP, cancel it S seconds in
  {"op": "second_gcs", "first": OP, "second": OP, "after": S}   B starts `second` S s into A's `first`
  {"op": "stray", "messages": [RAW...], "during": OP|null, "after": S}
  {"op": "faults", "up": SCHEDULE|null, "down": SCHEDULE|null}   on A's link, from now on
  {"op": "wait", "seconds": S}

With operator control (`--operator-control`; `fuzz.protocol.control`), also:

  {"op": "control", "gcs": "a"|"b", "action": "request"|"release"|"allow"|"disallow",
   "allow": bool, "timeout": S, "wait_for_owner": bool, "answer": "allow"|"release"|"refuse"|null}
      through the GCS's control client, to its result: a request (param 2 `allow`, param 3
      `timeout`; with `wait_for_owner`, a refusal waits for the owner's answer), a release, or the
      owner's takeover flag set or cleared (a GCS that does not believe it owns control sends
      nothing). `answer` is what the owner, A or B, answers a request forwarded to it, from
      this step on.
  {"op": "gcs_loss", "gcs": "a"|"b", "seconds": S, "wait": W}   the GCS sends no HEARTBEAT
      for S s from now (then beats again); the step lets W s pass
  an operation with "gcs": "b" is GCS B's (mission writes now meet the control filter), and
  strays may carry MAV_CMD_REQUEST_OPERATOR_CONTROL and MAV_CMD_MISSION_START

WIRE_ITEM is a dict of MISSION_ITEM_INT fields (a "seq"/"mission_type" key overrides what
goes out; "fx"/"fy" are floats sent in MISSION_ITEM.x/y instead of the int x/y converted);
RAW is {"msg": NAME, "fields": {...}, "to": "target"|"broadcast"|"other-system"|
"other-component", "from": "a"|"b"|"mute"} ("mute" never answers).

Operations run until their result, bounded by the protocol's own timeouts; then every
node is given a bounded time to return to idle. The invariants (`INVARIANTS`) are checked
after every step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

from mavconform.conformance.harness.stored_form import describe_differences
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPE_BY_VALUE, PLAN_TYPES, MissionItem, MissionType
from mavconform.reference_impl.mission.results import OperationResult
from mavconform.reference_impl.mission.transitions import SlotState
from mavconform.reference_impl.net.sim import CaptureHook
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_results import ControlResult, Decision

from ..case import Violation
from .control import CONTROL_INVARIANTS, WIRE_STATUS_GRACE, WIRE_STATUS_WAIT, operation_bound
from .faults import build_fault_model
from .gcs import FuzzGcs
from .connection import TargetConnection
from .versions import Plan, Versions, Write, describe_plan
from .world import SYSTEM_A, SYSTEM_B, World, describe_system

INVARIANTS: dict[str, str] = {
    "atomic-upload": "The vehicle's stored plan of each type is always one whole version it "
                     "accepted (or the initial or cleared one), never a mix of two (spec profile).",
    "download-matches-upload": "A successful download returns the plan last accepted (one of "
                               "the versions the vehicle may hold).",
    "one-result": "Every operation ends with exactly one result, within a bound derived from "
                  "the protocol's timeouts and retry limit.",
    "idle": "After every step, the vehicle and every GCS return to idle within a bound derived "
            "from the protocol's timeouts.",
    "retry-limit": "Neither end resends one request more often than the retry limit.",
    "target-hang": "After every step the vehicle still answers MISSION_REQUEST_LIST (a HEARTBEAT "
                   "alone is not an answer).",
    "target-crash": "The vehicle never dies: an in-process vehicle never raises; a remote one keeps "
                    "sending HEARTBEAT and answering.",
}
DECISIONS = {"allow": Decision.ALLOW, "release": Decision.RELEASE, "refuse": Decision.REFUSE}


def invariants(handover: bool = False) -> dict[str, str]:
    """The invariants a campaign checks: the mission ones, and with `handover` the control ones."""
    return {**INVARIANTS, **CONTROL_INVARIANTS} if handover else dict(INVARIANTS)


HEARTBEAT_SILENCE = 3.0   # s without a HEARTBEAT (a 1 Hz stream) that make a silent target a crashed one

MAX_ROUNDS = 10_000   # bound on the wait loop of one step (each round advances time or ends)
UDP_DRAIN = 0.3       # s at most after stray messages over a real network, for their replies to land
UDP_QUIET = 0.05      # s without an answer from the target that end that wait early


@dataclass
class _Run:
    gcs: FuzzGcs
    name: str
    op: dict[str, Any]
    done: int                     # len(gcs.results) when it started
    started: float
    plans: tuple[Plan, ...] = ()  # upload: what the vehicle may store if it applies it
    result: OperationResult | None = None
    # Its GCS sent stray messages meanwhile: the vehicle's replies to those carry no
    # correlation id and may be taken for this operation's answer, so its result says
    # nothing definite about the vehicle (a clear "refused" by a late reply to a stray).
    untrusted: bool = False

    @property
    def finished(self) -> bool:
        return len(self.gcs.results) > self.done


@dataclass
class _ControlRun:
    """One operator-control operation of a GCS's control client, waited for like `_Run`."""

    gcs: FuzzGcs
    name: str
    op: dict[str, Any]
    done: int                     # len(gcs.control_results) when it started
    started: float
    bound: float                  # `control.operation_bound`

    @property
    def finished(self) -> bool:
        return len(self.gcs.control_results) > self.done


@dataclass
class _Group:
    """What one step did that the oracle must hear about."""

    runs: list[_Run] = field(default_factory=list)
    writes: list[Write] = field(default_factory=list)
    strays: bool = False   # raw messages went out: their replies may still be on the way
    controls: list[_ControlRun] = field(default_factory=list)


class Runner:
    """Applies steps to a fresh `World` and checks the invariants after each."""

    def __init__(self, target: str, seed: int, *, capture: CaptureHook | None = None,
                 atomic: bool | None = None, connection: TargetConnection | None = None,
                 profile: str | None = None, latency: float = 0.0, handover: bool = False) -> None:
        self.world = w = World(target, seed, capture=capture, atomic=atomic, connection=connection,
                               profile=profile, latency=latency, handover=handover)
        self.index = -1
        self.step_started = 0.0
        self._folded = {"a": 0, "b": 0}   # control results folded into the wire judge, per GCS
        self._faulty = False                # UDP: A's link had faults since the last fold
        if w.wire is not None:              # who holds control as the example starts
            first = w.connection.control_status_after(w.now() - WIRE_STATUS_WAIT, WIRE_STATUS_WAIT)
            if first is not None:
                w.wire.observed(first.gcs_main)
        initial = {t: w.stored(t) for t in PLAN_TYPES}   # None over the wire: unknown
        self.versions = Versions(initial, atomic=w.profile.atomic, form=w.profile.form)
        t = w.profile.timings
        self.idle_bound = (t.default_timeout * (t.max_retries + 1)       # a download left open
                           + t.item_timeout * (t.max_retries + 1)        # an upload left silent
                           + 2 * t.default_timeout)

    def close(self) -> None:
        self.world.close()

    # --- the two entry points -------------------------------------------------------------
    def apply(self, step: dict[str, Any]) -> Violation | None:
        """Run one step; a violation seen while it ran (results, idleness) is returned."""
        self.index += 1
        self.step_started = self.world.now()
        step = self.world.profile.scope.adapt(step)
        if step is None:   # about what the profile says the target does not have
            return None
        kind = step.get("op")
        handler: Callable[[dict[str, Any]], _Group | Violation | None] = {
            "upload": self._operation, "download": self._operation, "clear": self._operation,
            "set_current": self._operation, "cancel": self._cancel, "second_gcs": self._second_gcs,
            "stray": self._stray, "faults": self._faults, "wait": self._wait,
            "control": self._control, "gcs_loss": self._gcs_loss,
        }[kind]
        group = handler(step)
        if group is None or isinstance(group, Violation):
            return self._control_broken() or group
        return self._control_broken() or self._conclude(group) or self._control_broken()

    def check(self) -> Violation | None:
        """The invariants that hold between steps."""
        w = self.world
        self._raise_tool_crash()
        crashed = w.crashes()
        if crashed:
            return self._violation("target-crash", f"the vehicle raised and fell silent: {crashed[0]}")
        if w.watch is not None:
            w.watch.tick(w.now())
            v = self._control_broken()
            if v is not None:
                return v
        if w.vehicle is not None:
            for t in PLAN_TYPES:
                stored = w.stored(t)
                if not self.versions.allows(t, stored):
                    return self._violation("atomic-upload", (
                        f"the vehicle stores {describe_plan(stored)} as its {t.label} plan, which is "
                        f"none of the versions it accepted or may have applied "
                        f"({self.versions.describe(t)}): a partial or invented plan"))
                self.versions.observe(t, stored)
            limit = w.profile.timings.max_retries
            retries = w.vehicle.server.stats.max_consecutive_retries
            if w.profile.retry_cap and retries > limit:
                return self._violation("retry-limit", (
                    f"the vehicle resent one item request {retries} times; the limit is {limit}"))
        return self._probe()

    # --- steps ----------------------------------------------------------------------------
    def _operation(self, step: dict[str, Any]) -> _Group:
        if step.get("gcs") == "b":
            return _Group(runs=[self._start(self.world.b, "B", step)])
        return _Group(runs=[self._start(self.world.a, "A", step)])

    def _cancel(self, step: dict[str, Any]) -> _Group:
        run = self._start(self.world.a, "A", step["of"])
        self.world.run_until(lambda: run.finished, float(step["after"]))
        if not run.finished:
            self.world.a.cancel(self.world.now())
        return _Group(runs=[run])

    def _second_gcs(self, step: dict[str, Any]) -> _Group:
        first = self._start(self.world.a, "A", step["first"])
        self.world.run_until(lambda: first.finished, float(step["after"]))
        return _Group(runs=[first, self._start(self.world.b, "B", step["second"])])

    def _stray(self, step: dict[str, Any]) -> _Group:
        group = _Group(strays=True)
        during = step.get("during")
        if during:
            run = self._start(self.world.a, "A", during)
            group.runs.append(run)
            self.world.run_until(lambda: run.finished, float(step["after"]))
            run.untrusted = not run.finished and any(raw.get("from", "a") == "a" for raw in step["messages"])
        for raw in step["messages"]:
            gcs = self.world.gcss[raw.get("from", "a")]
            msg = self._raw_message(raw)
            gcs.send_raw(msg)
            if self.world.wire is not None and cm.is_request_control(msg):
                # whatever it asked, it may have moved control (to its sender, or to nobody)
                self.world.wire.widen([gcs.system, 0], f"a stray operator-control command from "
                                      f"{self._name(gcs.system)}")
            write = self._raw_write(raw)
            if write is not None:
                group.writes.append(write)
        return group

    def _faults(self, step: dict[str, Any]) -> None:
        now = self.world.now()
        up, down = build_fault_model(step.get("up"), now), build_fault_model(step.get("down"), now)
        self.world.set_faults(up, down)
        self._faulty = self._faulty or not (up.is_clean and down.is_clean)
        return None

    def _wait(self, step: dict[str, Any]) -> _Group:
        self.world.run_for(float(step["seconds"]))
        return _Group()

    # --- operator control (--operator-control) ------------------------------------------------------
    def _control(self, step: dict[str, Any]) -> _Group:
        """A request, release or takeover-flag change through the GCS's control client, waited
        for to its result; `answer` is the owners' policy for forwarded requests from now on."""
        w = self.world
        gcs, name = self._control_gcs(step)
        answer = DECISIONS.get(step.get("answer") or "")
        for g in (w.a, w.b):
            g.answer = answer
        now = w.now()
        action = step["action"]
        timeout = min(max(float(step.get("timeout", cm.DEFAULT_REQUEST_TIMEOUT)), cm.TIMEOUT_MIN), cm.TIMEOUT_MAX)
        wait = bool(step.get("wait_for_owner")) and action == "request"
        if gcs.control_busy:
            return _Group()   # still busy with an earlier one (it had no result in its bound)
        run = _ControlRun(gcs, name, step, len(gcs.control_results), now, operation_bound(timeout, wait))
        if action == "request":
            gcs.request_control(now, allow_takeover=bool(step.get("allow")), timeout=timeout, wait=wait)
        elif action == "release":
            gcs.release_control(now)
        elif action in ("allow", "disallow"):
            if not gcs.set_takeover(action == "allow", now):
                return _Group()   # not in control, as far as it knows: nothing to set
        else:
            raise ValueError(f"not a control action: {action!r}")
        return _Group(controls=[run])

    def _gcs_loss(self, step: dict[str, Any]) -> _Group:
        """The GCS sends no HEARTBEAT for `seconds`, then beats again; `wait` s pass now."""
        w = self.world
        gcs, _ = self._control_gcs(step)
        gcs.silence(w.now(), float(step["seconds"]))
        w.run_for(float(step.get("wait", 0.0)))
        return _Group()

    def _control_gcs(self, step: dict[str, Any]) -> tuple[FuzzGcs, str]:
        w = self.world
        if not w.handover:
            raise ValueError(f"a {step['op']} step needs operator control (--operator-control)")
        return (w.b, "B") if step.get("gcs") == "b" else (w.a, "A")

    def _fold_control(self, until: float | None = None) -> None:
        """UDP: fold our GCSs' control results (those finished by `until`) into the wire judge
        in finishing order, then widen it wherever the target may have dropped an owner: a GCS
        that was silent, faults on the link its HEARTBEATs cross, an owner that never beats
        (the loss timeout of a remote target is unknown). Idempotent."""
        w = self.world
        wire = w.wire
        if wire is None:
            return
        new: list[tuple[float, int, ControlResult]] = []
        for key, gcs in (("a", w.a), ("b", w.b)):
            log = gcs.control_log
            done = self._folded[key]
            while done < len(log) and (until is None or log[done].finished <= until):
                new.append((log[done].finished, gcs.system, log[done]))
                done += 1
            self._folded[key] = done
        for _, sysid, result in sorted(new, key=lambda n: (n[0], n[1])):
            wire.result(sysid, result, result.finished)
        silent = [g for g in (w.a, w.b) if g.silent_until > self.step_started]
        clean = w.link_clean()
        if silent:
            wire.widen([0], f"{', '.join(self._name(g.system) for g in silent)} falling silent")
        elif self._faulty or not clean:
            wire.widen([0], "the link faults (an owner's HEARTBEATs may not have got through)")
        elif wire.possible and wire.possible - {0, SYSTEM_A, SYSTEM_B}:
            wire.widen([0], "an owner that sends no HEARTBEAT")
        self._faulty = not clean

    def _wire_writes(self, group: _Group) -> Violation | None:
        """UDP: a mission write the vehicle ACCEPTED while, by the answers so far, only another
        GCS can have been in control was executed for a non-owner. Judged in the order the
        results came; a write whose result came within WIRE_STATUS_GRACE of a control answer is
        not judged (the two may have crossed on the link)."""
        w = self.world
        wire = w.wire
        answers = [r.finished for g in (w.a, w.b) for r in g.control_log]
        for run in sorted(group.runs, key=lambda r: r.gcs.results[r.done].finished):
            result = run.gcs.results[run.done]
            self._fold_control(until=result.finished)
            if (not result.ok or run.untrusted or run.op["op"] not in ("upload", "clear")
                    or any(abs(t - result.finished) < WIRE_STATUS_GRACE for t in answers)
                    or wire.may_write(run.gcs.system)):
                continue
            could = " or ".join(sorted(self._name(s) for s in wire.possible or ()))
            return self._violation("non-owner-executed", (
                f"the vehicle ACCEPTED {describe_op(run.op)} by GCS {run.name}, which is not in control "
                f"(after {wire.because} only {could} can be)"))
        self._fold_control()
        return None

    def _name(self, sysid: int) -> str:
        return describe_system(sysid) if sysid else "nobody"

    def _wire_status(self) -> Violation | None:
        """UDP: the target's latest CONTROL_STATUS, held against the wire judge. It must be
        fresh (at most WIRE_STATUS_WAIT old: the stream is nominally 1 Hz) and sent after the
        step's last answer had time to show in it; if it is not, the probe waits (bounded, on
        a clean link) for one that is."""
        w = self.world
        wire = w.wire
        self._fold_control()
        now = w.now()
        since = max(now - WIRE_STATUS_WAIT, wire.answered_at + WIRE_STATUS_GRACE)
        wait = max(0.0, since - now) + WIRE_STATUS_WAIT
        status = w.connection.control_status_after(since, wait)
        if status is None:
            return self._violation("control-status-lies", (
                f"no CONTROL_STATUS from the target for {WIRE_STATUS_WAIT + wait:.1f} s, the last "
                f"{wait:.1f} s on a clean link (it should come at about 1 Hz)"))
        broken = wire.judge(status.gcs_main, status.gcs_secondary)
        return None if broken is None else self._violation(*broken)

    def _control_broken(self) -> Violation | None:
        """What the in-process control judge saw (first violation), or our own bug in it."""
        w = self.world
        error = w.control_error()
        if error is not None:
            raise error
        broken = w.watch.first if w.watch is not None else None
        if broken is None:
            return None
        return self._violation(broken.invariant, f"{broken.detail} (at t={broken.at:.2f} s)")

    # --- running operations ---------------------------------------------------------------
    def _start(self, gcs: FuzzGcs, name: str, op: dict[str, Any]) -> _Run:
        w = self.world
        now = w.now()
        gcs.listen()
        run = _Run(gcs, name, op, len(gcs.results), now)
        kind = op["op"]
        if kind == "upload":
            t = MissionType(op["type"])
            items, rewrite = wire_to_items(op["items"], t)
            run.plans = (tuple(items),)
            gcs.upload(t, items, rewrite, as_float=bool(op.get("float")), now=now)
        elif kind == "download":
            gcs.download(MissionType(op["type"]), now)
        elif kind == "clear":
            gcs.clear(MissionType(op["type"]), now)
        elif kind == "set_current":
            gcs.set_current(int(op["seq"]), now, via_command=bool(op.get("command")))
        else:
            raise ValueError(f"not an operation: {op!r}")
        return run

    def _bound(self, run: _Run | _ControlRun) -> float:
        """How long an operation may take: every message of it retried to the limit."""
        if isinstance(run, _ControlRun):
            return run.bound
        t = run.gcs.timings
        op = run.op
        if op["op"] == "upload":
            n = len(op["items"])
        elif op["op"] == "download":
            n = run.gcs.counts.get(op["type"], 0)   # grows once the vehicle says its count
        else:
            n = 0
        return t.default_timeout * (t.max_retries + 2) * max(n + 2, 2)

    def _wait_for_results(self, runs: list[_Run | _ControlRun]) -> Violation | None:
        w = self.world
        for _ in range(MAX_ROUNDS):
            pending = [r for r in runs if not r.finished]
            if not pending:
                return None
            now = w.now()
            limit, late = min(((r.started + self._bound(r), r) for r in pending), key=lambda p: p[0])
            if now >= limit:
                self._raise_tool_crash()
                crashed = w.crashes()
                if crashed:
                    return self._violation("target-crash", f"the vehicle raised and fell silent: {crashed[0]}")
                if isinstance(late, _ControlRun):
                    return self._violation("handover-unbounded", (
                        f"{describe_op(late.op)} by GCS {late.name} had no result {limit - late.started:g} s "
                        f"after it started (the control client's bound: its retries, and the request's "
                        f"timeout when it waits for the owner)"))
                return self._violation("one-result", (
                    f"{describe_op(late.op)} by GCS {late.name} had no result {limit - late.started:g} s "
                    f"after it started (the bound from the protocol's timeouts and retry limit)"))
            w.run_until(lambda: all(r.finished for r in runs), limit - now)
        return self._violation("one-result", "the operations of this step did not settle (wait loop bound)")

    def _conclude(self, group: _Group) -> Violation | None:
        v = self._wait_for_results([*group.runs, *group.controls])
        if v is not None:
            return v
        for control in group.controls:
            extra = len(control.gcs.control_results) - control.done
            if extra != 1:
                return self._violation("handover-unbounded", (
                    f"{describe_op(control.op)} by GCS {control.name} ended with {extra} results"))
        wire = self.world.wire
        if wire is not None:
            v = self._wire_writes(group)
            if v is not None:
                return v
        writes = list(group.writes)
        reads: list[tuple[MissionType, Plan]] = []
        for run in group.runs:
            result = run.result = run.gcs.results[run.done]
            limit = run.gcs.timings.max_retries
            if result.max_consecutive_retries > limit:
                return self._violation("retry-limit", (
                    f"GCS {run.name} resent one message {result.max_consecutive_retries} times during "
                    f"{describe_op(run.op)}; the limit is {limit}"))
            writes += self._op_writes(run)
            if run.op["op"] == "download" and result.ok:
                reads.append((MissionType(run.op["type"]), tuple(result.items or ())))
        touched = {t for wr in writes for t in wr.types}
        same = self.versions.form.same
        for t, plan in reads:
            candidates = [p for wr in writes if t in wr.types for p in wr.plans]
            if not self.versions.atomic and any(t in wr.types for wr in writes):
                continue   # a non-atomic vehicle (VARIANTS A2) may show a read the upload half-way
            if not (self.versions.allows(t, plan) or any(same(plan, p) for p in candidates)):
                return self._violation("download-matches-upload", (
                    f"a download of the {t.label} plan returned {describe_plan(plan)}, which is none "
                    f"of the versions the vehicle accepted ({self.versions.describe(t)})"
                    + self._closest(t, plan, candidates)))
        self.versions.apply(writes)
        for t, plan in reads:
            if t not in touched:
                self.versions.observe(t, plan)
        v = self._settle(group)
        if v is not None:
            return v
        for run in group.runs:
            extra = len(run.gcs.results) - run.done
            if extra != 1:
                return self._violation("one-result", (
                    f"{describe_op(run.op)} by GCS {run.name} ended with {extra} results"))
        return None

    def _closest(self, t: MissionType, plan: Plan, sent: list[Plan]) -> str:
        """How the downloaded plan differs from the nearest version of the same length, in
        the target's stored form: a reader must see the field, not only two digests."""
        form = self.versions.form
        held = [(p, True) for p in (self.versions.possible[t] or ())] + [(p, False) for p in sent]
        best: list[str] | None = None
        for p, stored in held:
            if len(p) == len(plan):
                diffs = form.differences(plan, p, want_stored=stored)
                if best is None or len(diffs) < len(best):
                    best = diffs
        if not best:
            return ""
        return f"; nearest: {describe_differences(best)} (compared as: {form.describe()})"

    def _op_writes(self, run: _Run) -> list[Write]:
        op, result = run.op, run.result
        assert result is not None
        confirmed = result.ok and not run.untrusted
        maybe = not confirmed and (result.outcome_unknown or run.untrusted)
        # refused before a single item went out (a DENIED from the control filter to a GCS not
        # in control, or from a vehicle busy with another GCS): nothing of it was applied,
        # even on a vehicle whose uploads are not atomic
        untouched = (not confirmed and not maybe and result.nack is not None and run.gcs.items_sent == 0)
        if op["op"] == "upload":
            plans = run.plans
            asked_float = any(msg._type == m.REQUEST_FLOAT for msg in run.gcs.heard)
            if op.get("float") or asked_float:
                # the items went out as MISSION_ITEM, "fx"/"fy" overrides and all (with
                # out-of-range x/y no float plan is possible: only a refusal is right)
                _, rewrite = wire_to_items(op["items"], MissionType(op["type"]))
                for truncate in (False, True):
                    variant = float_variant(plans[0], rewrite, truncate=truncate)
                    if variant is not None and variant not in plans:
                        plans = plans + (variant,)
            return [Write((MissionType(op["type"]),), plans, confirmed, maybe, untouched)]
        if op["op"] == "clear":
            types = PLAN_TYPES if op["type"] == MissionType.ALL else (MissionType(op["type"]),)
            return [Write(types, ((),), confirmed, maybe, untouched)]
        return []

    def _settle(self, group: _Group) -> Violation | None:
        """Wait (bounded) until both ends are idle and, in virtual time, nothing is in
        flight: a late reply must not land in the next step's operation, where the GCS
        could take it for an answer (replies carry no request id)."""
        w = self.world
        gcss = (w.a, w.b)
        if group.strays and not w.virtual:
            since = w.now()        # replies to stray messages: let them arrive now
            w.run_until(lambda: w.connection.replies_quiet(since, UDP_QUIET), UDP_DRAIN)
        if w.run_until(lambda: w.vehicle_idle() and not any(g.busy for g in gcss) and w.quiet(),
                       self.idle_bound):
            return None
        if not w.vehicle_idle():
            busy = ", ".join(f"{t.label} {w.vehicle.server.state(t).name}" for t in PLAN_TYPES
                             if w.vehicle.server.state(t) is not SlotState.IDLE)
            return self._violation("idle", (
                f"the vehicle was still busy ({busy}) {self.idle_bound:g} s after the step's "
                f"operations ended"))
        names = [n for n, g in (("A", w.a), ("B", w.b)) if g.busy]
        if names:
            return self._violation("idle", f"GCS {', '.join(names)} still busy {self.idle_bound:g} s after its result")
        return self._violation("idle", (
            f"the link never fell quiet in {self.idle_bound:g} s after the step's operations ended "
            f"({w.driver.in_flight()} datagrams in flight): a message storm"))

    # --- stray messages -------------------------------------------------------------------
    def _addressed(self, raw: dict[str, Any]) -> tuple[int, int]:
        ts, tc = self.world.target
        return {"target": (ts, tc), "broadcast": (0, 0), "other-system": ((ts % 250) + 1, tc),
                "other-component": (ts, (tc % 250) + 1)}[raw.get("to", "target")]

    def _raw_message(self, raw: dict[str, Any]) -> Any:
        cls = getattr(_d, f"MAVLink_{raw['msg'].lower()}_message")
        ts, tc = self._addressed(raw)
        return cls(target_system=ts, target_component=tc, **raw["fields"])

    def _raw_write(self, raw: dict[str, Any]) -> Write | None:
        """What a stray message may do to the stored plans: a COUNT 0 or a CLEAR_ALL that
        reaches the vehicle is a legitimate clear; a COUNT or ITEM may start or touch an
        upload (harmless on an atomic vehicle, a possible mix on a non-atomic one)."""
        if raw.get("to", "target") not in ("target", "broadcast"):
            return None
        name, fields = raw["msg"], raw["fields"]
        raw_type = fields.get("mission_type")
        if name == "MISSION_CLEAR_ALL":
            types = PLAN_TYPES if raw_type == MissionType.ALL else (
                (PLAN_TYPE_BY_VALUE[raw_type],) if raw_type in PLAN_TYPE_BY_VALUE else ())
            return Write(types, ((),), False, True) if types else None
        if raw_type not in PLAN_TYPE_BY_VALUE:
            return None
        t = PLAN_TYPE_BY_VALUE[raw_type]
        if name == "MISSION_COUNT":
            return Write((t,), ((),), False, fields["count"] == 0)
        if name in ("MISSION_ITEM_INT", "MISSION_ITEM"):
            return Write((t,), (), False, False)
        return None

    # --- liveness -------------------------------------------------------------------------
    def _probe(self) -> Violation | None:
        """MISSION_REQUEST_LIST from a third GCS over a clean link, retried like a GCS would;
        a MISSION_COUNT (or any MISSION_ACK, e.g. DENIED) to it is an answer. A download it
        opens is closed at once, so the probe leaves the vehicle as it found it."""
        w = self.world
        t = w.profile.timings
        with w.faults_lifted():
            for _ in range(t.max_retries + 1):
                if self._ask_list(MissionType.MISSION):
                    return self._counted(MissionType.MISSION) or (
                        None if w.virtual else self._other_counts()) or (
                        None if w.wire is None else self._wire_status())
                age = w.heartbeat_age()
                if age is not None and age > HEARTBEAT_SILENCE:
                    break          # silent altogether: no use asking again
        self._raise_tool_crash()
        asked = f"MISSION_REQUEST_LIST (asked every {t.default_timeout:g} s)"
        crashed = w.crashes()
        if crashed:
            return self._violation("target-crash", f"the vehicle raised and fell silent: {crashed[0]}")
        age = w.heartbeat_age()
        if age is not None and age > HEARTBEAT_SILENCE:
            return self._violation("target-crash", (
                f"the target fell silent: no HEARTBEAT for {_seconds(age)} and no answer to {asked}"))
        beating = "" if age is None else " although its HEARTBEAT still comes"
        return self._violation("target-hang", f"the vehicle did not answer {asked}{beating}")

    def _ask_list(self, t: MissionType) -> bool:
        """The probe asks for `t`'s list once: a MISSION_COUNT (or any MISSION_ACK, e.g.
        DENIED) to it within the profile's timeout is an answer."""
        w, probe = self.world, self.world.probe
        me = probe.system
        probe.listen()
        probe.send_raw(m.request_list_message(t, w.target))
        return w.run_until(lambda: any(msg._type in ("MISSION_COUNT", "MISSION_ACK") and msg.target_system == me
                                       for msg in probe.heard), w.profile.timings.default_timeout)

    def _counted(self, t: MissionType) -> Violation | None:
        """Judge the MISSION_COUNT the probe heard for `t` (if any) against the lengths of
        the plans the vehicle may hold, and close the download it opened."""
        w, probe = self.world, self.world.probe
        count = probe.counts.get(int(t))
        if count is not None and not self.versions.allows_count(t, count):
            return self._violation("download-matches-upload", (
                f"the vehicle reports {count} {t.label} items (MISSION_COUNT to a MISSION_REQUEST_LIST), "
                f"but every version it may hold has another length ({self.versions.describe(t)})"))
        if count:
            probe.send_raw(m.ack_message(MissionResult.OPERATION_CANCELLED, t, w.target))
            w.run_until(_always, 0.0)
        return None

    def _other_counts(self) -> Violation | None:
        """Over the wire the store cannot be read: the fence and rally counts are asked
        too (one try each, a few milliseconds), so a plan of the wrong length is seen after
        the step that made it, not only when a download happens to follow."""
        for t in (MissionType.FENCE, MissionType.RALLY):
            if self._ask_list(t):
                v = self._counted(t)
                if v is not None:
                    return v
        return None

    def _raise_tool_crash(self) -> None:
        """One of our own GCS nodes raised: that is our bug, never the target's."""
        exc = self.world.tool_crash()
        if exc is not None:
            raise exc

    def _violation(self, invariant: str, detail: str) -> Violation:
        return Violation(invariant, detail, self.index if self.index >= 0 else None)


# --- helpers ---------------------------------------------------------------------------------

WIRE_FIELDS = ("frame", "command", "param1", "param2", "param3", "param4", "x", "y", "z",
               "current", "autocontinue")


def wire_to_items(wire: list[dict[str, Any]], t: MissionType
                  ) -> tuple[list[MissionItem], dict[int, dict[str, int | float]]]:
    """Wire items -> the `MissionItem`s the client uploads, and the fields to rewrite on the
    way out: a "seq" or "mission_type" that differs from the transfer's (on either item
    message), and "fx"/"fy", floats that go out in MISSION_ITEM.x/y instead of the item's
    int x/y converted (MISSION_ITEM_INT keeps the int x/y; `fuzz.protocol.gcs.outgoing`)."""
    items, rewrite = [], {}
    for seq, d in enumerate(wire):
        items.append(MissionItem(seq, int(d["frame"]), int(d["command"]), float(d["param1"]),
                                 float(d["param2"]), float(d["param3"]), float(d["param4"]),
                                 int(d["x"]), int(d["y"]), float(d["z"]), int(d["current"]),
                                 int(d["autocontinue"]), t))
        over: dict[str, int | float] = {k: int(d[k]) for k in ("seq", "mission_type") if k in d}
        over.update((k, float(d[k])) for k in ("fx", "fy") if k in d)
        if over:
            rewrite[seq] = over
    return items, rewrite


def float_variant(plan: Plan, rewrite: dict[int, dict[str, Any]] | None = None, *,
                  truncate: bool = False) -> Plan | None:
    """The plan as a vehicle stores it when the items came as MISSION_ITEM (float x/y):
    each item's x/y as it went out (its int x/y converted, or the "fx"/"fy" override in
    `rewrite[seq]`), rounded to float32 by the wire and converted back the vehicle's way
    (`MissionItem.int_xy_from_float`, the spec vehicle's own). None if some item's x/y
    cannot be an int32 there (NaN, +-inf, 1e10, 215 deg): a vehicle must refuse that item
    (MAV_MISSION_INVALID_PARAM5_X / _PARAM6_Y), and one that accepts it stores a plan
    nobody can know, which then matches no candidate and is a finding.

    `truncate`: the conversion a C vehicle does, a float32 product cast to int32, which
    truncates toward zero (ArduPilot, GCS_Common.cpp `convert_MISSION_ITEM_to_MISSION_ITEM_INT`:
    `x = packet.x * 1.0e7f`): seen on ArduCopter SITL, a rally point sent as x = -1940
    degE7 by MISSION_ITEM came back as -1939."""
    from mavconform.reference_impl.mission.items import to_float32, xy_scale
    out = []
    for it in plan:
        fx, fy = it.float_xy()
        over = rewrite.get(it.seq) if rewrite else None
        if over:
            fx = to_float32(over["fx"]) if "fx" in over else fx
            fy = to_float32(over["fy"]) if "fy" in over else fy
        x, y = MissionItem.int_xy_from_float(it.frame, fx, fy)
        if x is None or y is None:
            return None
        if truncate:
            scale = to_float32(xy_scale(it.frame))
            x, y = (math.trunc(to_float32(fx * scale)), math.trunc(to_float32(fy * scale)))
        out.append(MissionItem(it.seq, it.frame, it.command, it.param1, it.param2, it.param3,
                               it.param4, x, y, it.z, it.current, it.autocontinue, it.mission_type))
    return tuple(out)


def describe_op(op: dict[str, Any]) -> str:
    kind = op.get("op")
    label = _type_label(op.get("type"))
    if kind == "upload":
        return f"an upload of {len(op['items'])} {label} items" + (" (float)" if op.get("float") else "")
    if kind == "download":
        return f"a download of the {label} plan"
    if kind == "clear":
        return f"a clear of the {label} plan" + ("s" if op.get("type") == MissionType.ALL else "")
    if kind == "set_current":
        how = "MAV_CMD_DO_SET_MISSION_CURRENT" if op.get("command") else "MISSION_SET_CURRENT"
        return f"a set-current to {op.get('seq')} ({how})"
    if kind == "control":
        action = op.get("action")
        if action == "request":
            return (f"a request for control (takeover {'allowed' if op.get('allow') else 'disallowed'}, "
                    f"timeout {op.get('timeout', cm.DEFAULT_REQUEST_TIMEOUT):g} s"
                    + (", waiting for the owner)" if op.get("wait_for_owner") else ")"))
        return {"release": "a release of control", "allow": "allowing takeover",
                "disallow": "disallowing takeover"}.get(action, f"control {action}")
    if kind == "gcs_loss":
        return f"{op.get('seconds')} s without HEARTBEAT"
    return str(kind)


def _type_label(value: Any) -> str:
    if value == MissionType.ALL:
        return "all"
    t = PLAN_TYPE_BY_VALUE.get(value)
    return t.label if t is not None else str(value)


def _always() -> bool:
    return True


def _seconds(value: float) -> str:
    return "the whole example" if value == float("inf") else f"{value:.1f} s"
