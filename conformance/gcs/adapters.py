"""Adapters: how the suite tells a GCS under test to upload, download, clear or set current.

The interface is `GcsAdapter.start(job, stage) -> Running`; `Running.result()` is None until
the GCS has said how the operation ended, `Running.stop()` ends it at the bound. Two kinds:

- `CommandAdapter`: a command run once per operation, `CMD {port} {op} {file}` (split like a
  shell line, no shell; each placeholder replaced in every argument). `{port}` is the scripted
  vehicle's UDP port on 127.0.0.1 (the GCS sends first), `{op}` the operation, `{file}` the
  job file (job.py), `{type}` and `{seq}` are there too. A GCS that listens instead names
  `{gcs_port}`: a free port on 127.0.0.1 it binds, to which the vehicle sends first (as SITL
  does to a ground station; a client socket that never binds would be on every address). Its result file says how it ended;
  without one, the exit code does (0 success, anything else failure) and the last line it
  printed is what it said. A command that outlives the job's bound is killed: the GCS never
  ended the operation. Needs real UDP.
- `NodeAdapter`: a GCS in this process, as a sans-IO node (the reference GCS, its mutants),
  that runs on either stage, so the tool's own tests drive it in virtual time.
"""

from __future__ import annotations

import os
import shlex
import signal
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Protocol

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.adaptations import NONE
from mavconform.reference_impl.mission.results import OperationResult
from mavconform.reference_impl.net.node import Address

from .job import Job, JobResult, read_result, write_job
from .stage import Stage

REQUIRED = ("{op}", "{file}")
PORTS = ("{port}", "{gcs_port}")
STOP_GRACE_S = 3.0    # after SIGTERM, before SIGKILL
USAGE_EXIT = 2        # the adapter could not run the job (a bad job, or its GCS is missing)
LOG_LINES = 8


class Running(Protocol):
    def result(self) -> JobResult | None: ...

    def stop(self) -> JobResult: ...


class GcsAdapter(Protocol):
    name: str
    needs_real_time: bool    # a process: it must be told a real port
    listens: bool            # it binds {gcs_port}, and the vehicle speaks first

    def start(self, job: Job, stage: Stage) -> Running: ...

    def describe(self) -> str: ...


# --- a command per operation ---------------------------------------------------------------------
def parse_command(template: str) -> list[str]:
    """The command's arguments; a UsageError if it cannot be split or lacks a placeholder."""
    try:
        args = shlex.split(template)
    except ValueError as exc:
        raise UsageError(f"--gcs-cmd {template!r}: {exc}") from None
    if not args:
        raise UsageError("--gcs-cmd: empty command")
    missing = [p for p in REQUIRED if not any(p in a for a in args)]
    if not any(p in a for p in PORTS for a in args):
        missing.insert(0, "{port} (or {gcs_port})")
    if missing:
        raise UsageError(f"--gcs-cmd {template!r}: lacks {', '.join(missing)} (the command is run as "
                         "'CMD {port} {op} {file}' per operation; see `mavconform run --help`)")
    return args


class CommandAdapter:
    needs_real_time = True

    def __init__(self, template: str, *, workdir: Path | None = None, name: str | None = None) -> None:
        self.args = parse_command(template)
        self.template = template
        self.name = name or Path(self.args[0]).name
        self._workdir = workdir
        self._count = 0

    def describe(self) -> str:
        return f"command: {self.template}"

    @property
    def listens(self) -> bool:
        """The GCS binds {gcs_port} and waits for the vehicle to speak first."""
        return any("{gcs_port}" in a for a in self.args)

    def start(self, job: Job, stage: Stage) -> "_Process":
        if not stage.real_time:
            raise UsageError("a GCS command needs real UDP (it is told the vehicle's port)")
        self._count += 1
        folder = Path(self._workdir or tempfile.mkdtemp(prefix="mavconform-gcs-")).resolve()
        folder.mkdir(parents=True, exist_ok=True)
        job_file = folder / f"job-{self._count:03d}.json"
        result_file = folder / f"result-{self._count:03d}.json"
        result_file.unlink(missing_ok=True)
        write_job(job, job_file, result_file)
        gcs_port = stage.vehicle.call[1] if stage.vehicle.call is not None else ""
        values = {"{port}": str(stage.vehicle_address[1]), "{gcs_port}": str(gcs_port),
                  "{op}": job.op, "{file}": str(job_file),
                  "{type}": job.mission_type.label, "{seq}": "" if job.seq is None else str(job.seq)}
        argv = []
        for arg in self.args:
            for key, value in values.items():
                arg = arg.replace(key, value)
            argv.append(arg)
        log = folder / f"log-{self._count:03d}.txt"
        try:
            with open(log, "wb") as out:
                proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT,
                                        start_new_session=True)
        except OSError as exc:
            raise UsageError(f"--gcs-cmd: cannot run {argv[0]!r}: {exc.strerror or exc}") from None
        return _Process(proc, job, result_file, log, stage)


class _Process:
    def __init__(self, proc: subprocess.Popen, job: Job, result_file: Path, log: Path, stage: Stage) -> None:
        self.proc, self.job, self.result_file, self.log, self.stage = proc, job, result_file, log, stage
        self._result: JobResult | None = None

    def result(self) -> JobResult | None:
        if self._result is None and self.proc.poll() is not None:
            self._result = self._read(self.proc.returncode)
        return self._result

    def stop(self) -> JobResult:
        if self.result() is not None:
            return self._result
        _kill(self.proc)
        self._result = JobResult(False, f"killed after the bound of {self.job.timeout_s:g} s", ended=False,
                                 at=self.stage.clock.now(), log=self._tail())
        return self._result

    def _read(self, code: int) -> JobResult:
        at, tail = self.stage.clock.now(), self._tail()
        if self.result_file.exists():
            try:
                got = read_result(self.result_file, self.job.mission_type)
            except ValueError as exc:
                return JobResult(False, f"unreadable result ({exc}); exit code {code}", at=at, log=tail)
            got.at, got.log = at, tail
            return got
        said = tail[-1] if tail else ""
        return JobResult(code == 0, f"exit code {code}" + (f": {said}" if said else ""), at=at, log=tail,
                         refused_job=code == USAGE_EXIT)

    def _tail(self) -> list[str]:
        try:
            lines = self.log.read_text(encoding="utf-8", errors="replace").splitlines()
        except OSError:
            return []
        return [line[:200] for line in lines if line.strip()][-LOG_LINES:]


def _kill(proc: subprocess.Popen) -> None:
    """SIGTERM the command's process group, then SIGKILL after a grace: bounded either way."""
    for sig, wait in ((signal.SIGTERM, STOP_GRACE_S), (signal.SIGKILL, STOP_GRACE_S)):
        try:
            os.killpg(proc.pid, sig)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            proc.wait(timeout=wait)
            return
        except subprocess.TimeoutExpired:
            continue


# --- a GCS in this process ---------------------------------------------------------------------
GcsBuilder = Callable[[GcsConfig, Address], GcsNode]


def reference_gcs(config: GcsConfig, vehicle: Address) -> GcsNode:
    return GcsNode(config, remote=vehicle)


class NodeAdapter:
    """The reference GCS (or a mutant: another `build`), spec-exact: the scripted vehicle
    says MAV_AUTOPILOT_GENERIC, and the adaptations are fixed to none anyway."""
    needs_real_time = False
    listens = False

    def __init__(self, name: str = "reference GCS", build: GcsBuilder = reference_gcs,
                 config: GcsConfig | None = None) -> None:
        self.name = name
        self.build = build
        self.config = config or GcsConfig(adaptations=NONE)

    def describe(self) -> str:
        return self.name

    def start(self, job: Job, stage: Stage) -> "_OperatingGcs":
        node = _OperatingGcs(self.build(replace(self.config), stage.vehicle_address), job, stage)
        stage.add_gcs(node)
        return node


class _OperatingGcs:
    """A GCS node that starts the job's operation as soon as it has found the vehicle."""

    def __init__(self, gcs: GcsNode, job: Job, stage: Stage) -> None:
        self.gcs, self.job, self.stage = gcs, job, stage
        self.started = False
        self._result: JobResult | None = None

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        self.gcs.datagram_received(data, source, now)
        self._begin(now)

    def poll(self, now: float) -> None:
        self.gcs.poll(now)
        self._begin(now)

    def next_deadline(self) -> float | None:
        return self.gcs.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.gcs.take_outgoing()

    def _begin(self, now: float) -> None:
        if self.started or not self.gcs.connected:
            return
        self.started = True
        job, gcs = self.job, self.gcs
        if job.op == "upload":
            gcs.upload(job.mission_type, job.items, now)
        elif job.op == "download":
            gcs.download(job.mission_type, now)
        elif job.op == "clear":
            gcs.clear(job.mission_type, now)
        else:
            gcs.set_current(job.seq or 0, now)

    def result(self) -> JobResult | None:
        if self._result is None and self.gcs.results:
            self._result = _from_operation(self.gcs.results[0], self.stage.clock.now())
        return self._result

    def stop(self) -> JobResult:
        if self.result() is None:
            self._result = JobResult(False, "never ended", ended=False, at=self.stage.clock.now())
        return self._result


def _from_operation(result: OperationResult, at: float) -> JobResult:
    items: Any = result.items if result.items is not None else None
    return JobResult(result.ok, result.summary(), items=items, at=at)
