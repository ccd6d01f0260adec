"""One operation's network: the scripted vehicle, and the GCS under test beside it.

Every operation gets a fresh stage (a new vehicle, a new port), so nothing a GCS left
behind (a late resend, a process that outlived its bound) reaches the next clause. Over
real UDP (`UdpStage`, what a GCS process needs: it is told the vehicle's port; for the
in-process GCSs, on a clock faster than real that both sides read) or in virtual time
(`SimStage`, for in-process GCSs in the tool's own tests: a 9 s retry sequence costs
microseconds). Both offer `clock`, `run_until` and `add_gcs`.
"""

from __future__ import annotations

import socket
from typing import Callable, Protocol

from mavconform.reference_impl.net import MonotonicClock, SimClock, SimNetwork, UdpDriver
from mavconform.reference_impl.net.clock import Clock
from mavconform.reference_impl.net.node import Address, DatagramNode
from mavconform.reference_impl.net.sim import CaptureHook

from .scripted_vehicle import ScriptedVehicle

HOST = "127.0.0.1"
SIM_VEHICLE: Address = ("127.0.0.1", 14550)
SIM_GCS: Address = ("127.0.0.1", 14551)


class Stage(Protocol):
    vehicle: ScriptedVehicle
    vehicle_address: Address
    real_time: bool
    lag: float   # how far behind its clock the stage's driver ran (conformance/host_lag.py)

    @property
    def clock(self) -> Clock: ...

    def run_until(self, condition: Callable[[], bool], *, timeout: float) -> bool: ...

    def add_gcs(self, node: DatagramNode) -> Address: ...

    def close(self) -> None: ...


class UdpStage:
    real_time = True

    def __init__(self, vehicle: ScriptedVehicle, capture: CaptureHook | None = None,
                 clock: Clock | None = None) -> None:
        self.vehicle = vehicle
        self.driver = UdpDriver(clock or MonotonicClock())
        if capture is not None:
            self.driver.add_capture(capture)
        self.vehicle_address = self.driver.add_node(vehicle, bind=(HOST, 0))

    @property
    def clock(self) -> Clock:
        return self.driver.clock

    def run_until(self, condition: Callable[[], bool], *, timeout: float) -> bool:
        return self.driver.run_until(condition, timeout=timeout)

    @property
    def lag(self) -> float:
        """How far behind its clock the driver ran (UdpDriver.lag)."""
        return self.driver.lag

    def add_gcs(self, node: DatagramNode) -> Address:
        return self.driver.add_node(node, bind=(HOST, 0))

    def close(self) -> None:
        self.driver.close()


def free_port() -> int:
    """A UDP port on 127.0.0.1 free a moment ago, for a GCS that listens (`{gcs_port}`): the
    OS picks it on a probe socket, which is closed so that the GCS can bind it."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind((HOST, 0))
        return probe.getsockname()[1]


class SimStage:
    real_time = False
    lag = 0.0   # virtual time never falls behind

    def __init__(self, vehicle: ScriptedVehicle, *, seed: int = 0, start: float = 0.0,
                 capture: CaptureHook | None = None) -> None:
        self.vehicle = vehicle
        self.network = SimNetwork(seed, SimClock(start))
        if capture is not None:
            self.network.add_capture(capture)
        self.vehicle_address = SIM_VEHICLE
        self.network.add_node(SIM_VEHICLE, vehicle)

    @property
    def clock(self) -> SimClock:
        return self.network.clock

    def run_until(self, condition: Callable[[], bool], *, timeout: float) -> bool:
        return self.network.run_until(condition, timeout=timeout)

    def add_gcs(self, node: DatagramNode) -> Address:
        self.network.add_node(SIM_GCS, node)
        self.network.connect(SIM_GCS, SIM_VEHICLE)
        return SIM_GCS

    def close(self) -> None:
        pass
