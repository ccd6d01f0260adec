"""The rig: one connection to the target, the sender of fuzz datagrams, and the oracle.

One node plays both parts at the target's address book: the oracle GCS (a reference
`GcsNode`, system 250, which the fuzz frames never claim to be) and the fuzzer, whose
datagrams leave from the same socket (so a `udpin:` target, which answers one address,
hears both).

- In-process targets in virtual time (`SimNetwork`, `SimClock`): a fresh vehicle per
  example, so every example, and its replay, starts from the same state and is exact.
- Over UDP: one live target for the whole campaign (an in-process vehicle on loopback
  sockets, or a real one at `udp:` / `udpin:`), with real, bounded waits.

The link, as the target's parser reads it: the fuzz datagrams and the oracle's own leave
one socket, so they are one byte stream to a target that parses as the MAVLink C library
does (admission.py, reference_impl/wire/cparser.py). The station keeps the admission rule's stream model in
step with it: every datagram that leaves for the target is fed to it in the order it is
sent (`Admission.observe`), the oracle's frames are held back while a batch is being sent
(`Rig.send` .. the end of `Rig.flush`), and before the oracle speaks after fuzz bytes that
leave the parser mid-frame, a filler datagram (`Admission.resync`: bytes that are no frame
start, completing that frame as one the target refuses) brings it back to IDLE. The filler
is derived from the model alone, so a replay of a case's datagrams sends the same one; it
is not a step of the case.

The oracle, after a batch (`check`):
  no-exception        an in-process vehicle raised (GuardedNode caught it);
  plan-unchanged      an in-process vehicle's stored plans differ from the known ones;
  target-crash        no HEARTBEAT from the target within HEARTBEAT_WAIT after the batch;
  download-completes  a normal mission download failed, or returned another plan than the
                      download made right after the known plan was uploaded, compared in
                      the target's stored form (conformance/harness/stored_form.py: the
                      `current` flag left out, home in slot 0 and compact storage where the
                      target's autopilot family - its HEARTBEAT, or the in-process
                      vehicle's profile - keeps them).
"""

from __future__ import annotations

import hashlib
from typing import Any

from mavconform.conformance.harness import plans
from mavconform.conformance.harness.stored_form import (SPEC_FORM, StoredForm, describe_differences,
                                             modelling_profile, stored_form_of)
from mavconform.conformance.session import build_vehicle
from mavconform.conformance.target_uri import TargetUri
from mavconform.fuzz.case import Violation
from mavconform.reference_impl.errors import LocalProtocolError
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType
from mavconform.reference_impl.net.clock import MonotonicClock, SimClock
from mavconform.reference_impl.net.faults import FaultModel
from mavconform.reference_impl.net.guard import GuardedNode
from mavconform.reference_impl.net.node import Address
from mavconform.reference_impl.net.sim import CaptureHook, SimNetwork
from mavconform.reference_impl.net.udp import UdpDriver
from mavconform.reference_impl.net.links import attach
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleNode
from mavconform.reference_impl.wire.signing import SigningKey

from .admission import INERT, Admission, inert_messages
from .mutators import MutationContext
from .program import Builder

ORACLE_ID = (250, 190)
HEARTBEAT_WAIT = 2.5        # s: a 1 Hz HEARTBEAT may not pause longer than this
DISCOVERY_WAIT = 5.0        # s for the first HEARTBEAT of a UDP target
SETTLE_WAIT = 2.0           # s an in-process UDP vehicle gets to read a sent batch
SEND_CHUNK = 32             # datagrams in flight at once over UDP (socket buffers are finite)
PLAN_VARIANT = 7            # the known plan (conformance/harness/plans.py, variant 7)
# A TCP target's bytes per second: a telemetry radio's 57600 baud. INAV's SITL reads its
# TCP port into a 2048-byte ring that overwrites unread bytes when a burst outruns it
# (drivers/serial_tcp.c:123-133; one frame is handled per 2 ms telemetry cycle): a 3200-byte
# burst of 200 requests drew 72 answers. Bytes a target drops mid-stream join frames no
# admission model predicts, so the fuzzer sends no faster than a flight controller on a
# radio reads (480 minimal frames/s). A serial target is paced at its own baud rate.
STREAM_FUZZ_RATE = 5760.0


def campaign_key(seed: int, which: str = "target") -> bytes:
    """The signing secret of a signing vehicle (or the wrong one), derived from the seed."""
    return hashlib.sha256(f"mavconform-frames/{which}/{seed}".encode()).digest()


def known_plans(in_process: bool) -> dict[MissionType, list]:
    """What the rig uploads before fuzzing: every plan type in-process, where the store is
    compared afterwards; only the mission elsewhere (a real target's fence is left alone)."""
    types = PLAN_TYPES if in_process else (MissionType.MISSION,)
    return {t: plans.plan(t, variant=PLAN_VARIANT) for t in types}


def _float_only(profile: str | None) -> bool:
    """Does --profile say the external target ignores the _INT mission messages (INAV 9.1)?
    Then the oracle GCS reads plans with MISSION_REQUEST (an in-process vehicle's own config
    says so for it)."""
    from mavconform.reference_impl.profiles import load_profile
    return profile is not None and load_profile(profile).int_messages_ignored


class _Station:
    """The oracle GCS plus the fuzzer's outbox, as one datagram node.

    Sends the outbox first, then (unless `holding`: a batch is being sent) the GCS's
    datagrams, preceded by the admission rule's resync filler when the fuzz bytes left the
    target's parser mid-frame; every datagram for the target is fed to the rule's stream
    model (`admission`, set once the campaign's builder exists) in that order."""

    def __init__(self, gcs: GcsNode, target_address: Address | None) -> None:
        self.gcs = gcs
        self.target_address = target_address
        self.outbox: list[bytes] = []
        self.last_heartbeat: float | None = None
        self._heartbeat: Any = None
        self.admission: Admission | None = None
        self.holding = False
        self._held: list[tuple[bytes, Address]] = []

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        gcs = self.gcs
        gcs.datagram_received(data, source, now)
        if gcs.target_heartbeat is not self._heartbeat:
            self._heartbeat = gcs.target_heartbeat
            self.last_heartbeat = now
            if self.target_address is None:
                self.target_address = source

    def poll(self, now: float) -> None:
        self.gcs.poll(now)

    def next_deadline(self) -> float | None:
        return self.gcs.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        admission = self.admission
        out: list[tuple[bytes, Address]] = []
        if self.outbox:
            to = self.target_address
            for d in self.outbox:
                if admission is not None:
                    admission.observe(d)
                out.append((d, to))
            self.outbox = []
        gcs = self.gcs.take_outgoing()
        if self.holding:
            self._held.extend(gcs)
            return out
        if self._held:
            gcs = self._held + gcs
            self._held = []
        if gcs and admission is not None:
            filler = admission.resync()
            if filler is not None:
                out.append((filler, self.target_address))
            for d, _ in gcs:
                admission.observe(d)
        out.extend(gcs)
        return out


class _Counted:
    """A node wrapper counting the datagrams it was handed (what the target really read)."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.received = 0

    def datagram_received(self, data: bytes, source: Address, now: float) -> None:
        self.received += 1
        self.node.datagram_received(data, source, now)

    def poll(self, now: float) -> None:
        self.node.poll(now)

    def next_deadline(self) -> float | None:
        return self.node.next_deadline()

    def take_outgoing(self) -> list[tuple[bytes, Address]]:
        return self.node.take_outgoing()


class Rig:
    """A connected target, ready for batches. Call `start()` first; `close()` at the end."""

    def __init__(self, uri: TargetUri, *, seed: int, signing: bool = False, virtual: bool = True,
                 capture: CaptureHook | None = None, scale: float = 1.0,
                 profile: str | None = None, latency: float = 0.0) -> None:
        self.profile = profile   # a UDP target's stored form: this profile's (None: from its HEARTBEAT)
        if virtual and not uri.in_process:
            raise ValueError("virtual time needs an in-process target")
        if signing and uri.kind != "builtin":
            raise ValueError("only builtin targets run a signing vehicle")
        self.uri = uri
        self.virtual = virtual
        self.scale = scale
        self.key = campaign_key(seed) if signing else None
        self.clock: Any = SimClock() if virtual else MonotonicClock()
        self.vehicle: VehicleNode | None = None
        self.guard: GuardedNode | None = None
        self.counted: _Counted | None = None
        self.stream: Any = None   # a TCP or serial target's link (reference_impl/net/stream_link.py)
        self.snapshot: Any = None
        self.plans = known_plans(uri.in_process)
        self.expected: tuple | None = None   # the mission as downloaded before the first batch
        self.form: StoredForm = SPEC_FORM     # how the target stores plans (set in start)
        self.frames_sent = 0
        self.datagrams_sent = 0
        gcs_config = GcsConfig(system=ORACLE_ID[0], component=ORACLE_ID[1],
                               signing=SigningKey(self.key) if self.key else None,
                               download_int=uri.in_process or not _float_only(profile))
        wall = self.clock.wall
        if uri.in_process:
            keyed = {"signing": SigningKey(self.key), "require_signature": True} if self.key else {}
            # the fuzzed frames and the oracle GCS come from addresses of their own
            self.vehicle = build_vehicle(uri, wall_clock=wall, single_peer_link=False, **keyed)
            self.guard = GuardedNode(self.vehicle)
            self.counted = _Counted(self.guard)
            gcs_config = GcsConfig(system=ORACLE_ID[0], component=ORACLE_ID[1],
                                   target=(self.vehicle.config.system, self.vehicle.config.component),
                                   signing=gcs_config.signing,
                                   download_int=not self.vehicle.config.int_forms_ignored)
        self.gcs = GcsNode(gcs_config, wall_clock=wall)
        if virtual:
            self.driver: Any = SimNetwork(seed, self.clock)
            self.station = _Station(self.gcs, "vehicle")
            self.driver.add_node("vehicle", self.counted)
            self.driver.add_node("gcs", self.station)
            link = FaultModel(delay=latency)   # one-way latency, each direction (fuzz/case.py)
            self.driver.connect("gcs", "vehicle", a_to_b=link, b_to_a=link.copy())
            self.vehicle.endpoint.add_address("gcs")
            self.gcs.endpoint.add_address("vehicle")
        else:
            self.driver = UdpDriver(self.clock, seed=seed)
            try:
                if uri.in_process:
                    where = self.driver.add_node(self.counted)
                    self.station = _Station(self.gcs, where)
                    here = self.driver.add_node(self.station)
                    self.vehicle.endpoint.add_address(here)
                    self.gcs.endpoint.add_address(where)
                else:   # udpin: the target sends first; its address is learned
                    self.station = _Station(self.gcs, None)
                    peer, _ = attach(self.driver, self.station, uri.link)
                    if peer is not None:
                        self.station.target_address = peer
                        self.gcs.endpoint.add_address(peer)
                    self.stream = self.driver.stream_of(self.station)
                    if self.stream is not None and self.stream.bytes_per_second is None:
                        self.stream.bytes_per_second = STREAM_FUZZ_RATE
            except BaseException:
                self.driver.close()
                raise
        if capture is not None:
            self.driver.add_capture(capture)
        self.session = GcsSession(self.driver, self.gcs)
        ctx = MutationContext(key=self.key or campaign_key(seed), wrong_key=campaign_key(seed, "wrong"),
                              wall_clock=wall)
        self._target: tuple[int, int] | None = None
        self._ctx = ctx
        self.builder: Builder | None = None

    # --- lifecycle ------------------------------------------------------------------------
    def start(self) -> Violation | None:
        """Find the target, upload the known plans; a Violation if the target is dead."""
        # the first HEARTBEAT too (an in-process target is known already): the oracle GCS may
        # adapt to the autopilot it names, and must do so before the reference download
        station = self.station
        if not self.driver.run_until(lambda: self.gcs.connected and station.target_address is not None
                                     and station.last_heartbeat is not None,
                                     timeout=DISCOVERY_WAIT * self.scale):
            return Violation("target-crash", f"no HEARTBEAT from {self.uri} within "
                             f"{DISCOVERY_WAIT * self.scale:g} s, before any fuzz frame was sent")
        self._target = self.gcs.target
        heartbeat = self.gcs.target_heartbeat
        model = modelling_profile(str(self.uri), vehicle_config=self.vehicle.config if self.vehicle else None,
                                  mutant=self.uri.kind == "mutant", chosen=self.profile,
                                  autopilot=getattr(heartbeat, "autopilot", None),
                                  mav_type=getattr(heartbeat, "type", None))
        self.form = stored_form_of(model)
        # what the target reads: an in-process vehicle's or --profile's (a HEARTBEAT's guess
        # is not enough to leave messages out of the fuzz)
        known = self.vehicle.config if self.vehicle is not None else (model[0] if self.profile and model else None)
        inert = inert_messages(known) if known is not None else INERT
        admission = Admission(self.key, self.key is not None, self._ctx.wall_clock, inert=inert)
        self.builder = Builder(self._target, self._ctx, admission, sign_frames=self.key is not None)
        station.admission = admission        # from now on every datagram to the target is fed to it
        for t, items in list(self.plans.items()):
            result = self._operation(lambda: self.session.upload(t, items))
            if result is None or not result.ok:
                what = "no result" if result is None else result.summary()
                if t is MissionType.MISSION or self._crash() is not None:
                    return self._crash_violation() or Violation(
                        "download-completes", f"the known {t.label} plan could not be uploaded before "
                        f"fuzzing ({what})")
                del self.plans[t]       # e.g. a vehicle that stores no fence: judged without one
        # What "the known plan" downloads as (a profile may store it transformed, e.g. with a
        # home item): every later download must equal this one.
        result = self._operation(lambda: self.session.download(MissionType.MISSION))
        if result is None or not result.ok:
            return self._crash_violation() or Violation(
                "download-completes", "the known mission could not be downloaded before fuzzing "
                f"({'no result' if result is None else result.summary()})")
        self.expected = result.items
        if self.vehicle is not None:
            self.snapshot = self.vehicle.store.snapshot()
        return None

    def close(self) -> None:
        if not self.virtual:
            self.driver.close()

    # --- sending --------------------------------------------------------------------------
    def send(self, frames: list[bytes]) -> None:
        """Queue one datagram (the frames back to back); the oracle stays quiet until the
        batch is flushed."""
        self.station.holding = True
        self.station.outbox.append(b"".join(frames))
        self.frames_sent += len(frames)
        self.datagrams_sent += 1

    def flush(self) -> None:
        """Deliver what is queued: in virtual time, at once; over UDP, in chunks the target
        can read (an in-process target is waited for, bounded). Then the oracle may speak."""
        try:
            self._flush()
        finally:
            self.station.holding = False

    def _flush(self) -> None:
        if self.virtual:
            self.driver.run_until_quiet(timeout=0.0)
            return
        counted = self.counted
        if counted is None and self.stream is not None:
            self._flush_stream(self.stream)
            return
        if counted is None:
            self.driver.run_until(_always, timeout=0.0)
            return
        pending, self.station.outbox = self.station.outbox, []
        base = counted.received
        for i in range(0, len(pending), SEND_CHUNK):
            chunk = pending[i:i + SEND_CHUNK]
            self.station.outbox.extend(chunk)
            want = base + i + len(chunk)
            self.driver.run_until(lambda: counted.received >= want or self._crash() is not None,
                                  timeout=SETTLE_WAIT)

    def _flush_stream(self, link: Any) -> None:
        """A stream link's queue is never overrun (it would drop whole frames, and the target
        would read a stream the admission model did not): each datagram waits for room, and
        the batch is on the wire before the oracle speaks. Every wait is bounded by the line
        time of what is queued."""
        pending, self.station.outbox = self.station.outbox, []
        limit = link.max_queued // 2
        rate = link.bytes_per_second or STREAM_FUZZ_RATE
        for datagram in pending:
            if not link.up:
                break      # the target went away: check() reports it
            self.driver.run_until(lambda: link.queued + len(datagram) <= limit or not link.up,
                                  timeout=link.queued / rate + 1.0)
            self.station.outbox.append(datagram)
            self.driver.run_until(_always, timeout=0.0)
        self.driver.run_until(lambda: link.queued == 0 or not link.up, timeout=link.queued / rate + 1.0)

    def crashed(self) -> Violation | None:
        return self._crash_violation()

    # --- the oracle -----------------------------------------------------------------------
    def check(self, *, lazy_heartbeat: bool = False) -> Violation | None:
        """Judge the target after a batch (see the module docstring). `lazy_heartbeat` (long
        UDP campaigns) accepts a HEARTBEAT heard up to HEARTBEAT_WAIT before now instead of
        waiting for one after the batch, so a live target costs no wait at all."""
        v = self._crash_violation() or self._store_violation()
        if v is not None:
            return v
        wait = HEARTBEAT_WAIT * self.scale
        now = self.driver.clock.now()
        since = now - wait if lazy_heartbeat else now
        station = self.station
        heard = self.driver.run_until(
            lambda: (station.last_heartbeat is not None and station.last_heartbeat > since)
            or self._crash() is not None, timeout=wait)
        v = self._crash_violation()
        if v is not None:
            return v
        if not heard:
            return Violation("target-crash", f"no HEARTBEAT from the target within {wait:g} s after the batch "
                             f"(it had sent them at 1 Hz before)")
        result = self._operation(lambda: self.session.download(MissionType.MISSION))
        v = self._crash_violation() or self._store_violation()
        if v is not None:
            return v
        want = self.expected
        if result is None or not result.ok:
            what = "no result within the client's own bound" if result is None else result.summary()
            return Violation("download-completes", f"a normal mission download after the batch did not "
                             f"complete: {what}")
        if not self.form.same(result.items, want, want_stored=True):
            return Violation("download-completes", "the mission downloaded after the batch is not the known "
                             f"plan: {_plan_diff(want, result.items, self.form)}")
        return None

    # --- internals ------------------------------------------------------------------------
    def _operation(self, run: Any) -> Any:
        try:
            return run()
        except LocalProtocolError:
            return None

    def _crash(self) -> str | None:
        return self.guard.crash if self.guard is not None else None

    def _crash_violation(self) -> Violation | None:
        crash = self._crash()
        if crash is None:
            return None
        return Violation("no-exception", f"the vehicle raised {crash}; from outside it fell silent")

    def _store_violation(self) -> Violation | None:
        if self.vehicle is None or self.snapshot is None:
            return None
        now = self.vehicle.store.snapshot()
        for t in PLAN_TYPES:
            if now[t] != self.snapshot[t]:
                return Violation("plan-unchanged", f"the stored {t.label} plan changed during the batch: "
                                 f"{_plan_diff(self.snapshot[t], now[t])}")
        return None


def _plan_diff(want: tuple, got: tuple | None, form: StoredForm | None = None) -> str:
    """What differs: item counts, else (with `form`: in the target's stored form, every
    field) the first differing item."""
    if got is None:
        return "nothing came back"
    if len(want) != len(got):
        return f"{len(got)} items instead of {len(want)}"
    if form is not None:
        diffs = form.differences(got, want, want_stored=True)
        return f"{describe_differences(diffs) if diffs else 'equal'} (compared as: {form.describe()})"
    for a, b in zip(want, got):
        if a != b:
            return f"item {a.seq} differs ({b} instead of {a})"
    return "equal"


def _always() -> bool:
    return True
