"""The tester keeps up with a busy target: while it waits, each frame that comes is looked
at once, not again at every later datagram (a busy stream scanned from the floor at each
wake-up cost the loop more than it had: it read late, and the kernel dropped frames)."""

from __future__ import annotations

from mavconform.conformance.harness.match import msg
from mavconform.conformance.session import Session
from mavconform.conformance.target_uri import parse_target

from .busy_vehicle import make_busy

WINDOW = 3.0   # s of virtual time: some 600 telemetry frames (a burst after each send)


def _busy_session() -> Session:
    session = Session(parse_target("builtin:spec"), virtual=True)
    make_busy(session.vehicle)
    session.discover()
    session.t.mark()
    return session


def _counting():
    looked = [0]

    def never(frame) -> bool:
        looked[0] += 1
        return False
    return msg(None, where=never), looked


def test_poll_for_looks_at_each_frame_a_busy_target_sends_about_once():
    with _busy_session() as session:
        t = session.t
        floor = len(t.node.inbox)
        match, looked = _counting()
        assert t.poll_for(match, WINDOW) is None
        frames = len(t.node.inbox) - floor
        assert frames > 500
        assert looked[0] <= 2 * frames   # once while waiting, once more for the answer


def test_collect_looks_at_each_frame_a_busy_target_sends_about_once():
    with _busy_session() as session:
        t = session.t
        floor = len(t.node.inbox)
        match, looked = _counting()
        assert t.collect(match, WINDOW) == []
        frames = len(t.node.inbox) - floor
        assert frames > 500
        assert looked[0] <= 2 * frames


def test_a_wait_still_ends_on_the_frame_it_waits_for_amid_the_stream():
    with _busy_session() as session:
        t = session.t
        t.mark()
        frame = t.expect(msg("HEARTBEAT"), within=2.0)   # 1 Hz, among ~400 telemetry frames/s
        assert frame.msg._type == "HEARTBEAT"
        later = t.collect(msg("HEARTBEAT"), 2.5)
        assert len(later) >= 2 and all(f.msg._type == "HEARTBEAT" for _, f in later)
        assert frame not in [f for _, f in later]   # consumed once


def test_a_verdict_names_the_last_mission_message_not_a_later_statustext():
    """INAV repeats "UNABLE TO ARM" every few seconds: the detail names the protocol message."""
    from mavconform.reference_impl.mission import messages as m
    from mavconform.reference_impl.mission.items import MissionType
    from mavconform.reference_impl.wire.frame import Frame

    with Session(parse_target("builtin:spec"), virtual=True) as session:
        t = session.t
        t.mark()
        assert t.last_seen() == "no mission message arrived"
        for message in (m.count_message(3, MissionType.MISSION, t.target), m.statustext_message(4, "UNABLE TO ARM")):
            t.node.inbox.append((t.now(), Frame(message, b"", 1, 1)))
        assert t.last_seen().startswith("last mission message: MISSION_COUNT{")
