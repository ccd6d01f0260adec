"""The node-side endpoint: who counts as a peer, and the bounds on what it remembers."""

from mavconform.reference_impl.endpoint import MAX_ADDRESSES, MavlinkEndpoint
from mavconform.reference_impl.wire import FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d


def heartbeat(sysid: int) -> bytes:
    return FrameEncoder(sysid, 190).encode(d.MAVLink_heartbeat_message(6, 8, 0, 0, 4, 3))


def test_garbage_senders_never_become_broadcast_targets():
    """Review finding: every source address, even of pure garbage, joined the broadcast set
    for good (a reflection vector, and unbounded growth)."""
    ep = MavlinkEndpoint(1, 1)
    for port in range(1000):
        assert ep.receive(b"\x00garbage" * 3, ("127.0.0.1", 20000 + port)) == []
    assert ep.addresses == {} and len(ep.decode_errors) == 100
    ep.receive(heartbeat(255), ("127.0.0.1", 14550))
    assert list(ep.addresses) == [("127.0.0.1", 14550)]


def test_learned_addresses_are_bounded_and_configured_ones_kept():
    ep = MavlinkEndpoint(1, 1)
    ep.add_address(("127.0.0.1", 9))
    for port in range(3 * MAX_ADDRESSES):
        ep.receive(heartbeat(200), ("127.0.0.1", 30000 + port))
    assert len(ep.addresses) == MAX_ADDRESSES and ("127.0.0.1", 9) in ep.addresses
    assert ("127.0.0.1", 30000 + 3 * MAX_ADDRESSES - 1) in ep.addresses


def test_a_single_peer_link_reads_and_answers_only_its_first_peer():
    """VARIANTS.md L1/L2: a real SITL GCS link is bound to one address; others are never read."""
    ep = MavlinkEndpoint(1, 1, single_peer=True)
    first, other = ("127.0.0.1", 14550), ("127.0.0.1", 14551)
    assert len(ep.receive(heartbeat(245), first)) == 1
    assert ep.receive(heartbeat(246), other) == [] and ep.foreign_datagrams == 1
    ep.send(d.MAVLink_heartbeat_message(2, 3, 0, 0, 4, 3))
    assert [to for _, to in ep.take_outgoing()] == [first]
    # a second identity on the first peer's address is heard (MAVLink routing by system id)
    assert len(ep.receive(heartbeat(246), first)) == 1
