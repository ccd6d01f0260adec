"""`SharedLink`: several MAVLink nodes (GCS identities) on one socket.

A real vehicle's GCS link is often bound to one peer address: ArduPilot SITL's `udpclient`
socket is connected to the one address it was given, and PX4 locks a link to its first
sender (VARIANTS.md L1, L2). A second GCS on a socket of its own is then never heard, and
the replies meant for it arrive on the first GCS's socket. MAVLink routing has the answer
already: several systems behind one link, each message routed by its target_system. So
every node on the link sees every datagram, and each keeps what is addressed to it (the
conformance `Tester` judges only frames that are broadcast or carry its own system id; the
fuzzer's GCSs likewise). One `DatagramNode` to the driver: one socket, one fault model.
"""

from __future__ import annotations

from .node import Address, DatagramNode


class SharedLink:
    """A `DatagramNode` carrying the nodes that share one socket."""

    def __init__(self, first: DatagramNode) -> None:
        self.nodes: list[DatagramNode] = [first]

    def join(self, node: DatagramNode) -> None:
        self.nodes.append(node)

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        for node in self.nodes:
            node.datagram_received(data, source, now)

    def poll(self, now: float) -> None:
        for node in self.nodes:
            node.poll(now)

    def next_deadline(self) -> float | None:
        deadlines = [d for node in self.nodes if (d := node.next_deadline()) is not None]
        return min(deadlines, default=None)

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        out: list[tuple[bytes, Address]] = []
        for node in self.nodes:
            out.extend(node.take_outgoing())
        return out
