"""Net: clocks, the in-memory SimNetwork, the UDP driver, link faults, URIs and capture.

Nodes (`DatagramNode`) are sans-IO; these drivers move their datagrams, in virtual time
(`SimNetwork` + `SimClock`) or real time (`UdpDriver` + `MonotonicClock`), through a
`FaultModel` per link direction, and report every datagram to capture hooks.
"""

from .capture import McapCapture
from .clock import Clock, MonotonicClock, SimClock
from .faults import DropMessage, DropWhere, FaultModel, LinkStats, MessageRule, parse_drop_rule
from .node import Address, DatagramNode
from .sim import CaptureRecord, SimNetwork
from .udp import UdpDriver
from .uri import UdpUri, parse_udp_uri

__all__ = [
    "Address", "CaptureRecord", "Clock", "DatagramNode", "DropMessage", "DropWhere",
    "FaultModel", "LinkStats", "McapCapture", "MessageRule", "MonotonicClock", "SimClock",
    "SimNetwork", "UdpDriver", "UdpUri", "parse_drop_rule", "parse_udp_uri",
]
