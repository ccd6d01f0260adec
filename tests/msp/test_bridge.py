"""`mavconform bridge`: the reference GCS through the bridge to builtin:msp in virtual time (upload,
download, clear, refusals by the mapping table, a waypoint that did not store, a flight
controller that falls silent, set-current, MISSION_CURRENT), and the command over real loopback
with the MAVLink suite against it."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import pytest

from mavconform.conformance import expectations
from mavconform.reference_impl.gcs import GcsNode
from mavconform.reference_impl.mission.constants import Cmd, MissionResult
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.mission.results import Outcome
from mavconform.reference_impl.msp.bridge import MspBridge, MspLink
from mavconform.reference_impl.msp.commands import Waypoint
from mavconform.reference_impl.msp.flight_controller import MspFlightController
from mavconform.reference_impl.msp.frame import MspFrame
from mavconform.reference_impl.msp.jobs import EMPTY
from mavconform.reference_impl.msp.mapping import ROW_IDS
from mavconform.reference_impl.msp.nodes import MspServerNode
from mavconform.reference_impl.net.clock import SimClock
from mavconform.reference_impl.net.sim import SimNetwork

MISSION = MissionType.MISSION


def _plan(n: int, alt: float = 20.5) -> list[MissionItem]:
    return [MissionItem(i, 3, Cmd.NAV_WAYPOINT, 0, 0, 0, 0, 473977420 + 100 * i, 85455940, alt + i, 0, 1)
            for i in range(n)]


class _Rig:
    def __init__(self, controller: MspFlightController | None = None) -> None:
        self.net = SimNetwork(seed=1, clock=SimClock())
        self.fc = MspServerNode(controller)
        self.link = MspLink()
        self.bridge = MspBridge(self.link)
        self.gcs = GcsNode(remote="bridge")
        for name, node in (("gcs", self.gcs), ("bridge", self.bridge), ("link", self.link), ("fc", self.fc)):
            self.net.add_node(name, node)
        self.net.connect("gcs", "bridge")
        self.net.connect("link", "fc")
        self.link.peer = "fc"
        assert self.net.run_until(lambda: self.gcs.connected, timeout=5)

    def do(self, op: str, *args):
        getattr(self.gcs, op)(*args, self.net.clock.now())
        assert self.net.run_until(lambda: not self.gcs.busy, timeout=60)
        return self.gcs.results[-1]

    def texts(self) -> list[str]:
        return [m.text for m in self.gcs.received if m._type == "STATUSTEXT"]


def test_upload_download_and_clear_reach_the_flight_controller() -> None:
    rig = _Rig()
    plan = _plan(4)
    assert rig.do("upload", MISSION, plan).outcome is Outcome.SUCCESS
    stored = rig.fc.controller.waypoints
    assert [(w.number, w.action, w.lat, w.alt, w.flag) for w in stored] == \
        [(i + 1, 1, 473977420 + 100 * i, 2050 + 100 * i, 0xA5 if i == 3 else 0) for i in range(4)]
    rig.fc.controller.waypoints = rig.fc.controller.waypoints[:3] + [replace(stored[3], alt=9900)]  # changed by another MSP client
    got = rig.do("download", MISSION)
    assert got.outcome is Outcome.SUCCESS and list(got.items) == plan[:3] + [replace(plan[3], z=99.0)]
    assert rig.do("clear", MISSION).outcome is Outcome.SUCCESS
    assert rig.fc.controller.waypoints == [EMPTY]
    assert rig.do("download", MISSION).items == ()


@pytest.mark.parametrize("plan,mission_type,code", [
    ([replace(it, param2=2.0) for it in _plan(2)], MISSION, MissionResult.INVALID_PARAM2),
    (_plan(2, alt=20.555), MISSION, MissionResult.INVALID_PARAM7),
    ([replace(it, command=Cmd.NAV_TAKEOFF) for it in _plan(1)], MISSION, MissionResult.UNSUPPORTED),
    ([MissionItem(0, 2, Cmd.NAV_RETURN_TO_LAUNCH)], MISSION, MissionResult.UNSUPPORTED),   # MSP's "no mission"
    (_plan(121), MISSION, MissionResult.NO_SPACE),
    ([MissionItem(0, 0, 5100, x=1, y=1, mission_type=MissionType.RALLY)], MissionType.RALLY, MissionResult.UNSUPPORTED),
])
def test_what_msp_cannot_hold_is_refused_and_nothing_is_written(plan, mission_type, code) -> None:
    rig = _Rig()
    assert rig.do("upload", MISSION, _plan(2)).outcome is Outcome.SUCCESS
    before = list(rig.fc.controller.waypoints)
    result = rig.do("upload", mission_type, plan)
    assert result.outcome is Outcome.NACK and result.nack == code
    assert rig.fc.controller.waypoints == before


class _DropsP1(MspFlightController):
    """Acknowledges every waypoint and stores a HOLD_TIME's seconds as 0 (INAV-style silent loss)."""

    def store(self, wp: Waypoint) -> None:
        super().store(replace(wp, p1=0) if wp.action == 3 else wp)


def test_a_waypoint_that_did_not_store_fails_the_upload_and_the_old_mission_is_put_back() -> None:
    rig = _Rig(_DropsP1())
    assert rig.do("upload", MISSION, _plan(2)).outcome is Outcome.SUCCESS
    before = list(rig.fc.controller.waypoints)
    hold = _plan(3)
    hold[1] = MissionItem(1, 3, Cmd.NAV_LOITER_TIME, 12.0, 0, 0, 0, 473977520, 85455940, 21.5, 0, 1)
    result = rig.do("upload", MISSION, hold)
    assert result.outcome is Outcome.NACK and result.nack == MissionResult.ERROR
    assert "waypoint 2 did not store as writ" in " ".join(rig.texts())
    rig.net.run_for(1.0)
    assert rig.fc.controller.waypoints == before
    assert rig.do("download", MISSION).items == tuple(_plan(2))


class _FallsSilent(MspFlightController):
    """Stops answering once `after` more waypoints have been written."""

    after = 10 ** 6

    def handle(self, frame: MspFrame) -> list[MspFrame]:
        if frame.command == 209:
            self.after -= 1
        return [] if self.after < 0 else super().handle(frame)


def test_a_flight_controller_silent_mid_upload_is_an_error_and_nothing_half_written_is_served() -> None:
    fc = _FallsSilent()
    rig = _Rig(fc)
    assert rig.do("upload", MISSION, _plan(2)).outcome is Outcome.SUCCESS
    fc.after = 3
    started = rig.net.clock.now()
    result = rig.do("upload", MISSION, _plan(6))
    assert result.outcome is Outcome.NACK and result.nack == MissionResult.ERROR
    assert rig.net.clock.now() - started < 10                       # bounded: retries, then the error
    assert any("did not answer MSP_SET_WP" in t for t in rig.texts())
    download = rig.do("download", MISSION)                          # still silent: refused, not the half list
    assert download.outcome is Outcome.NACK and download.nack == MissionResult.ERROR
    fc.after = 10 ** 6                                              # it answers again, holding 3 of 6, unflagged
    assert len(fc.waypoints) == 3 and not fc.valid
    assert rig.do("download", MISSION).items == ()
    assert any("unfinished" in t for t in rig.texts())


def test_set_current_is_refused_on_the_ground_and_mission_current_follows_nav_status() -> None:
    rig = _Rig()
    assert rig.do("upload", MISSION, _plan(3)).outcome is Outcome.SUCCESS
    rig.gcs.set_current(2, rig.net.clock.now(), via_command=True)
    rig.net.run_for(3.0)
    acks = [m for m in rig.gcs.received if m._type == "COMMAND_ACK"]
    assert acks and acks[-1].result == 1                             # MAV_RESULT_TEMPORARILY_REJECTED
    assert "set current refused by the flight controller" in rig.texts()
    rig.fc.controller.nav_status = bytes((3, 0, 1, 3, 0, 0, 0))     # flying: active waypoint number 3
    rig.net.run_for(2.5)
    currents = [m.seq for m in rig.gcs.received if m._type == "MISSION_CURRENT"]
    assert currents[-1] == 2


def test_every_entry_of_the_bridge_expectations_is_a_row_of_the_mapping() -> None:
    entries = expectations.load("msp-bridge").entries
    assert entries and all(e.variant in ROW_IDS for e in entries)


@pytest.mark.udp
def test_the_bridge_command_serves_the_mavlink_suite(tmp_path) -> None:
    bridge = subprocess.Popen([sys.executable, "-m", "mavconform", "bridge", "--msp", "builtin",
                               "--listen", "udpin:0", "--duration", "120"], stdout=subprocess.PIPE, text=True)
    try:
        line = bridge.stdout.readline()
        assert "listening on udp:127.0.0.1:" in line, line
        port = line.split("udp:127.0.0.1:")[1].split(";")[0]
        assert "0 waypoints, mission valid 0, 120 at most" in bridge.stdout.readline()
        run = subprocess.run([sys.executable, "-m", "mavconform", "run", "--target", f"udp:127.0.0.1:{port}",
                              "--clauses", "MIS.UP.01,MIS.DN.0[12],MIS.CLR.01,MIS.CUR.05", "--expect", "msp-bridge",
                              "--report-dir", str(tmp_path), "-q"], capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
        assert "known-deviation        1" in run.stdout
    finally:
        bridge.terminate()
        bridge.wait(timeout=10)


@pytest.mark.parametrize("argv,message", [
    (["--msp", "udpin:5760"], "--msp: bad endpoint 'udpin:5760'"),
    (["--msp", "serial:/dev/no-such-port"], "cannot open serial port /dev/no-such-port"),
    (["--msp", "builtin", "--listen", "tcp:127.0.0.1:1"], "--listen: bad endpoint"),
])
def test_bad_addresses_are_one_line_and_exit_2(argv, message, capsys) -> None:
    from mavconform.cli import main
    assert main(["bridge", *argv, "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err


class _NoisyFc(MspServerNode):
    """Replies behind line noise, a broken frame start and a frame with a bad checksum."""

    def take_outgoing(self):
        return [(b"\x00\xff$M>\x05" + b"$M>\x00\x14\x00" + data, peer) for data, peer in super().take_outgoing()]


def test_a_noisy_stream_is_counted_and_the_mission_still_goes_through() -> None:
    rig = _Rig()
    noisy = _NoisyFc(rig.fc.controller)
    rig.net.add_node("noisy", noisy)
    rig.net.connect("link", "noisy")
    rig.link.peer = "noisy"
    assert rig.do("upload", MISSION, _plan(3)).outcome is Outcome.SUCCESS
    assert rig.do("download", MISSION).items == tuple(_plan(3))
    stats = rig.link.parser.stats
    assert stats.garbage_bytes > 0 and stats.bad_checksum > 0


class _HasHome(MspFlightController):
    """A flight controller with a GPS home: MSP_WP 0 holds it."""

    def _wp(self, payload: bytes) -> bytes:
        if payload[:1] == b"\x00":
            return Waypoint(0, 4, 473977420, 85455940, 48830, 0, 0, 0, 0xA5).pack()
        return super()._wp(payload)


def _command(rig: _Rig, msg) -> list:
    before = len(rig.gcs.received)
    rig.gcs.send(msg)
    rig.net.run_for(3.0)
    return rig.gcs.received[before:]


def test_home_is_msp_waypoint_0() -> None:
    from mavconform.reference_impl.mission import messages as m
    from mavconform.reference_impl.wire.dialect import mavlink as d
    get = m.command_long_message(Cmd.GET_HOME_POSITION, (1, 1))
    got = _command(_Rig(_HasHome()), get)
    home = [x for x in got if x._type == "HOME_POSITION"]
    assert home and (home[0].latitude, home[0].longitude, home[0].altitude) == (473977420, 85455940, 488300)
    assert [x.result for x in got if x._type == "COMMAND_ACK"] == [0]
    rig = _Rig()                                                     # no home yet (no GPS fix): zeros
    assert [x.result for x in _command(rig, get) if x._type == "COMMAND_ACK"] == [1]
    set_home = d.MAVLink_command_int_message(1, 1, 0, Cmd.DO_SET_HOME, 0, 0, 0, 0, 0, 0, 473977420, 85455940, 488.3)
    assert [x.result for x in _command(rig, set_home) if x._type == "COMMAND_ACK"] == [1]   # on the ground: refused
