"""Authenticity of operator control: per-GCS MAVLink 2 signing keys, in virtual time.

The vehicle knows GCS A (201) and GCS B (202) by their own keys (a `Roster`). One test per
way of faking authority: an unsigned request while signatures are required, a frame signed
with a key the vehicle does not hold, a genuine frame of the owner recorded and played
again, GCS B signing with its own key while writing A's system id, and a system outside the
roster. Then a Hypothesis property: an attacker mixing all of these at random times while A
and B hand over control changes nothing the vehicle does.

Each check is a function of how the vehicle is built, and each is also run on a vehicle
whose gate is deliberately weakened in one way (`WEAKENED`), where it must fail: none of
these tests passes by testing nothing.
"""

from __future__ import annotations

from collections import Counter
from typing import Any, Callable, Iterable

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from mavconform.reference_impl.endpoint import MavlinkEndpoint
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.handover import control_messages as cm
from mavconform.reference_impl.handover.authenticity import KnownGcs, Roster
from mavconform.reference_impl.handover.control_client import ClientConfig, always
from mavconform.reference_impl.handover.control_manager import ManagerConfig
from mavconform.reference_impl.handover.control_results import ControlChanged, ControlOutcome as O, Decision
from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.net import FaultModel, SimNetwork
from mavconform.reference_impl.net.sim import CaptureRecord
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleConfig, VehicleNode
from mavconform.reference_impl.wire import FrameDecoder, FrameEncoder
from mavconform.reference_impl.wire.dialect import mavlink as d
from mavconform.reference_impl.wire.frame import Frame, SignatureVerdict
from mavconform.reference_impl.wire.signing import SigningKey

from ..rigs import Fleet
from .gcs_keys import A, B, KEY_A, KEY_B, KEY_X, STRANGER

VEHICLE = (1, 1)
COMP = d.MAV_COMP_ID_MISSIONPLANNER
ROSTER = Roster((KnownGcs(A, KEY_A, "A"), KnownGcs(B, KEY_B, "B")))
LATENCY = FaultModel(delay=0.02)
HOME = (47.397742, 8.545594)


def plan(n: int, north: float = 100.0) -> list[MissionItem]:
    return [MissionItem(i, 3, int(Cmd.NAV_WAYPOINT), x=round((HOME[0] + i * north / 111_195.0) * 1e7),
                        y=round(HOME[1] * 1e7), z=20.0) for i in range(n)]


# --- the rig -------------------------------------------------------------------------------
Weaken = Callable[[VehicleNode], None]


def fleet(*, require: bool = True, open_when_unowned: bool = False, weaken: Weaken | None = None,
          seed: int = 5) -> Fleet:
    """The vehicle (operator control on, the A/B roster) and GCSs A and B, each signing with
    its own key and allowing takeover when asked; `weaken` breaks the vehicle's gate first."""
    net = SimNetwork(seed=seed)
    config = VehicleConfig(control=ManagerConfig(owner_loss_timeout=5.0, open_when_unowned=open_when_unowned),
                           roster=ROSTER, require_signature=require)
    vehicle = VehicleNode(config, wall_clock=net.clock.wall)
    if weaken is not None:
        weaken(vehicle)
    net.add_node("vehicle", vehicle)
    sessions = {}
    for name, sysid, k in (("A", A, KEY_A), ("B", B, KEY_B)):
        gcs = GcsNode(GcsConfig(system=sysid, signing=k, control=ClientConfig()), remote="vehicle",
                      wall_clock=net.clock.wall, control_policy=always(Decision.ALLOW))
        net.add_node(name, gcs)
        net.connect(name, "vehicle", a_to_b=LATENCY, b_to_a=LATENCY.copy())
        sessions[name] = GcsSession(net, gcs)
    for session in sessions.values():
        session.wait_for_target(5.0)
    return Fleet(net, vehicle, sessions)


def other_gcs(f: Fleet, name: str, sysid: int, signing: SigningKey | None) -> GcsSession:
    """One more GCS on its own link, aimed at the vehicle without waiting to hear it (a
    vehicle that drops its frames never learns where it is, so never answers)."""
    node = GcsNode(GcsConfig(system=sysid, target=VEHICLE, signing=signing, control=ClientConfig()),
                   remote="vehicle", wall_clock=f.net.clock.wall)
    f.net.add_node(name, node)
    f.net.connect(name, "vehicle", a_to_b=LATENCY, b_to_a=LATENCY.copy())
    return GcsSession(f.net, node)


def command(cmd: int, *params: float) -> Any:
    p = [*params, 0, 0, 0, 0, 0, 0, 0][:7]
    return d.MAVLink_command_long_message(*VEHICLE, cmd, 0, *p)


def release(sysid: int) -> Any:
    return cm.request_command(VEHICLE, cm.ACTION_RELEASE, False, 10.0, sysid)


def request(sysid: int, allow: bool = False) -> Any:
    return cm.request_command(VEHICLE, cm.ACTION_REQUEST, allow, 10.0, sysid)


def dropped(f: Fleet) -> Counter[str]:
    return f.vehicle.endpoint.rejections


# --- deliberately weakened gates (negative controls) --------------------------------------
class _SignedIsEnough(MavlinkEndpoint):
    """Trusts any signed frame: a failed check is let through (unsigned ones still are not)."""

    def _signature_acceptable(self, frame: Frame) -> bool:
        return super()._signature_acceptable(frame) or frame.signature is SignatureVerdict.INVALID


class _NoStreams(dict):
    def __setitem__(self, k: Any, v: Any) -> None:   # remembers no stream: no replay protection
        pass


class _Forgetful(FrameDecoder):
    """Checks signatures but keeps no per-stream timestamps (only the one-minute rule is left)."""

    def _keyed(self, k: SigningKey) -> Any:
        mav = super()._keyed(k)
        mav.signing.stream_timestamps = _NoStreams()
        return mav


class _AnyRosterKey(FrameDecoder):
    """Accepts a signature made with any key in the roster, whatever system the frame claims."""

    def _decode_one(self, chunk: bytes, iflags: int) -> Any:
        each = self.__dict__.setdefault("_each", {})
        for sysid in self.keyring:
            one = each.setdefault(sysid, FrameDecoder(signing=self.keyring.key_for(sysid),
                                                      wall_clock=self._wall_clock))
            got = one._decode_one(chunk, iflags)
            if isinstance(got, Frame) and got.signature is SignatureVerdict.VALID:
                return got
        return super()._decode_one(chunk, iflags)


def accepts_unsigned(v: VehicleNode) -> None:
    v.endpoint.require_signature = False


def trusts_any_signed_frame(v: VehicleNode) -> None:
    v.endpoint.__class__ = _SignedIsEnough


def no_replay_protection(v: VehicleNode) -> None:
    v.endpoint.decoder.__class__ = _Forgetful


def any_roster_key(v: VehicleNode) -> None:
    v.endpoint.decoder.__class__ = _AnyRosterKey


def no_roster_gate(v: VehicleNode) -> None:
    v.gate = None


# --- the attacker --------------------------------------------------------------------------
class Attacker:
    """A node on the vehicle's network that sends frames to it: `inject` now, or `plan`ned
    (at, kind, message, pick) at virtual times. Kinds say how the frame is made; each has the
    label the vehicle must drop it under (`expected`). Replays and reflections pick (by
    `pick`) from genuine frames recorded on the other links (`record`)."""

    ENCODED = {   # kind: (claimed system, key or None, label)
        "unsigned as A": (A, None, "unsigned"),
        "unsigned as B": (B, None, "unsigned"),
        "unsigned stranger": (STRANGER, None, "unsigned"),
        "stranger's own key": (STRANGER, KEY_X, "unknown key"),
        "B's key as A": (A, KEY_B, "bad signature"),
        "A's key as B": (B, KEY_A, "bad signature"),
        "foreign key as A": (A, KEY_X, "bad signature"),
    }
    KINDS = (*ENCODED, "replay", "reflect")
    MESSAGES = ("request", "request allowing takeover", "release", "mission start", "clear",
                "count", "set current")

    def __init__(self, net: SimNetwork, attack_plan: Iterable[tuple[float, str, str, int]] = (), *,
                 muted: bool = False) -> None:
        wall = net.clock.wall
        self.encoders = {kind: FrameEncoder(sysid, COMP, signing=k, wall_clock=wall)
                         for kind, (sysid, k, _) in self.ENCODED.items()}
        self.plan = sorted(attack_plan)
        self.muted = muted
        self.expected: Counter[str] = Counter()
        self.recorded: list[bytes] = []    # genuine GCS frames the vehicle received
        self.reflected: list[bytes] = []   # the vehicle's frames to the GCSs
        self._out: list[tuple[bytes, str]] = []
        net.add_node("attacker", self)
        net.connect("attacker", "vehicle", a_to_b=FaultModel(delay=0.001))
        net.add_capture(self.record)

    def record(self, r: CaptureRecord) -> None:
        if r.kind == "rx" and r.dst == "vehicle" and r.src in ("A", "B"):
            self.recorded.append(r.data)
        elif r.kind == "rx" and r.src == "vehicle" and r.dst in ("A", "B"):
            self.reflected.append(r.data)

    def inject(self, data: bytes, label: str) -> None:
        self._out.append((data, "vehicle"))
        self.expected[label] += 1

    def message(self, name: str, sysid: int) -> Any:
        return {
            "request": lambda: request(sysid),
            "request allowing takeover": lambda: request(sysid, allow=True),
            "release": lambda: release(sysid),
            "mission start": lambda: command(Cmd.MISSION_START),
            "clear": lambda: d.MAVLink_mission_clear_all_message(*VEHICLE, 0),
            "count": lambda: d.MAVLink_mission_count_message(*VEHICLE, 5, 0),
            "set current": lambda: d.MAVLink_mission_set_current_message(*VEHICLE, 1),
        }[name]()

    # DatagramNode
    def datagram_received(self, data: bytes, source: Any, now: float) -> None:
        pass

    def poll(self, now: float) -> None:
        while self.plan and self.plan[0][0] <= now:
            _, kind, name, pick = self.plan.pop(0)
            if self.muted:
                continue
            if kind in self.ENCODED:
                sysid, _, label = self.ENCODED[kind]
                self.inject(self.encoders[kind].encode(self.message(name, sysid)), label)
            else:
                pool = self.recorded if kind == "replay" else self.reflected
                if pool:
                    self.inject(pool[pick % len(pool)], "replayed" if kind == "replay" else "unknown key")

    def next_deadline(self) -> float | None:
        return self.plan[0][0] if self.plan else None

    def take_outgoing(self) -> list[tuple[bytes, Any]]:
        out, self._out = self._out, []
        return out


# --- one test per way of faking authority --------------------------------------------------
def check_unsigned_request_changes_nothing(weaken: Weaken | None = None) -> None:
    """Signatures required: a GCS without its key (system B, unsigned) asks for control of an
    unowned vehicle, and an unsigned frame claiming A releases A's control. Both are dropped
    and counted; nobody answers them; control stays where it was."""
    f = fleet(weaken=weaken)
    unsigned_b = other_gcs(f, "unsigned B", B, None)
    got = unsigned_b.request_control()
    assert got.outcome is O.TIMEOUT and f.vehicle.owner == 0, (got, f.vehicle.owner)
    assert f.sessions["A"].request_control().outcome is O.GRANTED
    unsigned_a = other_gcs(f, "unsigned A", A, None)
    unsigned_a.gcs.send(release(A))
    f.net.run_for(3.0)
    assert f.vehicle.owner == A
    assert dropped(f)["unsigned"] >= 5 and set(dropped(f)) == {"unsigned"}   # their HEARTBEATs too
    assert not unsigned_b.gcs.received and not unsigned_a.gcs.received


def check_unknown_key_is_refused(weaken: Weaken | None = None) -> None:
    """A frame signed with a key the vehicle does not hold: claiming a roster GCS (B) it is a
    bad signature, claiming a system with no key (66) an unknown key. Neither gets control."""
    f = fleet(weaken=weaken)
    fake_b = other_gcs(f, "fake B", B, KEY_X)
    stranger = other_gcs(f, "stranger", STRANGER, KEY_X)
    assert fake_b.request_control().outcome is O.TIMEOUT and f.vehicle.owner == 0
    assert stranger.request_control().outcome is not O.GRANTED and f.vehicle.owner == 0
    assert dropped(f)["bad signature"] >= 3 and dropped(f)["unknown key"] >= 3
    assert f.sessions["B"].request_control().outcome is O.GRANTED   # the real B is not locked out


def check_replayed_owner_frames_do_nothing(weaken: Weaken | None = None) -> None:
    """A's genuine MISSION_CLEAR_ALL and its release, recorded on the link and played again
    later from elsewhere, while A holds control of a 3-item plan: neither is executed."""
    f = fleet(weaken=weaken)
    a = f.sessions["A"]
    attacker = Attacker(f.net)
    assert a.request_control().ok
    assert a.clear(MissionType.MISSION).ok
    assert a.upload(MissionType.MISSION, plan(3)).ok
    assert a.release_control().outcome is O.RELEASED
    assert a.request_control().ok and f.vehicle.owner == A
    f.net.run_for(5.0)
    raw = FrameDecoder()
    recorded = [(data, [x.msg for x in raw.feed(data)][0]) for data in attacker.recorded]
    clear = next(data for data, msg in recorded if msg._type == "MISSION_CLEAR_ALL")
    released = next(data for data, msg in recorded if cm.is_request_control(msg) and msg.param1 == 0)
    for data in (clear, released):
        attacker.inject(data, "replayed")
    f.net.run_for(2.0)
    assert f.vehicle.owner == A, f.vehicle.owner
    assert len(f.vehicle.store.items(MissionType.MISSION)) == 3
    assert dropped(f) == {"replayed": 2}
    assert a.upload(MissionType.MISSION, plan(4)).ok               # A is not locked out


def check_spoofed_sysid_is_refused(weaken: Weaken | None = None) -> None:
    """GCS B, with its own valid key, writes A's system id into frames that would release A's
    control, clear A's plan and start the mission: bad signatures, all dropped."""
    f = fleet(weaken=weaken)
    a = f.sessions["A"]
    assert a.request_control().ok and a.upload(MissionType.MISSION, plan(3)).ok
    b_as_a = other_gcs(f, "B as A", A, KEY_B)
    for msg in (release(A), d.MAVLink_mission_clear_all_message(*VEHICLE, 0), command(Cmd.MISSION_START)):
        b_as_a.gcs.send(msg)
    f.net.run_for(3.0)
    v = f.vehicle
    assert v.owner == A and len(v.store.items(MissionType.MISSION)) == 3 and not v.flight.flying
    assert dropped(f)["bad signature"] >= 3 and set(dropped(f)) == {"bad signature"}
    assert a.upload(MissionType.MISSION, plan(2)).ok                 # A is not locked out
    assert f.sessions["B"].request_control().outcome is O.GRANTED    # B, as itself, may ask


def check_stranger_never_gains_control(weaken: Weaken | None = None) -> None:
    """Unsigned frames accepted, control open to all while unowned: still, system 67 (not in
    the roster, unsigned) is told DENIED and refused every write, and system 66 signing with
    a key of its own is dropped. Roster GCSs are served as before."""
    f = fleet(require=False, open_when_unowned=True, weaken=weaken)
    stranger = other_gcs(f, "stranger", 67, None)
    got = stranger.request_control()
    assert (got.outcome, got.result) == (O.REJECTED, d.MAV_RESULT_DENIED) and f.vehicle.owner == 0, got
    refused = stranger.upload(MissionType.MISSION, plan(2))
    assert refused.nack == MissionResult.DENIED, refused
    keyed = other_gcs(f, "keyed stranger", STRANGER, KEY_X)
    assert keyed.request_control().outcome is O.TIMEOUT and f.vehicle.owner == 0
    assert dropped(f)["unknown key"] >= 3
    assert f.vehicle.gate.refused[67] >= 2
    assert any("system 67 is not in the roster" in e for e in f.vehicle.events)
    assert f.sessions["B"].upload(MissionType.MISSION, plan(2)).ok   # open while unowned, to the roster
    assert f.sessions["B"].request_control().outcome is O.GRANTED


CASES = {
    "unsigned request": (check_unsigned_request_changes_nothing, accepts_unsigned),
    "unknown key": (check_unknown_key_is_refused, trusts_any_signed_frame),
    "replay": (check_replayed_owner_frames_do_nothing, no_replay_protection),
    "spoofed sysid": (check_spoofed_sysid_is_refused, any_roster_key),
    "stranger": (check_stranger_never_gains_control, no_roster_gate),
}


@pytest.mark.parametrize("case", CASES)
def test_authenticity(case: str) -> None:
    check, _ = CASES[case]
    check()


@pytest.mark.parametrize("case", CASES)
def test_authenticity_check_fails_on_a_weakened_gate(case: str) -> None:
    """The negative control: the same check on a vehicle whose gate lacks one defence."""
    check, weaken = CASES[case]
    with pytest.raises(AssertionError):
        check(weaken)


def test_the_vehicle_signs_what_it_sends_each_gcs_with_that_gcss_key():
    """Per-link keys: every frame the vehicle sends A checks out with A's key (and link id)
    and not with B's, and the other way round; so neither GCS can forge what the other hears."""
    f = fleet()
    heard: dict[str, list[bytes]] = {"A": [], "B": []}
    f.net.add_capture(lambda r: heard[r.dst].append(r.data) if r.kind == "rx" and r.src == "vehicle" else None)
    assert f.sessions["A"].request_control().ok
    f.net.run_for(3.0)
    for name, mine, other in (("A", KEY_A, KEY_B), ("B", KEY_B, KEY_A)):
        assert len(heard[name]) >= 6
        own = FrameDecoder(signing=mine, wall_clock=f.net.clock.wall)
        theirs = FrameDecoder(signing=other, wall_clock=f.net.clock.wall)
        for data in heard[name]:
            assert data[-13] == mine.link_id
            assert [x.authenticity for x in own.feed(data)] == ["ok"]
            assert [x.authenticity for x in theirs.feed(data)] == ["bad signature"]
    assert not f.vehicle.endpoint.rejections


# --- an attacker during a handover ---------------------------------------------------------
requests = st.tuples(st.just("request"), st.sampled_from("AB"), st.booleans())
# A takes control first; then mostly requests (B's are forwarded to A, who allows: a handover)
steps = st.lists(st.one_of(
    requests, requests,
    st.tuples(st.just("release"), st.sampled_from("AB")),
    st.tuples(st.just("upload"), st.sampled_from("AB")),
    st.tuples(st.just("wait"), st.floats(0.1, 8.0))), min_size=1, max_size=6).map(
        lambda rest: [("request", "A", False), *rest])
attacks = st.lists(st.tuples(st.floats(0.0, 40.0), st.sampled_from(Attacker.KINDS),
                             st.sampled_from(Attacker.MESSAGES), st.integers(0, 10_000)),
                   min_size=1, max_size=25)


def handover_under_attack(program: list[tuple], attack_plan: list[tuple], weaken: Weaken | None = None, *,
                          counted: bool = True) -> Attacker:
    """Run A and B's `program` twice from the same seed: once with the attacker silent, once
    injecting its plan. The attacked vehicle must do exactly what the quiet one did (same
    control changes, plans, flight, and frames to A and B at the same times: an assertion
    saying "attacker effect"), and (`counted`) have dropped and counted every injected frame
    under its own reason."""
    runs = []
    for muted in (True, False):
        f = fleet(weaken=weaken, seed=11)
        start = f.net.clock.now()
        attacker = Attacker(f.net, [(start + at, *rest) for at, *rest in attack_plan], muted=muted)
        for n, step in enumerate(program):
            s = f.sessions[step[1]] if step[0] != "wait" else None
            if step[0] == "request":
                s.request_control(allow_takeover=step[2])
            elif step[0] == "release":
                s.release_control()
            elif step[0] == "upload":
                s.upload(MissionType.MISSION, plan(2 + n))
            else:
                f.net.run_for(step[1])
        f.net.run_for(max(0.0, start + 42.0 - f.net.clock.now()))
        runs.append((f, attacker))
    (quiet, _), (attacked, attacker) = runs
    v, q = attacked.vehicle, quiet.vehicle
    owners = [c.owner for c in v.control_events if isinstance(c, ControlChanged)]
    assert set(owners) <= {0, A, B}, f"attacker effect: control went to {owners}"
    assert v.events == q.events, "attacker effect: the vehicle did something else"
    assert list(v.control_events) == list(q.control_events), "attacker effect: control moved otherwise"
    for t in MissionType.MISSION, MissionType.FENCE, MissionType.RALLY:
        assert v.store.items(t) == q.store.items(t), f"attacker effect: {t.label} differs"
    assert (v.flight.flying, v.owner) == (q.flight.flying, q.owner), "attacker effect: flight or owner differs"
    for name in "AB":
        got, want = attacked.gcs(name), quiet.gcs(name)
        assert [bytes(m.get_msgbuf()) for m in got.received] == [bytes(m.get_msgbuf()) for m in want.received], \
            f"attacker effect: GCS {name} was told something else"
        assert (got.results, got.control_results) == (want.results, want.control_results), \
            f"attacker effect: GCS {name}'s operations ended otherwise"
    if counted:
        assert v.endpoint.rejections == attacker.expected, "an injected frame was not dropped under its reason"
    return attacker


@settings(deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(program=steps, attack_plan=attacks)
def test_an_attacker_changes_nothing_while_a_and_b_hand_over(program, attack_plan):
    """Unsigned frames, a stranger's key, B's key under A's id, a foreign key, replays of
    A's and B's recorded frames and reflections of the vehicle's own, any message, at any
    time: none gets through, each is counted, and the handover goes as it would alone."""
    handover_under_attack(program, attack_plan)


@pytest.mark.parametrize("weaken", [accepts_unsigned, trusts_any_signed_frame, no_replay_protection,
                                    any_roster_key], ids=lambda w: w.__name__)
def test_the_attack_property_fails_on_a_weakened_gate(weaken):
    """The property finds an attack that gets through each weakened gate and changes what the
    vehicle does (not merely the drop counts)."""
    @settings(deadline=None, max_examples=200, phases=[Phase.generate], report_multiple_bugs=False, derandomize=True,
              database=None, suppress_health_check=list(HealthCheck))
    @given(program=steps, attack_plan=attacks)
    def weakened(program, attack_plan):
        handover_under_attack(program, attack_plan, weaken, counted=False)
    with pytest.raises(AssertionError, match="attacker effect"):
        weakened()
