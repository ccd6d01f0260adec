"""The chaos proxy: the sans-IO core on its own, under SimNetwork in virtual time, on one
UdpDriver with the reference GCS and vehicle, and as the `mavconform proxy` command."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections import Counter

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from mcap.reader import make_reader

from mavconform.fuzz.proxy import DOWN, FRONT, UP, ChaosProxy, ProxyNode, UdpProxy
from mavconform.cli import main
from mavconform.reference_impl.files import SAMPLES_DIR, load_plan
from mavconform.reference_impl.gcs import GcsConfig, GcsNode
from mavconform.reference_impl.mission.items import PLAN_TYPES, MissionType, renumber
from mavconform.reference_impl.mission.timing import Timings
from mavconform.reference_impl.net import (CaptureRecord, DropMessage, FaultModel, McapCapture, MonotonicClock,
                                SimNetwork, UdpDriver)
from mavconform.reference_impl.session import GcsSession
from mavconform.reference_impl.vehicle import VehicleNode
from mavconform.reference_impl.wire.codec import FrameDecoder

PLAN = load_plan(SAMPLES_DIR / "demo.plan")
LOSSY = dict(loss=0.05, duplicate=0.1, reorder=0.1, reorder_delay=0.03, delay=0.005, jitter=0.005)


def _drain(proxy: ChaosProxy) -> list[tuple[int, bytes, object]]:
    """Everything every port wants sent, as (port, data, dst)."""
    ports = [FRONT, *range(proxy.legs_in_use)]
    return [(port, data, dst) for port in ports for data, dst in proxy.take_outgoing(port)]


def _names(data: bytes) -> list[str]:
    return [getattr(f, "name", "DECODE_ERROR") for f in FrameDecoder().feed(data)]


# -- the core, driven by hand ---------------------------------------------------------------

def test_clean_proxy_relays_both_ways_from_the_right_ports():
    proxy = ChaosProxy("vehicle")
    assert proxy.from_gcs(b"a", "gcs", 0.0) == 0
    proxy.from_gcs(b"b", "gcs", 0.0)
    assert _drain(proxy) == [(0, b"a", "vehicle"), (0, b"b", "vehicle")]
    proxy.from_vehicle(b"r", 0, "vehicle", 0.1)
    assert _drain(proxy) == [(FRONT, b"r", "gcs")]
    assert (proxy.stats[UP].sent, proxy.stats[UP].delivered) == (2, 2)
    assert (proxy.stats[DOWN].sent, proxy.stats[DOWN].delivered) == (1, 1)
    assert proxy.next_deadline() is None


def test_each_gcs_gets_its_own_leg_and_its_own_replies():
    proxy = ChaosProxy("vehicle")
    assert proxy.from_gcs(b"1", "gcs-a", 0.0) == 0
    assert proxy.from_gcs(b"2", "gcs-b", 0.0) == 1
    assert proxy.from_gcs(b"3", "gcs-a", 0.0) == 0
    assert _drain(proxy) == [(0, b"1", "vehicle"), (0, b"3", "vehicle"), (1, b"2", "vehicle")]
    proxy.from_vehicle(b"to-b", 1, "vehicle", 0.0)
    proxy.from_vehicle(b"to-a", 0, "vehicle", 0.0)
    assert _drain(proxy) == [(FRONT, b"to-b", "gcs-b"), (FRONT, b"to-a", "gcs-a")]


def test_a_full_leg_table_hands_the_quietest_leg_to_a_new_gcs():
    proxy = ChaosProxy("vehicle", max_legs=2)
    proxy.from_gcs(b"", "a", 0.0)
    proxy.from_gcs(b"", "b", 0.0)
    proxy.from_gcs(b"", "a", 1.0)            # b is now the quietest
    assert proxy.from_gcs(b"", "c", 2.0) == 1
    assert (proxy.legs_in_use, proxy.reassigned) == (2, 1)
    assert proxy.leg_of("b") is None and proxy.gcs_of(1) == "c"
    _drain(proxy)
    proxy.from_vehicle(b"r", 1, "vehicle", 2.0)
    assert _drain(proxy) == [(FRONT, b"r", "c")]


def test_only_the_vehicle_is_heard_on_a_leg_and_never_at_the_listen_port():
    proxy = ChaosProxy("vehicle")
    proxy.from_vehicle(b"early", 0, "vehicle", 0.0)   # no GCS yet: no leg 0
    proxy.from_gcs(b"x", "gcs", 0.0)
    proxy.from_vehicle(b"spoof", 0, "stranger", 0.0)
    assert proxy.from_gcs(b"loop", "vehicle", 0.0) is None   # the vehicle at the listen port
    assert proxy.stray == 3
    assert _drain(proxy) == [(0, b"x", "vehicle")]
    assert proxy.stats[DOWN].sent == 0


def test_delays_wait_for_the_drivers_clock():
    proxy = ChaosProxy("vehicle", up=FaultModel(delay=0.05))
    proxy.from_gcs(b"x", "gcs", 1.0)
    assert _drain(proxy) == [] and proxy.next_deadline() == pytest.approx(1.05)
    proxy.poll(1.04)
    assert _drain(proxy) == []
    proxy.poll(1.05)
    assert _drain(proxy) == [(0, b"x", "vehicle")] and proxy.next_deadline() is None


def test_the_delay_queue_is_bounded():
    proxy = ChaosProxy("vehicle", up=FaultModel(delay=1.0), max_pending=2)
    for i in range(5):
        proxy.from_gcs(b"%d" % i, "gcs", 0.0)
    assert (proxy.pending(), proxy.overflowed, proxy.stats[UP].dropped) == (2, 3, 3)
    proxy.poll(1.0)
    assert [d for _, d, _ in _drain(proxy)] == [b"0", b"1"]


def test_one_fault_model_for_both_directions_counts_rules_per_direction():
    model = FaultModel(rules=(DropMessage("HEARTBEAT", 1),))
    proxy = ChaosProxy("vehicle", up=model, down=model)
    heartbeat = _heartbeat_bytes()
    proxy.from_gcs(heartbeat, "gcs", 0.0)
    proxy.from_gcs(heartbeat, "gcs", 0.0)
    proxy.from_vehicle(heartbeat, 0, "vehicle", 0.0)
    proxy.from_vehicle(heartbeat, 0, "vehicle", 0.0)
    assert proxy.stats[UP].dropped == 1 and proxy.stats[DOWN].dropped == 1
    assert len(_drain(proxy)) == 2


@settings(max_examples=40)
@given(seed=st.integers(0, 2**32), loss=st.floats(0, 1), dup=st.floats(0, 1),
       reorder=st.floats(0, 1), corrupt=st.floats(0, 1), delay=st.sampled_from([0.0, 0.01]),
       traffic=st.lists(st.tuples(st.booleans(), st.floats(0, 0.1)), max_size=40))
def test_every_datagram_is_accounted_for_and_the_seed_decides(seed, loss, dup, reorder, corrupt,
                                                              delay, traffic):
    """out = in - dropped + duplicated once the queue is empty; equal seeds, equal runs; and
    without reorder, delay or jitter nothing overtakes anything."""
    def run() -> tuple[list, ChaosProxy]:
        model = FaultModel(loss=loss, duplicate=dup, reorder=reorder, corrupt=corrupt, delay=delay)
        proxy = ChaosProxy("vehicle", up=model, down=model, seed=seed)
        records: list[CaptureRecord] = []
        proxy.add_capture(records.append)
        now, sent = 0.0, []
        for i, (upward, gap) in enumerate(traffic):
            now += gap
            proxy.poll(now)
            data = b"%05d" % i
            if upward or proxy.legs_in_use == 0:
                proxy.from_gcs(data, "gcs", now)
            else:
                proxy.from_vehicle(data, 0, "vehicle", now)
            sent.append(data)
        proxy.poll(now + 10.0)
        return [(r.kind, r.src, r.dst, r.data) for r in records], proxy

    records, proxy = run()
    assert proxy.pending() == 0 and proxy.overflowed == 0
    for stats in proxy.stats.values():
        assert stats.delivered == stats.sent - stats.dropped + stats.duplicated
    assert sum(s.sent for s in proxy.stats.values()) == len(traffic)
    assert Counter(k for k, *_ in records) == Counter(
        tx=len(traffic), drop=sum(s.dropped for s in proxy.stats.values()),
        rx=sum(s.delivered for s in proxy.stats.values()))
    assert run()[0] == records
    if reorder == 0 and delay == 0 and corrupt == 0:
        up = [data for kind, src, _, data in records if kind == "rx" and src == "gcs"]
        assert up == sorted(up)


# -- under SimNetwork, in virtual time ------------------------------------------------------

def _sim(seed: int, up: FaultModel | None, down: FaultModel | None):
    net = SimNetwork(seed=seed)
    vehicle = VehicleNode(wall_clock=net.clock.wall)
    proxy = ChaosProxy("vehicle", up=up, down=down, seed=seed, max_legs=1)
    gcs = GcsNode(remote="proxy", wall_clock=net.clock.wall)
    net.add_node("vehicle", vehicle)
    net.add_node("proxy", ProxyNode(proxy))
    net.add_node("gcs", gcs)
    net.connect("gcs", "proxy")
    net.connect("proxy", "vehicle")
    records: list[CaptureRecord] = []
    proxy.add_capture(records.append)
    session = GcsSession(net, gcs)
    session.wait_for_target(5.0)
    return session, vehicle, proxy, records


def _round_trip(session: GcsSession) -> None:
    for t in PLAN_TYPES:
        assert session.upload(t, PLAN.items(t)).ok
    for t in PLAN_TYPES:
        result = session.download(t)
        assert result.ok and result.items == tuple(renumber(PLAN.items(t), t))


def test_sim_round_trip_through_a_lossy_proxy_repeats_from_its_seed():
    runs = []
    for _ in range(2):
        session, _vehicle, proxy, records = _sim(11, FaultModel(**LOSSY), FaultModel(**LOSSY))
        _round_trip(session)
        runs.append(([(r.time, r.kind, r.src, r.dst, r.data) for r in records],
                     {d: s for d, s in proxy.stats.items()}))
    assert runs[0] == runs[1]
    stats = runs[0][1]
    for s in stats.values():
        assert s.dropped and s.duplicated and s.reordered
    assert {(src, dst) for _, _, src, dst, _ in runs[0][0]} == {("gcs", "vehicle"), ("vehicle", "gcs")}


def test_sim_drop_rule_drops_exactly_the_first_vehicle_ack_and_the_gcs_retries():
    session, vehicle, proxy, records = _sim(
        3, None, FaultModel(rules=(DropMessage("MISSION_ACK", 1),)))
    result = session.upload(MissionType.MISSION, PLAN.mission)
    assert result.ok and result.retries >= 1
    dropped = [r for r in records if r.kind == "drop"]
    assert [(r.src, _names(r.data)) for r in dropped] == [("vehicle", ["MISSION_ACK"])]
    assert proxy.stats[DOWN].dropped == 1 and proxy.stats[UP].dropped == 0
    acks = [r for r in records if r.kind == "rx" and "MISSION_ACK" in _names(r.data)]
    assert len(acks) == 1   # the ACCEPTED sent again for the resent last item
    assert vehicle.store.count(MissionType.MISSION) == len(PLAN.mission)


def test_proxy_node_has_one_leg():
    with pytest.raises(ValueError, match="max_legs=1"):
        ProxyNode(ChaosProxy("vehicle"))


# -- one UdpDriver: reference vehicle <- proxy <- reference GCS, on 127.0.0.1 ----------------

@pytest.mark.udp
def test_udp_round_trip_through_the_proxy_with_faults_is_captured_both_ways(tmp_path):
    clock = MonotonicClock()
    path = tmp_path / "run.mcap"
    with UdpDriver(clock=clock, seed=5) as driver:
        vehicle = VehicleNode(wall_clock=clock.wall)
        vehicle_at = driver.add_node(vehicle)
        lossy_down = FaultModel(**LOSSY, rules=(DropMessage("MISSION_REQUEST_INT", 2),))
        proxy = ChaosProxy(vehicle_at, up=FaultModel(**LOSSY), down=lossy_down, seed=5)
        node = UdpProxy(driver, proxy)
        gcs = GcsNode(remote=node.address, wall_clock=clock.wall)
        gcs_at = driver.add_node(gcs)
        with McapCapture(path) as capture:
            proxy.add_capture(capture)
            session = GcsSession(driver, gcs)
            assert session.wait_for_target(5.0) == (1, 1)
            assert session.upload(MissionType.MISSION, PLAN.mission).ok
            got = session.download(MissionType.MISSION)
            assert got.ok and got.items == tuple(renumber(PLAN.mission, MissionType.MISSION))
        assert len(node.leg_addresses) == 1
        assert set(vehicle.endpoint.addresses) == {node.leg_addresses[0]}
        ups, downs = proxy.stats[UP], proxy.stats[DOWN]
        assert ups.sent and downs.sent and downs.dropped >= 1
        assert ups.duplicated + ups.reordered + downs.duplicated + downs.reordered > 0
        dropped = ups.dropped + downs.dropped
    topics = Counter()
    with open(path, "rb") as f:
        for _, channel, message in make_reader(f).iter_messages():
            body = json.loads(message.data)
            topics[(channel.topic, body["kind"], body["msg"])] += 1
    up = f"{gcs_at[0]}:{gcs_at[1]} -> {vehicle_at[0]}:{vehicle_at[1]}"
    down = f"{vehicle_at[0]}:{vehicle_at[1]} -> {gcs_at[0]}:{gcs_at[1]}"
    assert {up, down, f"{down} (lost)"} <= {topic for topic, _, _ in topics} <= {
        up, down, f"{up} (lost)", f"{down} (lost)"}
    # each datagram once, as sent (its relayed copy is not written again); a duplicate the
    # link made is an rx; a loss is on the direction's lost channel
    assert sum(n for (topic, kind, _), n in topics.items() if topic == up and kind == "tx") == ups.sent
    assert sum(n for (topic, kind, _), n in topics.items() if topic == down and kind == "tx") == downs.sent
    assert sum(n for (topic, kind, _), n in topics.items() if topic == up and kind == "rx") <= ups.duplicated
    assert topics[(up, "tx", "MISSION_ITEM_INT")] >= len(PLAN.mission)
    assert topics[(down, "tx", "MISSION_ITEM_INT")] >= len(PLAN.mission)
    assert topics[(f"{down} (lost)", "drop", "MISSION_REQUEST_INT")] >= 1
    assert all(topic.endswith(" (lost)") == (kind == "drop") for topic, kind, _ in topics)
    assert sum(n for (_, kind, _), n in topics.items() if kind == "drop") == dropped


@pytest.mark.udp
def test_udp_drop_rule_drops_exactly_that_ack():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as driver:
        vehicle = VehicleNode(wall_clock=clock.wall)
        vehicle_at = driver.add_node(vehicle)
        proxy = ChaosProxy(vehicle_at, down=FaultModel(rules=(DropMessage("MISSION_ACK", 1),)))
        records: list[CaptureRecord] = []
        proxy.add_capture(records.append)
        quick = GcsConfig(timings=Timings().scaled(0.4))   # the lost ACK costs 0.6 s, not 1.5
        gcs = GcsNode(quick, remote=UdpProxy(driver, proxy).address, wall_clock=clock.wall)
        driver.add_node(gcs)
        session = GcsSession(driver, gcs)
        session.wait_for_target(5.0)
        first = session.upload(MissionType.MISSION, PLAN.mission)
        second = session.upload(MissionType.MISSION, PLAN.mission)
    assert first.ok and first.retries >= 1
    assert second.ok
    assert [_names(r.data) for r in records if r.kind == "drop"] == [["MISSION_ACK"]]
    assert proxy.stats[DOWN].dropped == 1


@pytest.mark.udp
def test_udp_two_gcss_share_the_vehicle_each_through_its_own_port():
    clock = MonotonicClock()
    with UdpDriver(clock=clock) as driver:
        vehicle = VehicleNode(wall_clock=clock.wall)
        proxy = ChaosProxy(driver.add_node(vehicle))
        node = UdpProxy(driver, proxy)
        a = GcsNode(remote=node.address, wall_clock=clock.wall)
        b = GcsNode(remote=node.address, wall_clock=clock.wall)
        a_at, b_at = driver.add_node(a), driver.add_node(b)
        GcsSession(driver, a).wait_for_target(5.0)
        GcsSession(driver, b).wait_for_target(5.0)
        assert GcsSession(driver, a).upload(MissionType.MISSION, PLAN.mission).ok
        got = GcsSession(driver, b).download(MissionType.MISSION)
    assert got.ok and got.items == tuple(renumber(PLAN.mission, MissionType.MISSION))
    assert len(node.leg_addresses) == 2
    assert {proxy.gcs_of(0), proxy.gcs_of(1)} == {a_at, b_at}
    assert set(vehicle.endpoint.addresses) == set(node.leg_addresses)
    assert proxy.stray == 0


# -- the command --------------------------------------------------------------------------

def _sigint_as_by_default() -> None:
    """A suite started as a background job passes SIGINT on ignored, and Python keeps an
    ignored SIGINT: the proxy would never see the Ctrl-C this test sends."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _cli(*args: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mavconform", *args], text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"}, preexec_fn=_sigint_as_by_default)


def _port_of(line: str) -> int:
    assert line.startswith("chaos proxy listening on udp:127.0.0.1:"), line
    return int(line.split("udp:127.0.0.1:")[1].split(",")[0])


@pytest.mark.udp
def test_cli_proxy_carries_the_gcs_cli_to_a_vehicle_and_stops_cleanly(tmp_path):
    clock = MonotonicClock()
    capture = tmp_path / "proxy.mcap"
    with UdpDriver(clock=clock) as driver:
        vehicle = VehicleNode(wall_clock=clock.wall)
        vehicle_at = driver.add_node(vehicle)
        proxy = _cli("proxy", "--listen", "udp:127.0.0.1:0", "--forward",
                     f"udp:127.0.0.1:{vehicle_at[1]}", "--loss", "0.05", "--dup", "0.1",
                     "--reorder", "0.1", "--delay", "5", "--jitter", "5", "--seed", "9",
                     "--capture", str(capture), "--duration", "60")
        try:
            port = _port_of(proxy.stdout.readline())   # bounded: the proxy exits by --duration
            gcs = _cli("gcs", "upload", "--target", f"udp:127.0.0.1:{port}",
                       str(SAMPLES_DIR / "demo.plan"))
            for _ in range(600):                         # the vehicle runs here, <= 60 s
                driver.run_for(0.1)
                if gcs.poll() is not None:
                    break
            out, err = gcs.communicate(timeout=10)
            assert gcs.returncode == 0, out + err
            assert out.count("ok   upload") == 3
            proxy.send_signal(signal.SIGINT)
            rest, perr = proxy.communicate(timeout=10)
        finally:
            for p in (proxy, locals().get("gcs")):
                if p is not None and p.poll() is None:
                    p.kill()
                    p.communicate()
    assert proxy.returncode == 0, perr
    assert "stopped" in perr
    assert "speaks to the vehicle from 127.0.0.1:" in rest
    counts = {line.split()[0]: line for line in rest.splitlines() if line.startswith(("up ", "down "))}
    assert set(counts) == {"up", "down"}
    for line in counts.values():
        assert int(line.split("in ")[1].split(",")[0]) > 0
    assert vehicle.store.count(MissionType.MISSION) == len(PLAN.mission)
    with open(capture, "rb") as f:   # closed properly on Ctrl-C: the summary reads
        topics = {channel.topic for _, channel, _ in make_reader(f).iter_messages()}
    directions = {t for t in topics if not t.endswith(" (lost)")}   # losses: the proxy's faults
    assert len(directions) == 2 and all(t.count(" -> ") == 1 for t in directions)
    assert {t.removesuffix(" (lost)") for t in topics} == directions


@pytest.mark.udp
def test_cli_proxy_stops_by_itself_after_duration(tmp_path):
    capture = tmp_path / "idle.mcap"
    proxy = _cli("proxy", "--listen", "udp:127.0.0.1:0", "--forward", "udp:127.0.0.1:9",
                 "--duration", "0.3", "--capture", str(capture))
    out, err = proxy.communicate(timeout=30)
    assert proxy.returncode == 0, err
    lines = out.splitlines()
    _port_of(lines[0])
    assert lines[1].startswith("up   gcs -> vehicle: in 0, out 0, dropped 0")
    assert lines[2].startswith("down vehicle -> gcs: in 0, out 0")
    with open(capture, "rb") as f:
        assert list(make_reader(f).iter_messages()) == []


@pytest.mark.udp
def test_cli_proxy_stops_cleanly_on_sigterm(tmp_path):
    capture = tmp_path / "term.mcap"
    proxy = _cli("proxy", "--listen", "udp:127.0.0.1:0", "--forward", "udp:127.0.0.1:9",
                 "--duration", "60", "--capture", str(capture))
    try:
        _port_of(proxy.stdout.readline())
        proxy.send_signal(signal.SIGTERM)
        out, err = proxy.communicate(timeout=10)
    finally:
        if proxy.poll() is None:
            proxy.kill()
            proxy.communicate()
    assert proxy.returncode == 0 and "stopped" in err, err
    assert out.splitlines()[0].startswith("up   gcs -> vehicle: in 0")
    with open(capture, "rb") as f:
        assert make_reader(f).get_summary() is not None   # finished, not truncated


@pytest.mark.parametrize("argv, says", [
    (["--forward", "http:127.0.0.1:5"], "--forward: bad endpoint 'http:127.0.0.1:5': unknown scheme"),
    (["--forward", "udpin:127.0.0.1:5"], "--forward: bad endpoint 'udpin:127.0.0.1:5': here a peer listens"),
    (["--forward", "udp:127.0.0.1:0"], "--forward: bad endpoint 'udp:127.0.0.1:0': port 0"),
    (["--forward", "udp:127.0.0.1:70000"], "bad port 70000"),
    (["--forward", "udp:1.2.3:5"], "bad host '1.2.3'"),
    (["--forward", "udp:0.0.0.0:5"], "0.0.0.0 is not an address a vehicle listens at"),
    (["--listen", "udp:127.0.0.1:x"], "--listen: bad endpoint 'udp:127.0.0.1:x': bad port"),
    (["--listen", "udp:127.0.0.1:5760", "--forward", "udp:127.0.0.1:5760"],
     "is the proxy's own --listen address"),
    (["--drop", "NO_SUCH_MESSAGE"], "bad drop rule 'NO_SUCH_MESSAGE'"),
])
def test_cli_usage_mistakes_are_one_line_and_exit_2(argv, says, capsys, tmp_path):
    base = {"--listen": "udp:127.0.0.1:0", "--forward": "udp:127.0.0.1:14550"}
    extra = []
    for i in range(0, len(argv), 2):
        if argv[i] in base:
            base[argv[i]] = argv[i + 1]
        else:
            extra += argv[i:i + 2]
    capture = tmp_path / "never.mcap"
    code = main(["proxy", *(x for kv in base.items() for x in kv), *extra,
                 "--capture", str(capture), "--duration", "0.1"])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and says in err, err
    assert not capture.exists()


def test_cli_option_values_are_checked(capsys):
    for argv in (["--loss", "1.5"], ["--max-gcs", "0"], ["--only", "sideways"]):
        with pytest.raises(SystemExit) as exc:
            main(["proxy", "--listen", "udp:127.0.0.1:0", "--forward", "udp:127.0.0.1:9", *argv])
        assert exc.value.code == 2
        assert capsys.readouterr().err.count("\n") == 1


def _heartbeat_bytes() -> bytes:
    from mavconform.reference_impl.wire.codec import FrameEncoder
    from mavconform.reference_impl.wire.dialect import mavlink as d

    return FrameEncoder(1, 1).encode(d.MAVLink_heartbeat_message(2, 4, 0, 0, 3, 3))

