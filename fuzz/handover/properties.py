"""The safety properties of the handover under faults, and the judge that checks them.

The judge is a set of probes: a `DatagramNode` wrapped around the vehicle and one around each
GCS, so it sees the state of every node after every step it takes (a datagram or a poll), in
virtual time, exactly. What it records: the system manager's owner (`gcs_main`) after every
vehicle step; what every GCS believes after every GCS step; every CONTROL_STATUS and every
COMMAND_ACK of MAV_CMD_REQUEST_OPERATOR_CONTROL delivered to a GCS; the mission computer's
handover and emergency events; where the vehicle is. Symbols: `bound`, `commit_timeout`
(= bound - closing) as in docs/handover.md "Bound"; `d(g)` the longest one-way delay of the
vehicle-to-g link (delay + jitter + reorder_delay when reordering; a partition or a loss drops,
it does not delay); "flying" means the mission computer is on_mission or on_handover and the
flight model flies.

P1 one commander. "GCS g believes it commands" means: g's operator-control client says
`in_control`, i.e. the last word g had from the vehicle's system manager (the gcs_main of the
latest CONTROL_STATUS, or an ACCEPTED COMMAND_ACK to g's own request since) names g.
  (a) The manager never has more than one owner (single-owner mode: one `gcs_main`), and
      everything it tells a GCS was true when sent: a CONTROL_STATUS delivered to g at r names
      an owner the manager had at some instant of [r - d(g), r]; an ACCEPTED ACK of a control
      request delivered to g at r comes from an instant of [r - d(g), r] at which g owned
      control.
  (b) A stale belief never survives a fresh CONTROL_STATUS: if g believes it commands at t
      while the owner is not g, and control last left g at c, then no CONTROL_STATUS reached g
      in (c + d(g), t). Since the manager streams CONTROL_STATUS every `status_period` and at
      once on a change, on a link that delivers two GCSs believe they command at the same
      instant for at most `status_period + d(g)` (the staleness the brief allows); a lost
      CONTROL_STATUS lengthens it by a period per loss, and a partition until it heals.
P2 a handover ends in bounded time, and an abort keeps the old owner. Every handover started
  at s has ended by s + bound: COMPLETED or UNCONFIRMED only if control moved to the partner
  by s + commit_timeout (COMPLETED: the partner holds it at the end); ABORTED only if the
  partner never held control during it, and then the old commander holds control at the end
  unless something outside the handover took it (the emergency procedure, the commander's own
  release, another GCS); after such an abort ("not granted in time") the partner does not get
  control before the vehicle has left that handover region, except by an emergency takeback.
  The bound is the mission computer's own deadline, so it holds whatever the faults:
  every handover lasts at most `bound` = `commit_timeout + closing` seconds of virtual time
  (default 40 = 30 + 10; the scenario files' `handover_bound_s` = 15, so 11.25 + 3.75).
P3 never ownerless outside the emergency procedure. From take-off (the parent holds control),
  while flying, gcs_main is 0 only after the owner released control itself; an owner lost for
  silence, or revoked, leaves gcs_main 0 only with the mission computer on_emergency.
P4 no command from a non-owner is executed. A datagram from GCS g that changes the stored
  mission, starts or resumes the flight, or changes the current item, reached the vehicle
  while g owned control.
P5 one handover per region entry. Two handovers started for the same handover region have
  the vehicle outside that region (plain containment, sampled every `REGION_SAMPLE` = 0.1 s of
  vehicle steps; the mission computer counts an exit only after `dwell` outside, 1 s in the
  scenarios, so a real exit is never missed) between them.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from typing import Any

from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.control_results import ControlChanged
from mavconform.reference_impl.handover.emergency_procedure import EmergencyEnded, EmergencyStarted
from mavconform.reference_impl.handover.geo import GeoPoint
from mavconform.reference_impl.handover.mission_computer import HandoverFinished, HandoverStarted
from mavconform.reference_impl.handover.mission_computer_transitions import HandoverOutcome, McState
from mavconform.reference_impl.handover.regions import Intersection
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.wire.dialect import mavlink as _d

from .world import SETUP_DELAY

__all__ = ["PROPERTIES", "Judge", "Report", "Violation"]

PROPERTIES = {
    "P1": "one commander: the manager's word is true when sent, and no GCS believes it commands past a "
          "CONTROL_STATUS that said otherwise",
    "P2": "a handover ends within the bound, completed with the partner in control or aborted with the old "
          "owner kept",
    "P3": "never ownerless outside the emergency procedure (after the first grant, gcs_main 0 only after a "
          "release by the owner, or during the emergency)",
    "P4": "no command from a non-owner is executed (mission writes, MISSION_START, set-current)",
    "P5": "one handover per region entry",
}
EPS = 1e-9
REGION_SAMPLE = 0.1   # s: P5 looks where the vehicle is this often (an exit lasts at least the dwell)
_FLYING = (McState.ON_MISSION, McState.ON_HANDOVER)


@dataclass(frozen=True)
class Violation:
    prop: str
    at: float
    text: str

    def __str__(self) -> str:
        return f"{self.prop} at {self.at:.3f} s: {self.text}"


@dataclass
class Report:
    """What one flight showed: the violations and the figures a campaign sums."""

    violations: list[Violation] = field(default_factory=list)
    handovers: dict[str, int] = field(default_factory=dict)      # outcome -> count
    durations: list[float] = field(default_factory=list)         # every handover's, s
    emergencies: int = 0
    takebacks: int = 0
    max_stale_belief: float = 0.0    # longest a GCS believed it commanded while another did, s
    flight_time: float = 0.0
    setup_failed: str = ""


class _Probe:
    """A DatagramNode around `node`; `after(now, source)` runs after every step."""

    def __init__(self, node: Any, after: Any, before: Any = None) -> None:
        self.node, self._after, self._before = node, after, before

    def datagram_received(self, data: bytes, source: Any, now: float) -> None:
        snap = self._before() if self._before is not None else None
        self.node.datagram_received(data, source, now)
        self._after(now, source, snap)

    def poll(self, now: float) -> None:
        self.node.poll(now)
        self._after(now, None, None)

    def next_deadline(self) -> float | None:
        return self.node.next_deadline()

    def take_outgoing(self) -> list:
        return self.node.take_outgoing()


class Judge:
    """Watches one flight (world.py builds it with `Judge(scenario, vehicle, gcss, sysids, case)`)."""

    def __init__(self, scenario: Any, vehicle: Any, gcss: dict[str, Any], sysids: dict[str, int], case: Any) -> None:
        self.vehicle, self.gcss, self.sysids, self.case = vehicle, gcss, sysids, case
        self.names = {v: k for k, v in sysids.items()}
        self.cfg = vehicle.config.handover
        self.d = {name: max(case.link(name)[1].worst_delay, SETUP_DELAY) + 1e-6 for name in gcss}
        self.report = Report()
        self.owner_t: list[float] = [0.0]
        self.owner_v: list[int] = [vehicle.owner]
        self.beliefs: dict[str, list[tuple[float, bool]]] = {n: [(0.0, False)] for n in gcss}
        self.statuses: dict[str, list[tuple[float, int]]] = {n: [] for n in gcss}
        self.acks: dict[str, list[float]] = {n: [] for n in gcss}
        ids = self.cfg.gcs_ids
        self.regions = {f"{x}+{y}": Intersection((self.cfg.coverage(x), self.cfg.coverage(y)))
                        for i, x in enumerate(ids) for y in ids[i + 1:]}
        self.outside_seen: dict[str, bool] = {}
        self.last_start: dict[str, float] = {}
        self.armed: list[tuple[str, int, float]] = []      # (region, partner, aborted at)
        self.open: dict[tuple[int, int, float], HandoverStarted] = {}
        self.zero_cause = ""
        self.active = False
        self._seen_handover = 0
        self._seen_control = len(vehicle.control_events)
        self._p3_reported = False
        self._mc_before = vehicle.mission_computer.state     # at the end of the last vehicle step
        self._next_sample = 0.0
        self.vehicle_probe = _Probe(vehicle, self._after_vehicle, self._snapshot)
        self.takeoff = 0.0

    def gcs_probe(self, name: str) -> _Probe:
        return _Probe(self.gcss[name], lambda now, source, snap: self._after_gcs(name, now))

    def take_off(self, world: Any) -> None:
        self.active, self.takeoff = True, world.takeoff

    def violate(self, prop: str, at: float, text: str) -> None:
        if len(self.report.violations) < 100:
            self.report.violations.append(Violation(prop, at, text))

    # --- the vehicle's steps --------------------------------------------------------------------
    def _snapshot(self) -> tuple:
        v = self.vehicle
        return (v.owner, v.store.items(MissionType.MISSION), v.server.progress.seq, v.flight.flying,
                v.flight.diverting)

    def _after_vehicle(self, now: float, source: Any, snap: tuple | None) -> None:
        v = self.vehicle
        mc = v.mission_computer
        if len(v.control_events) != self._seen_control:
            for e in list(v.control_events)[self._seen_control - len(v.control_events):]:
                if isinstance(e, ControlChanged) and e.owner == 0 and e.previous:
                    self.zero_cause = "release" if e.reason.startswith("released by GCS") else e.reason
            self._seen_control = len(v.control_events)
        if len(v.handover_events) != self._seen_handover:
            for e in list(v.handover_events)[self._seen_handover - len(v.handover_events):]:
                self._handover_event(e, now)
            self._seen_handover = len(v.handover_events)
        owner = v.owner
        if owner != self.owner_v[-1]:
            self._owner_changed(owner, now, self._mc_before)
        self._mc_before = mc.state
        if not self.active:
            return
        self._watch_regions(now)
        # P3
        flying = v.flight.flying and mc.state in _FLYING
        if flying and owner == 0 and self.zero_cause != "release":
            if not self._p3_reported:
                self._p3_reported = True
                self.violate("P3", now, f"no GCS in control while {mc.state.value} (control dropped: "
                                        f"{self.zero_cause or 'never granted'}), and no emergency")
        elif owner:
            self._p3_reported = False
        # P4
        if snap is not None and source in self.sysids:
            sender = self.sysids[source]
            owner_before, mission, seq, was_flying, was_diverting = snap
            effects = []
            if v.store.items(MissionType.MISSION) is not mission:
                effects.append("the stored mission changed")
            if v.server.progress.seq != seq:
                effects.append(f"the current item changed {seq} -> {v.server.progress.seq}")
            if (v.flight.flying and not was_flying) or (was_diverting and not v.flight.diverting and v.flight.flying):
                effects.append("the flight started")
            if effects and sender != owner_before and sender != v.config.system:
                self.violate("P4", now, f"{' and '.join(effects)} on a datagram from GCS {sender} "
                                        f"(gcs_main {owner_before})")

    def _owner_changed(self, owner: int, now: float, before: McState) -> None:
        """`before`: the mission computer's state before this step (on_emergency: a takeback)."""
        self.owner_t.append(now)
        self.owner_v.append(owner)
        if owner and self.active:
            for region, partner, since in list(self.armed):
                if partner == owner and not self.outside_seen.get(region, False) and before is not McState.ON_EMERGENCY:
                    self.violate("P2", now, f"GCS {owner} got control {now - since:.2f} s after its handover "
                                            f"({region}) was aborted, the vehicle still in that region")
                    self.armed.remove((region, partner, since))

    def _watch_regions(self, now: float) -> None:
        if now < self._next_sample:
            return
        pending = [r for r in self.regions if r in self.last_start and not self.outside_seen.get(r, False)]
        if not pending:
            return
        self._next_sample = now + REGION_SAMPLE
        p = self.vehicle.flight.where(now)
        point = GeoPoint(p.lat, p.lon)
        for r in pending:
            if not self.regions[r].contains(point):
                self.outside_seen[r] = True
                self.armed = [a for a in self.armed if a[0] != r]

    def _handover_event(self, e: Any, now: float) -> None:
        rep = self.report
        if isinstance(e, HandoverStarted):
            if e.region in self.last_start and not self.outside_seen.get(e.region, False) and self.active:
                self.violate("P5", now, f"a second handover for region {e.region} without leaving it since the "
                                        f"one started at {self.last_start[e.region]:.2f} s")
            self.last_start[e.region] = now
            self.outside_seen[e.region] = False
            self.armed = [a for a in self.armed if a[0] != e.region]
            self.open[(e.commander, e.partner, e.at)] = e
        elif isinstance(e, HandoverFinished):
            r = e.result
            started = self.open.pop((r.commander, r.partner, r.started), None)
            rep.handovers[r.outcome.value] = rep.handovers.get(r.outcome.value, 0) + 1
            rep.durations.append(r.duration)
            self._judge_handover(r, started.region if started else "?", now)
        elif isinstance(e, EmergencyStarted):
            rep.emergencies += 1
        elif isinstance(e, EmergencyEnded) and e.owner:
            rep.takebacks += 1

    def _judge_handover(self, r: Any, region: str, now: float) -> None:
        cfg = self.cfg
        if r.duration > cfg.bound + EPS:
            self.violate("P2", now, f"handover {r.commander}->{r.partner} took {r.duration:.3f} s, more than "
                                    f"the bound {cfg.bound:g} s")
        commit = self._first_owner(r.partner, r.started, r.finished)
        if r.outcome is HandoverOutcome.ABORTED:
            if commit is not None:
                self.violate("P2", now, f"handover {r.commander}->{r.partner} aborted, yet GCS {r.partner} "
                                        f"held control at {commit:.3f} s")
            elif r.owner != r.commander and not self._taken_away(r):
                self.violate("P2", now, f"handover {r.commander}->{r.partner} aborted with gcs_main {r.owner}, "
                                        f"not the old commander ({r.detail})")
            if r.detail.startswith("control not granted"):
                self.armed.append((region, r.partner, now))
        else:
            if commit is None or commit > r.started + cfg.commit_timeout + EPS:
                self.violate("P2", now, f"handover {r.commander}->{r.partner} {r.outcome.value}, but control "
                                        f"did not move to GCS {r.partner} within {cfg.commit_timeout:g} s")
            if r.outcome is HandoverOutcome.COMPLETED and self.vehicle.owner != r.partner:
                self.violate("P2", now, f"handover {r.commander}->{r.partner} completed with gcs_main "
                                        f"{self.vehicle.owner}")

    def _taken_away(self, r: Any) -> bool:
        """Control left the old commander for a reason outside the handover."""
        return (r.detail.startswith("emergency:") or r.detail.startswith("control went to GCS")
                or (r.owner == 0 and self.zero_cause == "release"))

    def _first_owner(self, sysid: int, start: float, end: float) -> float | None:
        """The first instant in [start, end] at which `sysid` owned control."""
        i = max(0, bisect.bisect_right(self.owner_t, start) - 1)
        for t, o in zip(self.owner_t[i:], self.owner_v[i:]):
            if t > end + EPS:
                break
            if o == sysid:
                return max(t, start)
        return None

    # --- the GCSs' steps --------------------------------------------------------------------------
    def _after_gcs(self, name: str, now: float) -> None:
        gcs = self.gcss[name]
        me = self.sysids[name]
        if gcs.received:
            for msg in gcs.received:
                t = msg._type
                if t == "CONTROL_STATUS" and msg.flags & cm.FLAG_SYSTEM_MANAGER:
                    self.statuses[name].append((now, msg.gcs_main))
                elif (t == "COMMAND_ACK" and msg.command == cm.REQUEST_CONTROL and msg.result == _d.MAV_RESULT_ACCEPTED
                      and msg.target_system == me):
                    self.acks[name].append(now)
            gcs.received.clear()
        believes = gcs.control is not None and gcs.control.in_control
        if believes != self.beliefs[name][-1][1]:
            self.beliefs[name].append((now, believes))

    # --- after the flight ---------------------------------------------------------------------------
    def finish(self, world: Any) -> Report:
        rep = self.report
        rep.setup_failed = world.setup_failed
        end = world.net.clock.now()
        rep.flight_time = end - world.takeoff
        if world.setup_failed:
            return rep
        for (commander, partner, at), _ in self.open.items():
            if end > at + self.cfg.bound + EPS:
                self.violate("P2", end, f"handover {commander}->{partner} started at {at:.3f} s has not ended "
                                        f"{end - at:.1f} s later (bound {self.cfg.bound:g} s)")
        self._judge_beliefs(end)
        return rep

    def _owners(self, a: float, b: float) -> set[int]:
        """Every owner the manager had at some instant of [a, b] (a change instant counts for both)."""
        i = max(0, bisect.bisect_left(self.owner_t, a) - 1)
        j = bisect.bisect_right(self.owner_t, b)
        return set(self.owner_v[i:max(j, i + 1)])

    def _left_before(self, sysid: int, t: float) -> float | None:
        """When control last left `sysid` at or before t (None: it never held it before t)."""
        j = bisect.bisect_right(self.owner_t, t) - 1
        for k in range(j, 0, -1):
            if self.owner_v[k - 1] == sysid and self.owner_v[k] != sysid:
                return self.owner_t[k]
        return None

    def _judge_beliefs(self, end: float) -> None:
        for name in self.gcss:
            me, d = self.sysids[name], self.d[name]
            for r, named in self.statuses[name]:
                if named not in self._owners(r - d, r):
                    self.violate("P1", r, f"GCS {me} was told gcs_main {named} at {r:.3f} s; the manager's owner "
                                          f"in the {d:.3f} s before was {sorted(self._owners(r - d, r))}")
            for r in self.acks[name]:
                if me not in self._owners(r - d, r):
                    self.violate("P1", r, f"GCS {me} got an ACCEPTED control ACK at {r:.3f} s, yet it did not "
                                          f"own control in the {d:.3f} s before")
            times = [t for t, _ in self.statuses[name]]
            hist = self.beliefs[name] + [(end, False)]
            for (u, b), (v, _) in zip(hist, hist[1:]):
                if not b:
                    continue
                for w0, w1 in self._wrong(me, u, v):
                    self.report.max_stale_belief = max(self.report.max_stale_belief, w1 - w0)
                    c = self._left_before(me, w0)
                    if c is None:
                        self.violate("P1", w0, f"GCS {me} believes it commands but never owned control")
                        continue
                    k = bisect.bisect_right(times, c + d)
                    if k < len(times) and times[k] < w1 - EPS:
                        self.violate("P1", w1, f"GCS {me} still believed it commands at {w1:.3f} s although a "
                                               f"CONTROL_STATUS reached it at {times[k]:.3f} s, sent after control "
                                               f"left it at {c:.3f} s")

    def _wrong(self, me: int, u: float, v: float) -> list[tuple[float, float]]:
        """The maximal sub-intervals of [u, v) during which the owner is not `me`."""
        out: list[tuple[float, float]] = []
        i = max(0, bisect.bisect_right(self.owner_t, u) - 1)
        start: float | None = None
        for k in range(i, len(self.owner_t)):
            t0 = max(self.owner_t[k], u)
            if t0 >= v:
                break
            if self.owner_v[k] != me:
                start = t0 if start is None else start
            elif start is not None:
                out.append((start, t0))
                start = None
        if start is not None:
            out.append((start, v))
        return [(a, b) for a, b in out if b > a + EPS]
