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
after every step. The operator-control steps (control_steps.py) and the liveness probe
(liveness.py) are mixins of `Runner`; runs.py holds what a step ran, wire_plans.py how its
wire items become a plan.
"""

from __future__ import annotations

from typing import Any, Callable

from mavconform.conformance.harness.stored_form import describe_differences
from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.items import PLAN_TYPE_BY_VALUE, PLAN_TYPES, MissionType
from mavconform.reference_impl.mission.transitions import SlotState
from mavconform.reference_impl.net.sim import CaptureHook
from mavconform.reference_impl.wire.dialect import mavlink as _d
from mavconform.reference_impl.handover import control_messages as cm

from ..case import Violation
from .control import CONTROL_INVARIANTS, WIRE_STATUS_WAIT
from .faults import build_fault_model
from .gcs import FuzzGcs
from .connection import TargetConnection
from .control_steps import ControlSteps
from .liveness import Liveness
from .runs import ControlRun, Group, Run, describe_op
from .versions import Plan, Versions, Write, describe_plan
from .wire_plans import float_variant, wire_to_items
from .world import World

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


def invariants(handover: bool = False) -> dict[str, str]:
    """The invariants a campaign checks: the mission ones, and with `handover` the control ones."""
    return {**INVARIANTS, **CONTROL_INVARIANTS} if handover else dict(INVARIANTS)


MAX_ROUNDS = 10_000   # bound on the wait loop of one step (each round advances time or ends)
UDP_DRAIN = 0.3       # s at most after stray messages over a real network, for their replies to land
UDP_QUIET = 0.05      # s without an answer from the target that end that wait early


class Runner(ControlSteps, Liveness):
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
        handler: Callable[[dict[str, Any]], Group | Violation | None] = {
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
    def _operation(self, step: dict[str, Any]) -> Group:
        if step.get("gcs") == "b":
            return Group(runs=[self._start(self.world.b, "B", step)])
        return Group(runs=[self._start(self.world.a, "A", step)])

    def _cancel(self, step: dict[str, Any]) -> Group:
        run = self._start(self.world.a, "A", step["of"])
        self.world.run_until(lambda: run.finished, float(step["after"]))
        if not run.finished:
            self.world.a.cancel(self.world.now())
        return Group(runs=[run])

    def _second_gcs(self, step: dict[str, Any]) -> Group:
        first = self._start(self.world.a, "A", step["first"])
        self.world.run_until(lambda: first.finished, float(step["after"]))
        return Group(runs=[first, self._start(self.world.b, "B", step["second"])])

    def _stray(self, step: dict[str, Any]) -> Group:
        group = Group(strays=True)
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

    def _wait(self, step: dict[str, Any]) -> Group:
        self.world.run_for(float(step["seconds"]))
        return Group()

    # --- running operations ---------------------------------------------------------------
    def _start(self, gcs: FuzzGcs, name: str, op: dict[str, Any]) -> Run:
        w = self.world
        now = w.now()
        gcs.listen()
        run = Run(gcs, name, op, len(gcs.results), now)
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

    def _bound(self, run: Run | ControlRun) -> float:
        """How long an operation may take: every message of it retried to the limit."""
        if isinstance(run, ControlRun):
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

    def _wait_for_results(self, runs: list[Run | ControlRun]) -> Violation | None:
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
                if isinstance(late, ControlRun):
                    return self._violation("handover-unbounded", (
                        f"{describe_op(late.op)} by GCS {late.name} had no result {limit - late.started:g} s "
                        f"after it started (the control client's bound: its retries, and the request's "
                        f"timeout when it waits for the owner)"))
                return self._violation("one-result", (
                    f"{describe_op(late.op)} by GCS {late.name} had no result {limit - late.started:g} s "
                    f"after it started (the bound from the protocol's timeouts and retry limit)"))
            w.run_until(lambda: all(r.finished for r in runs), limit - now)
        return self._violation("one-result", "the operations of this step did not settle (wait loop bound)")

    def _conclude(self, group: Group) -> Violation | None:
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

    def _op_writes(self, run: Run) -> list[Write]:
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

    def _settle(self, group: Group) -> Violation | None:
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

    def _violation(self, invariant: str, detail: str) -> Violation:
        return Violation(invariant, detail, self.index if self.index >= 0 else None)


# --- helpers ---------------------------------------------------------------------------------

def _always() -> bool:
    return True


def _seconds(value: float) -> str:
    return "the whole example" if value == float("inf") else f"{value:.1f} s"
