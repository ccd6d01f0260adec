"""Blocking calls over a sans-IO GCS node: start an operation, run the driver to its result.

Works with either driver (`SimNetwork` in virtual time, `UdpDriver` in real time): both
offer `clock` and `run_until(condition, timeout=...)`. Every wait is bounded: the engine
ends every operation by itself, and the bound here only guards against an engine bug.
"""

from __future__ import annotations

from typing import Any, Callable, Protocol, Sequence

from .errors import LocalProtocolError
from .gcs import GcsNode
from .handover.control_client import ClientConfig
from .handover.control_results import ControlOperation, ControlOutcome, ControlResult
from .mission.items import MissionItem, MissionType
from .mission.results import Operation, OperationResult


class Driver(Protocol):
    clock: Any

    def run_until(self, condition: Callable[[], bool], *, timeout: float) -> bool: ...


class TargetUnresponsive(Exception):
    """The target never sent a HEARTBEAT: a finding about the target, not a usage error."""


class GcsSession:
    def __init__(self, driver: Driver, gcs: GcsNode) -> None:
        self.driver = driver
        self.gcs = gcs

    @property
    def now(self) -> float:
        return self.driver.clock.now()

    def wait_for_target(self, timeout: float = 5.0) -> tuple[int, int]:
        if not self.driver.run_until(lambda: self.gcs.connected, timeout=timeout):
            raise TargetUnresponsive(f"no HEARTBEAT from the target within {timeout:g} s")
        return self.gcs.target

    def upload(self, mission_type: MissionType, items: Sequence[MissionItem]) -> OperationResult:
        n = len(items)
        return self._run(lambda now: self.gcs.upload(mission_type, items, now), messages=n + 2)

    def download(self, mission_type: MissionType) -> OperationResult:
        # The count is unknown until the vehicle says; the bound grows as items arrive.
        return self._run(lambda now: self.gcs.download(mission_type, now), messages=None)

    def clear(self, mission_type: MissionType) -> OperationResult:
        return self._run(lambda now: self.gcs.clear(mission_type, now), messages=1)

    def set_current(self, seq: int, *, via_command: bool = False) -> OperationResult:
        return self._run(lambda now: self.gcs.set_current(seq, now, via_command=via_command), messages=1)

    # --- operator control (GcsConfig.control) ---------------------------------------------
    def wait_for_control_status(self, timeout: float = 3.0) -> bool:
        """Whether the target's system manager spoke (a CONTROL_STATUS) within `timeout`;
        until it does, this GCS does not know who is in control."""
        client = self.gcs.require_control()
        return self.driver.run_until(lambda: client.manager is not None, timeout=timeout)

    def request_control(self, *, allow_takeover: bool = False, timeout: float | None = None,
                        wait: bool = True) -> ControlResult:
        """Ask for control; refused, wait up to `timeout` (param 3) for the owner to let us in."""
        cfg = self._control_config()
        timeout = cfg.request_timeout if timeout is None else timeout
        bound = timeout + cfg.ack_timeout if wait else 0.0
        return self._run_control(ControlOperation.REQUEST, bound, lambda now: self.gcs.request_control(
            now, allow_takeover=allow_takeover, timeout=timeout, wait=wait))

    def release_control(self) -> ControlResult:
        return self._run_control(ControlOperation.RELEASE, 0.0, self.gcs.release_control)

    def allow_takeover(self, allowed: bool = True) -> ControlResult:
        """Set or clear the takeover flag. Not in control (as far as this GCS has heard),
        nothing is sent: the same command would be a request for control."""
        operation = ControlOperation.ALLOW_TAKEOVER if allowed else ControlOperation.DISALLOW_TAKEOVER
        client = self.gcs.require_control()
        if not client.in_control:
            now = self.now
            return ControlResult(operation, ControlOutcome.NOT_IN_CONTROL, None, 0,
                                 f"GCS {client.system} is not in control (gcs_main {client.owner}); nothing sent",
                                 now, now)
        return self._run_control(operation, 0.0, lambda now: self.gcs.set_takeover(allowed, now))

    def _control_config(self) -> ClientConfig:
        self.gcs.require_control()
        return self.gcs.config.control

    def _run_control(self, operation: ControlOperation, waiting: float,
                     start: Callable[[float], None]) -> ControlResult:
        """Start a user operation and run until its result. The bound: a command's resends
        (`per_command`) before the first answer, the wait for the owner, one more command
        round after it, and an answer to a forwarded request queued ahead of ours."""
        cfg = self._control_config()
        gcs = self.gcs
        done = len(gcs.control_results)
        start(self.now)
        per_command = cfg.ack_timeout * (cfg.max_retries + 2)
        bound = 3 * per_command + waiting

        def ours() -> ControlResult | None:
            return next((r for r in gcs.control_results[done:] if r.operation is operation), None)
        if not self.driver.run_until(lambda: ours() is not None, timeout=bound):
            raise LocalProtocolError("operator-control client did not finish within its own bound (engine bug)")
        return ours()

    def _run(self, start: Callable[[float], None], *, messages: int | None) -> OperationResult:
        gcs = self.gcs
        if not gcs.connected:
            raise LocalProtocolError("no target vehicle yet: call wait_for_target() first")
        done = len(gcs.results)
        start(self.now)
        timings = gcs.config.timings
        per_message = timings.default_timeout * (timings.max_retries + 2)
        while True:
            # A download's bound follows its count; everything else is fixed at the start.
            n = messages if messages is not None else _download_size(gcs) + 2
            finished = self.driver.run_until(lambda: len(gcs.results) > done,
                                             timeout=per_message * max(n, 2))
            if finished:
                return gcs.results[done]
            if messages is not None or _download_size(gcs) + 2 <= n:
                raise LocalProtocolError("mission client did not finish within its own bound (engine bug)")


def _download_size(gcs: GcsNode) -> int:
    op = getattr(gcs.client, "_op", None)
    return op.count if op is not None and op.operation is Operation.DOWNLOAD else 0
