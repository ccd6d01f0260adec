"""Framing (seed 001, "Packet format" and "Heartbeat"; seed 000, "Mission Types"): MIS.FRM.*

What the target's frames themselves must be: MAVLink 2 whenever a transfer needs the
mission_type extension (fence, rally), a good checksum on every frame, a packet sequence
that counts up by one per frame, and a HEARTBEAT that keeps coming.
"""

from __future__ import annotations

import ipaddress

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import MissionResult
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionItem, MissionType
from mavconform.reference_impl.wire.frame import Frame

from ..harness import plans, procedures
from ..harness.match import ITEMS, REQUESTS, ack, msg
from ..harness.measured import Measured
from ..harness.tester import Tester
from ..harness.tester_node import Arrival
from ..outcome import ClauseFailed, NotApplicable, PreconditionFailed
from ..session import Session
from . import check

MISSION, FENCE, RALLY = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY
RETRIES = procedures.RETRIES
HEARTBEAT_WINDOW = 2.5     # s in which at least two HEARTBEATs must come (1 Hz nominal)
HEARTBEAT_LOOKBACK = 1.0   # s of already-received traffic the window may start in
MAX_STEP_FORWARD = 127     # a seq step of more than this (mod 256) is a step backwards


# --- MIS.FRM.01 ---------------------------------------------------------------------------

def _require_v2(frame: Frame, during: str) -> None:
    if frame.version != 2:
        got = frame.msg
        fields = ", ".join(f"{k}={getattr(got, k)}" for k in ("seq", "count", "type") if hasattr(got, k))
        raise ClauseFailed(f"during {during} the vehicle sent {got._type}{{{fields}}} in a MAVLink "
                           f"{frame.version} frame (magic 0x{frame.raw[0]:02X}); expected MAVLink 2, the "
                           "only version that carries mission_type")


def _typed_upload(t: Tester, items: list[MissionItem], mt: MissionType) -> bool:
    """Upload, accepting requests and ACKs whatever mission_type they say (a MAVLink 1 frame
    cannot say any), checking every frame's version. False if the type is unsupported."""
    during = f"a {mt.label} upload"
    t.mark()
    t.send(m.count_message(len(items), mt, t.target))
    for _ in range((len(items) + 2) * (RETRIES + 2)):
        frame = t.poll_for(msg(REQUESTS) | ack(), t.timings.default_timeout)
        if frame is None:
            raise PreconditionFailed(f"{during} stalled: no request or MISSION_ACK within the reply timeout")
        _require_v2(frame, during)
        got = frame.msg
        if got._type == "MISSION_ACK":
            if got.type == MissionResult.UNSUPPORTED:
                return False
            if got.type != MissionResult.ACCEPTED:
                raise PreconditionFailed(f"{during} was answered {procedures.result_name(got.type)}")
            return True
        if 0 <= got.seq < len(items):
            t.send(m.item_message(items[got.seq], t.target))
    raise PreconditionFailed(f"{during} never ended")


def _typed_download(t: Tester, n: int, mt: MissionType) -> None:
    during = f"a {mt.label} download"
    t.mark()
    t.send(m.request_list_message(mt, t.target))
    frame = t.poll_for(msg("MISSION_COUNT") | ack(), t.timings.default_timeout)
    if frame is None:
        raise PreconditionFailed(f"{during}: MISSION_REQUEST_LIST got no answer")
    _require_v2(frame, during)
    for seq in range(n):
        for _ in range(RETRIES + 1):
            t.send(m.request_message(seq, mt, t.target))
            frame = t.poll_for(msg(ITEMS, seq=seq) | ack(), t.timings.default_timeout)
            if frame is not None:
                break
        if frame is None:
            raise PreconditionFailed(f"{during}: item {seq} never came")
        _require_v2(frame, during)
    t.send(m.ack_message(MissionResult.ACCEPTED, mt, t.target))


@check("MIS.FRM.01")
def fence_and_rally_in_mavlink2(s: Session) -> None:
    t = s.t
    done = []
    for mt in (FENCE, RALLY):
        items = plans.plan(mt, variant=80)
        if _typed_upload(t, items, mt):
            _typed_download(t, len(items), mt)
            done.append(mt.label)
    if not done:
        raise NotApplicable("the vehicle stores neither fence nor rally plans (both refused as unsupported)")


# --- MIS.FRM.02 ---------------------------------------------------------------------------

def _target_errors(s: Session) -> list:
    """The tester's kept decode errors from the target's address (all of them if the address
    is not known)."""
    address = s.target_address
    return [e for e in s.t.node.endpoint.decode_errors if address is None or e[0] == address]


def _new_errors(s: Session, before: list) -> list:
    seen = {id(e) for e in before}
    return [e for e in _target_errors(s) if id(e) not in seen]


def _checkable(error) -> bool:
    """A frame whose checksum we can judge: not one of a message our dialect lacks (its
    CRC_EXTRA is unknown to us, so its checksum cannot be checked)."""
    return not error[1].reason.startswith("unknown message id")


@check("MIS.FRM.02")
def frames_have_valid_checksums(s: Session) -> None:
    t = s.t
    before = _target_errors(s)
    frames_before = len(t.node.inbox)
    for mt in PLAN_TYPES:
        items = plans.plan(mt, variant=81)
        frame = procedures.upload(t, items, mt)
        if frame is None or frame.msg.type != MissionResult.ACCEPTED:
            continue
        if procedures.download(t, mt) is None:
            raise PreconditionFailed(f"the {mt.label} download did not complete")
    new = [e for e in _new_errors(s, before) if _checkable(e)]
    if new:
        received = len(t.node.inbox) - frames_before
        shown = "; ".join(str(e[1]) for e in new[:3])
        raise ClauseFailed(f"{len(new)} frame(s) from the target failed to decode (beside {received} good "
                           f"ones) during uploads and downloads of every plan type: {shown}")


# --- MIS.FRM.03 ---------------------------------------------------------------------------

def _on_loopback(s: Session) -> bool:
    if s.uri.in_process:
        return True
    address = s.target_address
    try:
        return isinstance(address, tuple) and ipaddress.ip_address(address[0]).is_loopback
    except ValueError:
        return False


def _counted(template: str, numbers: dict[str, object]) -> Measured:
    """`template` with its <name>s measured: the counts depend on the target's stream and on
    our socket's luck, so two runs of one target differ in them."""
    return Measured(template, **{k: str(v) for k, v in numbers.items() if f"<{k}>" in template})


def _arrivals(t: Tester) -> list[Arrival]:
    """The frames from the target while the clause's transfers run, each with what we had
    lost by then (TesterNode.arrivals)."""
    node = t.node
    node.arrivals = []
    try:
        procedures.ensure_plan(t, plans.mission(4, variant=82), MISSION)
        if procedures.download(t, MISSION) is None:
            raise PreconditionFailed("the mission download did not complete")
    finally:
        arrivals, node.arrivals = node.arrivals, None
    if len(arrivals) < 2:
        raise PreconditionFailed("fewer than two frames came from the target")
    return arrivals


@check("MIS.FRM.03")
def packet_sequence_counts_up(s: Session) -> None:
    """Between two frames we read, the target's sequence may skip as many values as frames
    of its we did not read there: undecoded ones (damaged, or of a message our dialect lacks)
    and those in datagrams our own socket dropped, each of which may have held as many frames
    as the target packs into one. More than that is the target's, but on a network that
    loses frames itself, or where our drops cannot be counted, only noted. Where we lost
    nothing, a repeat or a step back is the target's; where we lost frames (or cannot tell),
    the 8-bit number may have wrapped, so a step back of k is a skip of 255 - k values."""
    t = s.t
    arrivals = _arrivals(t)
    per = t.node.frames_per_datagram(s.target_address)
    first, last = arrivals[0], arrivals[-1]
    known = first.dropped is not None and last.dropped is not None
    dropped = last.dropped - first.dropped if known else None
    undecoded = last.undecoded_after - first.undecoded_before
    missing = beyond = 0
    first_beyond = last.frame   # the frame after the first gap we cannot explain
    for a, b in zip(arrivals, arrivals[1:]):
        step = (b.frame.seq - a.frame.seq) % 256
        fewest = step - 1 if step else 255   # values skipped, at the least
        drops = b.dropped - a.dropped if known else 0
        ours = b.undecoded_after - a.undecoded_before + drops * per
        if fewest <= ours:
            missing += fewest
            continue
        if known and not ours and (step == 0 or step > MAX_STEP_FORWARD):   # else maybe a wrapped skip
            kind = "repeated" if step == 0 else f"went back by {256 - step}"
            t.decided_by_frame(b.frame)
            raise ClauseFailed(f"the packet sequence {kind}: {a.frame.msg._type} had seq {a.frame.seq}, the next "
                               f"frame ({b.frame.msg._type}) seq {b.frame.seq}; each frame should carry the previous "
                               "seq + 1 (mod 256)")
        if not beyond:
            first_beyond = b.frame
        missing += fewest
        beyond += fewest - ours
    may_lose = not _on_loopback(s)
    numbers = {"missing": missing, "frames": len(arrivals), "beyond": beyond, "undecoded": undecoded,
               "dropped": dropped, "per": per}
    lost = "<undecoded> failed to decode; " + (
        "our socket's drops are unknown on this platform" if dropped is None
        else "our socket's receive queue dropped <dropped> datagram(s) of up to <per> frame(s) each")
    if beyond and not may_lose and known:
        t.decided_by_frame(first_beyond)
        raise ClauseFailed(_counted(
            "the packet sequence skipped <missing> value(s) over <frames> frames, <beyond> more than the frames "
            f"from the target we lost there ({lost}); on loopback nothing else is lost, so each frame should "
            "carry the previous seq + 1 (gaps are tolerated only for frames that could have been lost)", numbers))
    if missing:
        why = ("frames may be lost on this network" if may_lose and beyond
               else "the gap may be ours" if beyond else "no more than the frames of the target's we lost there")
        t.note(_counted(f"the packet sequence skipped <missing> value(s) over <frames> frames ({why}: {lost})",
                        numbers))


# --- MIS.FRM.04 ---------------------------------------------------------------------------

@check("MIS.FRM.04")
def heartbeat_is_regular(s: Session) -> None:
    t = s.t
    node = t.node
    opened = t.now() - HEARTBEAT_LOOKBACK * t.scale
    closes = opened + HEARTBEAT_WINDOW * t.scale

    def heartbeats() -> list[float]:
        out = []
        for at, frame in reversed(node.inbox):
            if at < opened:
                break
            if frame.msg._type == "HEARTBEAT":
                out.append(at)
        return out[::-1]

    t.wait_until(lambda: len(heartbeats()) >= 2, max(0.0, closes - t.now()) / t.scale)
    seen = [round(at - opened, 3) for at in heartbeats() if at <= closes]
    t.decided_by = t.note(Measured(f"HEARTBEATs at <at> s into a {HEARTBEAT_WINDOW * t.scale:g} s window",
                                   at=str(seen)))   # HEARTBEATs are not drawn: the note sums them up
    if len(seen) < 2:
        raise ClauseFailed(f"{len(seen)} HEARTBEAT(s) in {HEARTBEAT_WINDOW * t.scale:g} s; expected at least 2 "
                           "(a component broadcasts its HEARTBEAT regularly, nominally at 1 Hz)")


# --- MIS.FRM.05 ---------------------------------------------------------------------------

import time  # noqa: E402  (appended section: the imports above are shared)

from ..harness.sentinel import answers_before_sentinel, brief  # noqa: E402
from ..outcome import TargetUnresponsive  # noqa: E402

# the frame fuzzer's faults. Imported with the clauses, not inside one: the import takes
# ~0.2 s, and while a check computes, an in-process vehicle's timers wait (4 times as long
# on its 4x clock)
from mavconform.fuzz.frames.mutators import MutationContext, bad_crc, truncate  # noqa: E402

BAD_CRC_FLIP = 0x5A5A      # XORed into the checksum (fuzz.frames.mutators.bad_crc)
# After a frame cut short: bytes with no frame marker in them. A decoder that reads each
# datagram alone drops them; a stream parser (mavlink_parse_char keeps its state across
# datagrams) finishes the cut-off frame with them, fails its checksum and skips the rest,
# so the next real frame is read cleanly. 0x55 as a target_system is not the target's.
FILLER = bytes([0x55]) * 280


def _damaged_frames(t: Tester) -> list[tuple[str, bytes]]:
    """MISSION_CLEAR_ALL and MISSION_COUNT 0 (each would empty the plan if acted on), each
    once with a bad checksum and once cut off before its checksum; properly addressed."""
    ctx = MutationContext(key=b"", wrong_key=b"", wall_clock=time.time)   # neither fault signs
    out = []
    for name, message in (("MISSION_CLEAR_ALL", m.clear_all_message(MISSION, t.target)),
                          ("MISSION_COUNT 0", m.count_message(0, MISSION, t.target))):
        frame = t.node.endpoint.encoder.encode(message)
        out.append((f"{name} with a bad checksum", bad_crc(frame, BAD_CRC_FLIP, ctx)))
        out.append((f"{name} cut off before its checksum", truncate(frame, len(frame) - 3, ctx)))
        out.append(("bytes with no frame marker (ends the cut-off frame in a stream parser)", FILLER))
    return out


def _send_raw(t: Tester, data: bytes, what: str) -> None:
    """`data` to the target as one datagram, where the tester's messages go."""
    t.node.endpoint.send_raw(data, t.target)
    # the bytes hold the tester's packet sequence number, which depends on the run so far
    t.note(Measured(f"raw datagram: {what} ({len(data)} bytes <bytes>...)", bytes=data[:12].hex()))
    t.driver.run_until(lambda: True, timeout=0.0)


def _heard_after(t: Tester, name: str, mark: object) -> bool:
    """Whether a `name` frame was received after the inbox entry `mark` (times do not
    order frames: in virtual time many arrive at one instant)."""
    for entry in reversed(t.node.inbox):
        if entry is mark:
            return False
        if entry[1].msg._type == name:
            return True
    return False


def _heard_within(t: Tester, name: str, seconds: float) -> bool:
    """Whether a `name` frame was received in the last `seconds` (scaled)."""
    since = t.now() - seconds * t.scale
    for at, frame in reversed(t.node.inbox):
        if at < since:
            return False
        if frame.msg._type == name:
            return True
    return False


def _silenced(s: Session, what: str) -> ClauseFailed:
    crash = s.guard.crash if s.guard is not None else None
    if crash is not None:
        return ClauseFailed(f"the damaged frames crashed the in-process vehicle: {crash}")
    return ClauseFailed(what)


@check("MIS.FRM.05")
def damaged_frames_not_acted_on(s: Session) -> None:
    t = s.t
    procedures.ensure_plan(t, plans.mission(3, variant=83), MISSION)
    before = procedures.stored(t, MISSION)
    # HEARTBEAT is judged after the damaged frames only if it was coming before them (a
    # vehicle that does not beat regularly is MIS.FRM.04's finding, not this clause's)
    beating = _heard_within(t, "HEARTBEAT", HEARTBEAT_WINDOW)
    t.mark()
    sent_after = t.node.inbox[-1] if t.node.inbox else None
    for what, data in _damaged_frames(t):
        _send_raw(t, data, what)
    try:
        replies = answers_before_sentinel(t)
        alive = not beating or t.wait_until(lambda: _heard_after(t, "HEARTBEAT", sent_after),
                                            HEARTBEAT_WINDOW)
    except TargetUnresponsive as exc:
        raise _silenced(s, f"after the damaged frames the target fell silent: {exc}") from None
    if replies:
        t.decided_by_frame(replies[0])
        raise ClauseFailed(f"MISSION_CLEAR_ALL / MISSION_COUNT 0 frames with a bad checksum or cut off "
                           f"drew {brief(replies[0].msg)}; expected no answer (a damaged frame is dropped)")
    if not alive:
        raise _silenced(s, f"no HEARTBEAT came in the {HEARTBEAT_WINDOW * t.scale:g} s after the damaged "
                        "frames; expected the vehicle to go on as before")
    got = procedures.download(t, MISSION)
    if got is None:
        raise _silenced(s, "after the damaged frames a normal download of the plan did not complete; "
                        "expected the vehicle to answer as before")
    procedures.require_same_plan(got.items, before, "after MISSION_CLEAR_ALL and MISSION_COUNT 0 frames "
                                 "with a bad checksum or cut off", t.form)
