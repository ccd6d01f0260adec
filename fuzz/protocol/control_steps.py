"""The protocol fuzzer's operator-control steps (`--operator-control`; fuzz/protocol/control.py
holds the rules): a GCS's request, release or takeover flag through its control client, a GCS
falling silent, and the control state folded in and judged after each step, in process or
over the wire. A mixin of `steps.Runner`, whose world and runs it uses."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_results import ControlResult, Decision

from ..case import Violation
from .control import WIRE_STATUS_GRACE, WIRE_STATUS_WAIT, operation_bound
from .gcs import FuzzGcs
from .runs import ControlRun, Group, describe_op
from .world import SYSTEM_A, SYSTEM_B, describe_system

if TYPE_CHECKING:
    from .world import World

DECISIONS = {"allow": Decision.ALLOW, "release": Decision.RELEASE, "refuse": Decision.REFUSE}


class ControlSteps:
    """The control steps; `steps.Runner` supplies `world`, `index`, `_violation` and the runs."""

    world: "World"

    def _control(self, step: dict[str, Any]) -> Group:
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
            return Group()   # still busy with an earlier one (it had no result in its bound)
        run = ControlRun(gcs, name, step, len(gcs.control_results), now, operation_bound(timeout, wait))
        if action == "request":
            gcs.request_control(now, allow_takeover=bool(step.get("allow")), timeout=timeout, wait=wait)
        elif action == "release":
            gcs.release_control(now)
        elif action in ("allow", "disallow"):
            if not gcs.set_takeover(action == "allow", now):
                return Group()   # not in control, as far as it knows: nothing to set
        else:
            raise ValueError(f"not a control action: {action!r}")
        return Group(controls=[run])

    def _gcs_loss(self, step: dict[str, Any]) -> Group:
        """The GCS sends no HEARTBEAT for `seconds`, then beats again; `wait` s pass now."""
        w = self.world
        gcs, _ = self._control_gcs(step)
        gcs.silence(w.now(), float(step["seconds"]))
        w.run_for(float(step.get("wait", 0.0)))
        return Group()

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

    def _wire_writes(self, group: Group) -> Violation | None:
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
