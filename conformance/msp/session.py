"""One MSP conformance session: the link to the flight controller and the suite's client on it.

An in-process target (`builtin:msp`, a mutant) is served over real TCP loopback
(reference_impl/msp/links.py), so the bytes cross the kernel as they would to a SITL. In virtual time (the tool's own tests) the two nodes sit on a SimNetwork.
An external target is reached over the link its URI names; a TCP client reconnects on its
own bounded back-off, and a link that never comes up is a target that does not answer.
"""

from __future__ import annotations

from typing import Any

from mavconform.reference_impl.msp.nodes import MspClientNode, MspServerNode
from mavconform.reference_impl.net.clock import SimClock
from mavconform.reference_impl.msp.links import connect
from mavconform.reference_impl.net.links import stream_of
from mavconform.reference_impl.net.sim import CaptureHook, SimNetwork
from mavconform.reference_impl.net.udp import UdpDriver

from ..harness.link_timing import link_facts, stream_events
from .target import MspTarget
from .tester import MspTester

def build_server(target: MspTarget) -> MspServerNode:
    """The in-process flight controller `target` names."""
    if target.kind == "mutant":
        from .mutants import MSP_MUTANTS
        return MSP_MUTANTS[target.name].build()
    return MspServerNode()


class MspSession:
    clock_speed = 1.0   # a flight controller lives in real time (conformance/host_lag.py reads it)

    def __init__(self, target: MspTarget, *, virtual: bool = False, scale: float = 1.0, seed: int = 0,
                 capture: CaptureHook | None = None) -> None:
        self.target = target
        self.capture = capture
        self.server = build_server(target) if target.in_process else None
        self.node = MspClientNode()
        if virtual:
            if self.server is None:
                raise ValueError("virtual time needs an in-process flight controller")
            self.driver: Any = SimNetwork(seed=seed, clock=SimClock())
            self.driver.add_node("tester", self.node)
            self.driver.add_node("flight controller", self.server)
            self.driver.connect("tester", "flight controller")
            self.node.peer = "flight controller"
        else:
            self.driver = UdpDriver(seed=seed)
            self._open_real()
        if capture is not None:
            self.driver.add_capture(capture)
        self.started = self.driver.clock.now()
        self.tester = MspTester(self.driver, self.node, scale=scale,
                                allowance=self.link_facts["reply_allowance_s"])
        self.scale = scale

    def _open_real(self) -> None:
        connect(self.driver, self.node, self.target.link, server=self.server)

    @property
    def stream(self) -> Any:
        """Our end's stream link (TCP, serial), or None (UDP, or virtual time)."""
        return stream_of(self.driver, self.node)

    @property
    def link_facts(self) -> dict[str, Any]:
        """The run document's `run.link` (harness/link_timing.py), as a vehicle run's."""
        kind = "in-process" if self.target.in_process else self.target.link.mode
        return link_facts(kind, self.stream)

    def link_events(self) -> dict[str, Any]:
        """What happened to the link during the run (volatile), as a vehicle run's, and what
        our MSP reader skipped in the flight controller's stream (`msp`: counted, never raised)."""
        stats = self.node.parser.stats
        msp = {"frames": stats.frames, "garbage_bytes": stats.garbage_bytes, "bad_checksum": stats.bad_checksum,
               "bad_header": stats.bad_header, "oversize": stats.oversize, "truncated": stats.truncated}
        return {**(stream_events(self.stream, self.started) or {}), "msp": msp}

    def take_lag(self) -> float:
        """The most the driver ran behind its clock since the last call (host_lag.py)."""
        return self.driver.take_lag()

    def forget_lagged(self, tolerance: float) -> None:
        """Nothing to forget: no MSP clause shares an observation with another."""

    def close(self) -> None:
        close = getattr(self.driver, "close", None)
        if close is not None:
            close()

    def __enter__(self) -> "MspSession":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
