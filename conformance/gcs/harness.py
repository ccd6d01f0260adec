"""Play one operation against the GCS under test, and keep what both sides did.

`GcsHarness.run(job, ...)` builds a fresh scripted vehicle with the check's script, starts
the adapter's GCS on its own stage, serves both until the GCS says how the operation ended
(bounded by the job's timeout: past it the GCS is stopped and "never ended"), then, if the
check asks, watches `after` seconds longer for anything the GCS still sends. The `Operation`
it returns is the evidence a check judges: every mission message the GCS sent (with its
MAVLink version and time), every one the vehicle sent, the script's notes, and the result.
Each operation's events go into the clause's exchange, for the report.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable

from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.net.clock import Clock, MonotonicClock, ScaledClock

from ..harness.exchange import Exchange, message_fields
from ..harness.link_timing import link_facts
from ..outcome import ClauseFailed, TargetUnresponsive
from .adapters import GcsAdapter
from .job import Job, JobResult
from .scripted_vehicle import Event, Rule, ScriptedVehicle
from .stage import HOST, SimStage, Stage, UdpStage, free_port

WATCH_PERIOD = 0.05   # s: how often the driver wakes to see whether a GCS process has ended
SETTLE = 0.1          # s served after the GCS's result, for the messages it sent with it


@dataclass
class Operation:
    job: Job
    vehicle: ScriptedVehicle
    result: JobResult
    started: float
    gcs: tuple[int, int] | None = None      # the GCS's system and component, as heard
    indices: dict[int, int] = field(default_factory=dict)   # id(event) -> index in the exchange

    @property
    def events(self) -> list[Event]:
        return self.vehicle.log

    def sent(self, *names: str) -> list[Event]:
        """What the GCS sent, in order: every message, or those named."""
        return [e for e in self.events if e.dir == "rx" and (not names or e.msg._type in names)]

    def told(self, *names: str) -> list[Event]:
        """What the vehicle sent the GCS, in order."""
        return [e for e in self.events if e.dir == "tx" and (not names or e.msg._type in names)]

    def after(self, event: Event, *names: str) -> list[Event]:
        """What the GCS sent after `event`."""
        return [e for e in self.sent(*names) if e.t > event.t or (e.t == event.t and self._later(e, event))]

    def _later(self, a: Event, b: Event) -> bool:
        return self.events.index(a) > self.events.index(b)

    def index(self, event: Event | None) -> int | None:
        return None if event is None else self.indices.get(id(event))


class GcsHarness:
    """`clock_speed`: over real UDP, the clock the stages and an in-process GCS share, this
    many times real time (every timer, timeout and bound in its seconds, as the vehicle
    suite runs builtin vehicles); a GCS process lives in real time."""

    def __init__(self, adapter: GcsAdapter, *, real_time: bool = True, timeout_s: float = 30.0,
                 seed: int = 0, capture: Any = None, clock_speed: float = 1.0) -> None:
        self.adapter = adapter
        self.real_time = real_time or adapter.needs_real_time
        if clock_speed != 1.0 and adapter.needs_real_time:
            raise ValueError(f"a GCS process lives in real time, not on a {clock_speed:g}x clock")
        self.clock_speed = clock_speed if self.real_time else 1.0
        self.clock: Clock = ScaledClock(clock_speed) if self.clock_speed != 1.0 else MonotonicClock()
        self.timeout_s = timeout_s
        self.seed = seed
        self.capture = capture
        self.exchange: Exchange | None = None
        self.operations: list[Operation] = []
        self._sim_time = 0.0     # virtual stages continue one clock, so exchange times grow
        self._observed: dict[str, Operation] = {}
        # conformance/host_lag.py: the most a stage's driver ran behind the clock since
        # take_lag(), and that of each shared operation's stage
        self.lag = 0.0
        self._observed_lag: dict[str, float] = {}
        self._last_lag = 0.0

    # --- what a check calls -----------------------------------------------------------------
    def run(self, job: Job, *, plans: dict[MissionType, list[MissionItem]] | None = None,
            rules: Iterable[Rule] = (), request_float: bool = False, after: float = 0.0) -> Operation:
        job = Job(job.op, job.mission_type, job.items, job.seq, self.timeout_s)
        listening = self.adapter.listens
        vehicle = ScriptedVehicle({t: list(p) for t, p in (plans or {}).items()}, list(rules),
                                  request_float=request_float,
                                  wake_every=WATCH_PERIOD if self.real_time else None,
                                  call=(HOST, free_port()) if listening else None)
        stage = self._stage(vehicle)
        try:
            started = stage.clock.now()
            running = self.adapter.start(job, stage)
            stage.run_until(lambda: running.result() is not None, timeout=job.timeout_s)
            result = running.stop() if running.result() is None else running.result()
            # what the GCS sent with its result (a download's final ACK) is still on its way
            stage.run_until(lambda: False, timeout=max(after, SETTLE))
            if not stage.real_time:
                self._sim_time = stage.clock.now() + 1.0
        finally:
            self._last_lag = stage.lag
            self.lag = max(self.lag, stage.lag)
            stage.close()
        op = Operation(job, vehicle, result, started, vehicle.gcs)
        self.operations.append(op)
        self._record(op)
        if not op.sent():
            if result.refused_job:   # the adapter's failure, not the GCS's answer
                raise TargetUnresponsive(f"the GCS command could not run the job to {job.describe()}: "
                                         f"{result.said}")
            if result.ended and not result.ok:   # it said why: a refusal is its answer
                raise ClauseFailed(f"the GCS would not {job.describe()}: it sent nothing ({result.line()})")
            raise TargetUnresponsive(f"the GCS sent the vehicle nothing to {job.describe()} "
                                     f"({result.line()})")
        return op

    def observe(self, key: str, job: Job, **script: Any) -> Operation:
        """`run`, once per run for a given key: clauses that judge the same operation (a
        clean upload, a silent vehicle) share it; each clause's exchange shows it."""
        op = self._observed.get(key)
        if op is None:
            op = self._observed[key] = self.run(job, **script)
            self._observed_lag[key] = self._last_lag
        else:
            self._record(op)
            self.lag = max(self.lag, self._observed_lag.get(key, 0.0))   # judged on what it saw
        return op

    def take_lag(self) -> float:
        """The most a stage's driver ran behind the clock since the last call (host_lag.py)."""
        lag, self.lag = self.lag, 0.0
        return lag

    def forget_lagged(self, tolerance: float) -> None:
        """Drop the shared operations observed while the driver ran more than `tolerance`
        behind, so a clause run again observes afresh."""
        for key in [k for k, lag in self._observed_lag.items() if lag > tolerance]:
            del self._observed[key], self._observed_lag[key]

    def link(self) -> dict[str, Any] | None:
        """The run document's `run.link` when the clock was faster than real (else None, as
        before clocks could be: a GCS run over UDP in real time records no link)."""
        if self.clock_speed == 1.0:
            return None
        return {**link_facts("in-process", None), "clock_speed": self.clock_speed}

    def now(self) -> float:
        return self.clock.now() if self.real_time else self._sim_time

    def decide(self, op: Operation, event: Event | None) -> None:
        """The event the verdict is about (the report marks it)."""
        if self.exchange is not None:
            self.exchange.decide(op.index(event))

    # --- internals ---------------------------------------------------------------------------
    def _stage(self, vehicle: ScriptedVehicle) -> Stage:
        if self.real_time:
            return UdpStage(vehicle, self.capture, self.clock)
        return SimStage(vehicle, seed=self.seed, start=self._sim_time, capture=self.capture)

    def _record(self, op: Operation) -> None:
        ex = self.exchange
        if ex is None:
            return
        ex.note(op.started, "tester", f"GCS told to {op.job.describe()}")
        for event in op.events:
            if event.dir == "note":
                index = ex.note(event.t, "tester", f"vehicle script: {event.text}")
            else:
                fields = message_fields(event.msg)
                if event.dir == "rx" and event.version != 2:
                    fields = {**fields, "mavlink_version": event.version}
                index = ex.add(event.t, event.dir, "vehicle" if event.dir == "tx" else "gcs",
                               event.msg._type, fields)
            if index is not None:
                op.indices[id(event)] = index
        ex.note(op.result.at or op.started, "tester", op.result.line())
