"""Exchange vectors: complete exchanges between the reference GCS and vehicle, recorded.

Each scenario runs a fresh `GcsNode` against a fresh builtin vehicle (`spec`, `px4` or
`ardupilot`: conformance/session.py `build_vehicle`, the profile's own vehicle without the
suite's overrides) on a `SimNetwork` in virtual time, both link directions 10 ms one way and
any scripted faults the scenario names, the GCS's sysid 255 / compid 190 and the vehicle's
1 / 1. Every datagram either node sends is recorded once, in send order: as the JSON
transcript (time, direction, lost or not, hex, decoded fields) and, through `McapCapture`,
as an MCAP file with a marker where each step starts. A step that sets something up (the
upload before a download) is part of the exchange, so a transcript replays from nothing.

Same seed, same bytes: nothing reads the real clock or a global RNG (SimNetwork's design).

HANDOVER: the authority handover between two GCSs and the vehicle (`handover_scenarios()`,
`run_handover()`): a shipped handover scenario flown by reference_impl/handover/scenario_run.py
`run_scenario` (its fleet: the scenario's vehicle, one GCS per scenario GCS), each link 10 ms
one way, recorded with the same hook. The first GCS of the scenario is "gcs", the second
"gcs2" (transcript and MCAP channels alike); the files go to exchanges/handover/.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from mavconform.conformance.session import build_vehicle
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover.scenario import Scenario as HandoverScenarioFile
from mavconform.reference_impl.handover.scenario import load_scenario, shipped_scenarios
from mavconform.reference_impl.handover.scenario_fleet import gcs_address, gcs_config, vehicle_config
from mavconform.reference_impl.handover.scenario_run import ScenarioRun, run_scenario
from mavconform.reference_impl.interop.harness import sample_plan
from mavconform.reference_impl.interop.mocklink import ITEMS, FailureMode, MockLinkVehicle
from mavconform.reference_impl.mission.items import MissionType
from mavconform.reference_impl.mission.results import Operation, OperationResult
from mavconform.reference_impl.net import FaultModel, McapCapture, SimNetwork
from mavconform.reference_impl.net.faults import DropWhere, MessageRule
from mavconform.reference_impl.net.sim import CaptureRecord
from mavconform.reference_impl.wire.codec import FrameDecoder
from mavconform.reference_impl.wire.frame import DecodeError

from .dialect_info import DialectInfo
from .fields import message_fields

FORMAT = "mavconform-exchange/1"
PROFILES = ("spec", "px4", "ardupilot")
GCS, VEHICLE = "gcs", "vehicle"
GCS2 = "gcs2"            # a handover exchange's second GCS
HANDOVER = "handover"    # the "profile" (folder) of the handover exchanges
LATENCY = 0.01           # s, one way, both directions
RESULT_BOUND = 120.0     # virtual s an operation may take before the scenario is broken
SETTLE_BOUND = 30.0      # virtual s for both ends to be idle and the link empty afterwards
REQUESTS = frozenset({"MISSION_REQUEST_INT", "MISSION_REQUEST"})


@dataclass
class Step:
    label: str
    start: float
    end: float
    result: str


@dataclass
class Rig:
    """What a scenario's script drives: the network, the GCS, the vehicle, the steps."""

    net: SimNetwork
    gcs: GcsNode
    vehicle: Any
    capture: McapCapture | None
    steps: list[Step] = field(default_factory=list)
    sent: list[tuple[str, Any]] = field(default_factory=list)   # (sender, decoded msg) in order

    @property
    def now(self) -> float:
        return self.net.clock.now()

    def op(self, label: str, start: Callable[[float], None], *,
           midway: Callable[["Rig"], bool] | None = None,
           then: Callable[[float], None] | None = None) -> OperationResult:
        """Run one GCS operation to its result, then until both ends are idle; `then` is
        called once `midway` holds (a cancel in the middle of an upload)."""
        if self.capture is not None:
            self.capture.mark(label, clock=self.net.clock)
        began, done = self.now, len(self.gcs.results)
        start(began)
        if midway is not None:
            if not self.net.run_until(lambda: midway(self), timeout=RESULT_BOUND):
                raise RuntimeError(f"{label}: the midway point never came")
            then(self.now)
        if not self.net.run_until(lambda: len(self.gcs.results) > done, timeout=RESULT_BOUND):
            raise RuntimeError(f"{label}: no result within {RESULT_BOUND:g} virtual s")
        result = self.gcs.results[done]
        if not self.net.run_until(self._idle, timeout=SETTLE_BOUND):
            raise RuntimeError(f"{label}: the ends were not idle {SETTLE_BOUND:g} virtual s after the result")
        self.steps.append(Step(label, began, self.now, _describe(result)))
        return result

    def _idle(self) -> bool:
        """Both ends idle and nothing on the link: the next step starts clean (a late copy of
        one operation's MISSION_ACK could otherwise pass for the next one's)."""
        return self.vehicle.server.is_idle() and not self.gcs.busy and self.net.in_flight() == 0


@dataclass(frozen=True)
class Scenario:
    name: str
    description: str
    script: Callable[[Rig], None]
    # fresh scripted drop rules per run (they count): (GCS -> vehicle, vehicle -> GCS)
    rules: Callable[[], tuple[tuple[MessageRule, ...], tuple[MessageRule, ...]]] = lambda: ((), ())
    faults_text: tuple[str, ...] = ()
    mocklink: FailureMode | None = None   # a MockLink failure injected in front of the vehicle



def _upload(t: MissionType, n: int = 3, label: str = "") -> Callable[[Rig], OperationResult]:
    items = sample_plan(n, t)
    return lambda rig: rig.op(label or f"upload {t.label} ({n} items)",
                              lambda now: rig.gcs.upload(t, items, now))


def _download(t: MissionType) -> Callable[[Rig], OperationResult]:
    return lambda rig: rig.op(f"download {t.label}", lambda now: rig.gcs.download(t, now))


def _seq(*scripts: Callable[[Rig], Any]) -> Callable[[Rig], None]:
    def run(rig: Rig) -> None:
        for script in scripts:
            script(rig)
    return run


def _drop(sender_types: frozenset[str], seq: int | None) -> MessageRule:
    """Drop the first message of those types (with that seq), once."""
    return DropWhere(lambda msg: msg._type in sender_types and (seq is None or msg.seq == seq), limit=1)


def _cancel_after_item(seq: int) -> Callable[[Rig], None]:
    def script(rig: Rig) -> None:
        items = sample_plan(5, MissionType.MISSION)
        rig.op("upload mission (5 items), cancelled by the GCS after it sent item 1",
               lambda now: rig.gcs.upload(MissionType.MISSION, items, now),
               midway=lambda r: any(who == GCS and msg._type in ("MISSION_ITEM_INT", "MISSION_ITEM")
                                    and msg.seq >= seq for who, msg in r.sent),
               then=lambda now: rig.gcs.cancel(now))
    return script


def _error_item(rig: Rig) -> None:
    items = sample_plan(3, MissionType.MISSION)
    items[1] = dataclasses.replace(items[1], command=65000)    # no MAV_CMD has this number
    rig.op("upload mission (3 items), item 1 with command 65000 (unknown)",
           lambda now: rig.gcs.upload(MissionType.MISSION, items, now))


def _no_space(rig: Rig) -> None:
    n = rig.vehicle.server.behaviour.capacity[MissionType.RALLY] + 1
    items = sample_plan(n, MissionType.RALLY)
    rig.op(f"upload rally ({n} items: one more than the vehicle holds)",
           lambda now: rig.gcs.upload(MissionType.RALLY, items, now))


def _set_current(command: bool) -> Callable[[Rig], None]:
    how = "MAV_CMD_DO_SET_MISSION_CURRENT" if command else "MISSION_SET_CURRENT"
    return _seq(_upload(MissionType.MISSION),
                lambda rig: rig.op(f"set current item 1 ({how})",
                                   lambda now: rig.gcs.set_current(1, now, via_command=command)))


# The answer to the first item request for seq 1 carries seq 2 (QGC MockLink's "incorrect
# sequence"), once: the GCS drops the out-of-sequence item and asks for 1 again.
OUT_OF_SEQUENCE_ONCE = FailureMode(
    "read-req1-bad-seq-once", "FailReadRequest1IncorrectSequence (first answer only)", Operation.DOWNLOAD,
    "incorrect sequence (seq + 1) in the first answer to request 1", True, ITEMS, 1, "bump-seq",
    first_only=True)


def scenarios() -> tuple[Scenario, ...]:
    """Every mission scenario, in the order files are listed (then `handover_scenarios()`)."""
    m, f, r = MissionType.MISSION, MissionType.FENCE, MissionType.RALLY
    out = [
        Scenario(f"upload-{t.label}", f"upload a 3-item {t.label} plan", _upload(t)) for t in (m, f, r)
    ] + [
        Scenario(f"download-{t.label}", f"upload a 3-item {t.label} plan, then download it",
                 _seq(_upload(t), _download(t))) for t in (m, f, r)
    ] + [
        Scenario("clear-mission", "upload a 3-item mission, then clear the mission",
                 _seq(_upload(m), lambda rig: rig.op("clear mission", lambda now: rig.gcs.clear(m, now)))),
        Scenario("clear-all", "upload a mission and a fence, then clear all plan types (MAV_MISSION_TYPE_ALL)",
                 _seq(_upload(m), _upload(f),
                      lambda rig: rig.op("clear all", lambda now: rig.gcs.clear(MissionType.ALL, now)))),
        Scenario("set-current", "upload a 3-item mission, then make item 1 current with MISSION_SET_CURRENT",
                 _set_current(False)),
        Scenario("set-current-command", "upload a 3-item mission, then make item 1 current with "
                 "MAV_CMD_DO_SET_MISSION_CURRENT", _set_current(True)),
        Scenario("cancel-by-gcs", "a 5-item mission upload the GCS cancels (MISSION_ACK OPERATION_CANCELLED) "
                 "once it has sent item 1", _cancel_after_item(1)),
        Scenario("cancel-by-vehicle", "a 4-item mission upload whose items stop reaching the vehicle after "
                 "item 0: the vehicle re-requests, then gives the upload up (spec: MISSION_ACK "
                 "OPERATION_CANCELLED to the GCS)", _upload(m, 4),
                 rules=lambda: ((DropWhere(lambda msg: msg._type in ("MISSION_ITEM_INT", "MISSION_ITEM")
                                           and msg.seq >= 1),), ()),
                 faults_text=("gcs -> vehicle: every MISSION_ITEM_INT / MISSION_ITEM with seq >= 1 lost",)),
        Scenario("error-ack", "a 3-item mission upload whose item 1 has an unknown command: the vehicle "
                 "refuses it with an error MISSION_ACK", _error_item),
        Scenario("no-space", "a rally upload one item larger than the vehicle holds: MISSION_ACK NO_SPACE",
                 _no_space),
        Scenario("out-of-sequence", "upload a 3-item mission, then download it; the vehicle's first answer "
                 "to request 1 carries seq 2, which the GCS drops before asking for item 1 again",
                 _seq(_upload(m), _download(m)), mocklink=OUT_OF_SEQUENCE_ONCE,
                 faults_text=("vehicle -> gcs: the first MISSION_ITEM(_INT) seq 1 rewritten to seq 2 "
                              "(QGC MockLink FailReadRequest1IncorrectSequence, once)",)),
        Scenario("loss-retry-upload", "a 3-item mission upload over a link that loses the first request "
                 "for item 1, the first item 2 and the first final MISSION_ACK: each is resent",
                 _upload(m), rules=lambda: (
                     (_drop(frozenset({"MISSION_ITEM_INT", "MISSION_ITEM"}), 2),),
                     (_drop(REQUESTS, 1), _drop(frozenset({"MISSION_ACK"}), None))),
                 faults_text=("gcs -> vehicle: the first MISSION_ITEM(_INT) seq 2 lost",
                              "vehicle -> gcs: the first MISSION_REQUEST(_INT) seq 1 and the first "
                              "MISSION_ACK lost")),
        Scenario("loss-retry-download", "upload a 3-item mission, then download it over a link that loses "
                 "the first MISSION_COUNT, the first request for item 1 and the first item 2: each is "
                 "asked for again", _seq(_upload(m), _download(m)), rules=lambda: (
                     (_drop(REQUESTS, 1),),
                     (_drop(frozenset({"MISSION_COUNT"}), None),
                      _drop(frozenset({"MISSION_ITEM_INT", "MISSION_ITEM"}), 2))),
                 faults_text=("gcs -> vehicle: the first MISSION_REQUEST(_INT) seq 1 lost",
                              "vehicle -> gcs: the first MISSION_COUNT and the first MISSION_ITEM(_INT) "
                              "seq 2 lost")),
    ]
    return tuple(out)


@dataclass(frozen=True)
class HandoverScenario:
    """A handover exchange: a shipped handover scenario (reference_impl/handover/scenarios),
    with `links` adjusting each GCS's link faults (by GCS name: (up, down) `LinkFaults` ->
    new ones) on top of the 10 ms one way every exchange has."""

    name: str
    description: str
    file: str                                   # shipped scenario name (`mavconform handover run NAME`)
    links: Callable[[str, Any, Any], tuple[Any, Any]] = lambda name, up, down: (up, down)
    faults_text: tuple[str, ...] = ()


def _invitation_lost(name: str, up: Any, down: Any) -> tuple[Any, Any]:
    """B never hears the vehicle's commands (the invitation and its resends)."""
    return (up, dataclasses.replace(down, drop=down.drop + ("COMMAND_LONG",))) if name == "B" else (up, down)


def handover_scenarios() -> tuple[HandoverScenario, ...]:
    """The authority handover exchanges: two GCSs (operator control, handover agents) and the
    scenario's vehicle (system manager, mission computer), the whole flight."""
    return (
        HandoverScenario("conformance", "the shipped `conformance` handover scenario: A takes control, uploads "
                         "the 3-waypoint flight and starts it; the vehicle enters the A+B lens and the mission "
                         "computer hands control from A to B (COMPLETED); the flight returns home under B",
                         "conformance"),
        HandoverScenario("conformance-invitation-lost", "the `conformance` scenario with every COMMAND_LONG from "
                         "the vehicle to B lost: B never hears the invitation (sent once a second), so the "
                         "handover is ABORTED when the vehicle leaves the A+B region before any grant, and A "
                         "keeps control to the end", "conformance", links=_invitation_lost,
                         faults_text=("vehicle -> gcs2 (B): every COMMAND_LONG lost",)),
    )


def handover_file(hs: HandoverScenario) -> HandoverScenarioFile:
    """The scenario file as `run_handover` flies it: every link `LATENCY` one way, then `hs.links`."""
    s = load_scenario(shipped_scenarios()[hs.file])
    gcs = []
    for g in s.gcs:
        up, down = hs.links(g.name, dataclasses.replace(g.up, delay=LATENCY),
                            dataclasses.replace(g.down, delay=LATENCY))
        gcs.append(dataclasses.replace(g, up=up, down=down))
    return dataclasses.replace(s, gcs=tuple(gcs))


class _HandoverCapture:
    """`run_scenario`'s capture hook: every record, its GCS addresses renamed to the
    transcript's roles, to the recorder and the MCAP capture; markers to the MCAP."""

    def __init__(self, roles: dict[str, str], recorder: "_Recorder", mcap: McapCapture | None) -> None:
        self.roles, self.recorder, self.mcap = roles, recorder, mcap

    def __call__(self, rec: CaptureRecord) -> None:
        rec = dataclasses.replace(rec, src=self.roles.get(str(rec.src), rec.src),
                                  dst=self.roles.get(str(rec.dst), rec.dst))
        self.recorder(rec)
        if self.mcap is not None:
            self.mcap(rec)

    def mark(self, label: str, *, clock: Any, level: str = "info") -> None:
        if self.mcap is not None:
            self.mcap.mark(label, clock=clock, level=level)


def run_handover(hs: HandoverScenario, dialect: DialectInfo, *, seed: int = 0,
                 mcap_path: Path | None = None) -> Exchange:
    """Fly one handover scenario in virtual time (scenario_run.run_scenario, seeded `seed`);
    the transcript (and the MCAP file)."""
    s = handover_file(hs)
    if len(s.gcs) != 2:
        raise ValueError(f"{hs.name}: a handover exchange has two GCSs, {hs.file} has {len(s.gcs)}")
    roles = {gcs_address(g): role for g, role in zip(s.gcs, (GCS, GCS2))}
    events: list[dict[str, Any]] = []
    capture = McapCapture(mcap_path, compress=False) if mcap_path is not None else None
    try:
        run = run_scenario(s, seed=seed, capture=_HandoverCapture(roles, _Recorder(events, dialect), capture))
    finally:
        if capture is not None:
            capture.close()
    if run.setup_failure is not None or not run.finished:
        raise RuntimeError(f"{hs.name}: the handover run did not finish ({run.setup_failure or run.stopped_by})")
    vcfg = vehicle_config(s)
    peers = {VEHICLE: {"sysid": vcfg.system, "compid": vcfg.component,
                       "what": f"reference vehicle with the {hs.file} scenario's system manager and mission computer"}}
    for g, role in zip(s.gcs, (GCS, GCS2)):
        cfg = gcs_config(s, g)
        peers[role] = {"sysid": cfg.system, "compid": cfg.component,
                       "what": f"GCS {g.name}" + (" (parent)" if g.name == s.parent else "")
                               + ": reference GCS with operator control and a handover agent"}
    transcript = {
        "format": FORMAT,
        "id": f"{HANDOVER}/{hs.name}",
        "scenario": hs.name,
        "profile": HANDOVER,
        "description": hs.description,
        "seed": seed,
        "peers": peers,
        "link": {"latency": LATENCY, "faults": list(hs.faults_text)},
        "steps": _handover_steps(run),
        "events": events,
    }
    return Exchange(transcript["id"], hs, HANDOVER, transcript)


def _handover_steps(run: ScenarioRun) -> list[dict[str, Any]]:
    """The run's phases as steps: the parent's setup, each handover, the flight."""
    started = run.mission_started if run.mission_started is not None else 0.0
    ended = run.flight_ended if run.flight_ended is not None else run.end
    steps = [{"label": f"setup: {run.scenario.parent} takes control, uploads the flight and starts it",
              "start": 0.0, "end": _t(started), "result": "ok"}]
    for h in run.handovers:
        r = h.result
        steps.append({"label": f"handover {h.number} {h.commander}->{h.partner} (region {h.region})",
                      "start": _t(r.started), "end": _t(r.finished),
                      "result": f"{r.outcome.name}, owner {h.owner_after}" + (f" ({r.detail})" if r.detail else "")})
    steps.append({"label": "flight", "start": _t(started), "end": _t(ended),
                  "result": "complete" if run.flight_complete else "not at its last waypoint"})
    return steps


# --- running a scenario ------------------------------------------------------------------

@dataclass
class Exchange:
    id: str
    scenario: "Scenario | HandoverScenario"
    profile: str                  # or HANDOVER
    transcript: dict[str, Any]


def run(scenario: Scenario, profile: str, dialect: DialectInfo, *, seed: int = 0,
        mcap_path: Path | None = None) -> Exchange:
    """Run one scenario against one profile's vehicle; the transcript (and the MCAP file)."""
    net = SimNetwork(seed=seed)
    vehicle = build_vehicle(parse_target(f"builtin:{profile}"), wall_clock=net.clock.wall)
    gcs = GcsNode(GcsConfig(), remote=VEHICLE, wall_clock=net.clock.wall)
    mocklink = MockLinkVehicle(vehicle, scenario.mocklink) if scenario.mocklink is not None else None
    net.add_node(VEHICLE, mocklink or vehicle)
    net.add_node(GCS, gcs)
    up, down = scenario.rules()
    net.connect(GCS, VEHICLE, a_to_b=FaultModel(delay=LATENCY, rules=up),
                b_to_a=FaultModel(delay=LATENCY, rules=down))
    vehicle.endpoint.add_address(GCS)      # it beats to the GCS from the start, as in-process targets do
    # uncompressed: committed bytes must not depend on the installed zstandard's version
    capture = McapCapture(mcap_path, compress=False) if mcap_path is not None else None
    events: list[dict[str, Any]] = []
    recorder = _Recorder(events, dialect)
    rig = Rig(net, gcs, vehicle, capture)
    recorder.rig = rig
    net.add_capture(recorder)
    if capture is not None:
        net.add_capture(capture)
    try:
        if not net.run_until(lambda: gcs.connected, timeout=5.0):
            raise RuntimeError(f"{profile}: the vehicle sent no HEARTBEAT within 5 s")
        if mocklink is not None:
            mocklink.armed = True
        scenario.script(rig)
    finally:
        if capture is not None:
            capture.close()
    cfg = gcs.config
    transcript = {
        "format": FORMAT,
        "id": f"{profile}/{scenario.name}",
        "scenario": scenario.name,
        "profile": profile,
        "description": scenario.description,
        "seed": seed,
        "peers": {
            GCS: {"sysid": cfg.system, "compid": cfg.component, "what": "reference GCS (reference_impl/gcs.py)"},
            VEHICLE: {"sysid": vehicle.config.system, "compid": vehicle.config.component,
                      "what": f"reference vehicle, builtin:{profile} profile"},
        },
        "link": {"latency": LATENCY, "faults": list(scenario.faults_text)},
        "steps": [{"label": s.label, "start": _t(s.start), "end": _t(s.end), "result": s.result}
                  for s in rig.steps],
        "events": events,
    }
    return Exchange(transcript["id"], scenario, profile, transcript)


class _Recorder:
    """The capture hook behind the transcript: each sent datagram's frames once, and which
    of them the link lost."""

    def __init__(self, events: list[dict[str, Any]], dialect: DialectInfo) -> None:
        self.events = events
        self.dialect = dialect
        self.by_id = {m.id: m for m in dialect.messages}
        self.decoder = FrameDecoder(dialect=dialect.module)
        self.pending: dict[tuple[str, str, bytes], list[dict[str, Any]]] = {}
        self.rig: Rig | None = None

    def __call__(self, rec: CaptureRecord) -> None:
        key = (str(rec.src), str(rec.dst), rec.data)
        if rec.kind == "tx":
            rows = [self._row(rec, item) for item in self.decoder.feed(rec.data)]
            self.events.extend(rows)
            self.pending.setdefault(key, []).append(rows)
        elif rec.kind == "drop":
            queued = self.pending.get(key)
            if queued:
                for row in queued.pop(0):
                    row["lost"] = True
            else:
                self.events.extend(dict(self._row(rec, item), lost=True) for item in self.decoder.feed(rec.data))
        elif rec.kind == "rx":
            queued = self.pending.get(key)
            if queued:
                queued.pop(0)

    def _row(self, rec: CaptureRecord, item: Any) -> dict[str, Any]:
        row: dict[str, Any] = {"t": _t(rec.time), "from": str(rec.src), "to": str(rec.dst), "lost": False}
        if isinstance(item, DecodeError):
            row.update({"msg": "DECODE_ERROR", "error": item.reason, "hex": item.raw.hex()})
            return row
        info = self.by_id.get(item.msgid)
        if self.rig is not None:
            self.rig.sent.append((str(rec.src), item.msg))
        row.update({"msg": item.name, "msgid": item.msgid, "sysid": item.src_system, "compid": item.src_component,
                    "seq": item.seq, "version": item.version,
                    "fields": message_fields(item.msg, info) if info is not None else {},
                    "hex": item.raw.hex()})
        return row


def _t(seconds: float) -> float:
    return round(seconds, 6)


def _describe(result: OperationResult) -> str:
    return "ok" if result.ok else result.summary()
