"""Issue 12: one UDP address grammar, one parser, for run, fuzz, gcs, vehicle, proxy and the
pytest plugins. `udpin:PORT` used to work for run and fuzz only; gcs, vehicle and proxy said
"missing port"."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from mavconform.cli import main
from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import UdpUri, parse_udp_uri
from mavconform.reference_impl.net.uri import parse_link_uri
from ..vehicle_process import vehicle_process

NOWHERE = "no-such-host.invalid"   # RFC 6761: never resolves


@pytest.mark.parametrize("text, role, expected", [
    ("udp:127.0.0.1:14550", "target", UdpUri("udp", "127.0.0.1", 14550)),
    ("udp:localhost:14550", "peer", UdpUri("udp", "localhost", 14550)),
    ("udp:[::1]:14550", "target", UdpUri("udp", "::1", 14550)),
    ("udpin:14550", "target", UdpUri("udpin", "127.0.0.1", 14550)),
    ("udpin:0", "target", UdpUri("udpin", "127.0.0.1", 0)),
    ("udpin:0.0.0.0:14550", "target", UdpUri("udpin", "0.0.0.0", 14550)),
    ("udpin:[::1]:0", "target", UdpUri("udpin", "::1", 0)),
    ("UDPIN:14550", "target", UdpUri("udpin", "127.0.0.1", 14550)),
    (" udpin:14550 ", "target", UdpUri("udpin", "127.0.0.1", 14550)),
    # where we listen, either scheme names the address we bind; port 0 is any free port
    ("udp:127.0.0.1:0", "listen", UdpUri("udp", "127.0.0.1", 0)),
    ("udpin:0", "listen", UdpUri("udpin", "127.0.0.1", 0)),
])
def test_every_form_parses_the_same_for_every_role_that_takes_it(text, role, expected):
    assert parse_udp_uri(text, role=role) == expected
    assert parse_udp_uri(str(expected), role=role) == expected   # str() round-trips


@pytest.mark.parametrize("text", ["udp:127.0.0.1:14550", "udpin:14550", "udpin:127.0.0.1:0", "udp:[::1]:5"])
def test_targets_use_the_one_parser(text):
    target = parse_target(text)
    assert target.kind == target.udp.mode and target.udp == parse_udp_uri(text)


@pytest.mark.parametrize("text", ["udp:14550", "udpin:[::1]", "udp:127.0.0.1:0", f"udp:{NOWHERE}:1"])
def test_targets_are_refused_in_the_one_parsers_words(text):
    def refusal(parse) -> str:
        with pytest.raises(UsageError) as info:
            parse(text)
        return str(info.value)
    assert refusal(parse_target) == refusal(parse_link_uri)


@pytest.mark.parametrize("text, role, says", [
    ("udpin:14550", "peer", "here a peer listens and we send first: give udp:HOST:PORT"),
    ("udp:127.0.0.1:0", "target", "port 0 is only allowed where we listen"),
    ("udp:127.0.0.1:0", "peer", "port 0 is only allowed where we listen"),
    ("udp:14550", "target", "missing host"),
    ("udpin:", "listen", "missing port"),
    ("udpin:[::1]", "listen", "missing port"),
    ("udpin:[::1:5", "listen", "'[' without ']'"),
    ("udpin:localhost", "listen", "bad port 'localhost'"),
    (f"udpin:{NOWHERE}:0", "listen", f"cannot resolve host {NOWHERE!r}"),
])
def test_a_form_an_option_cannot_use_is_refused_naming_the_option(text, role, says):
    with pytest.raises(UsageError) as info:
        parse_udp_uri(text, role=role, option="--opt")
    assert str(info.value).startswith(f"--opt: bad endpoint {text!r}: ") and says in str(info.value)


def _usage(argv: list[str], capsys) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and err.startswith("mavconform: error: "), (code, err)
    return err


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.udp
def test_vehicle_listens_at_udpin_port(capsys):
    with vehicle_process("--listen", "udpin:0", "--quiet") as port:
        assert main(["gcs", "clear", "--target", f"udp:127.0.0.1:{port}", "--heartbeat-timeout", "10"]) == 0


@pytest.mark.udp
def test_gcs_listens_at_udpin_port_for_a_vehicle_that_sends_first(capsys):
    port = _free_port()
    with vehicle_process("--connect", f"udp:127.0.0.1:{port}", "--quiet"):
        assert main(["gcs", "clear", "--target", f"udpin:{port}", "--heartbeat-timeout", "10"]) == 0
    assert f"at udpin:127.0.0.1:{port}" in capsys.readouterr().out


@pytest.mark.udp
def test_proxy_listens_at_udpin_port(capsys):
    assert main(["proxy", "--listen", "udpin:0", "--forward", "udp:127.0.0.1:9", "--duration", "0.1"]) == 0
    assert "chaos proxy listening on udp:127.0.0.1:" in capsys.readouterr().out


@pytest.mark.parametrize("argv, says", [
    (["vehicle", "--listen", "udpin:0", "--connect", "udpin:14551"],
     "--connect: bad endpoint 'udpin:14551': here a peer listens"),
    (["proxy", "--listen", "udpin:0", "--forward", "udpin:14550"], "--forward: bad endpoint 'udpin:14550'"),
])
def test_a_listening_form_where_we_send_first_is_a_usage_error(argv, says, capsys):
    assert says in _usage(argv + ["--duration", "0.1"], capsys)


@pytest.mark.parametrize("argv, option", [
    (["run", "--target", f"udp:{NOWHERE}:14550"], ""),
    (["fuzz", "--target", f"udpin:{NOWHERE}:0", "--database", "none"], ""),
    (["gcs", "clear", "--target", f"udp:{NOWHERE}:14550"], "--target: "),
    (["gcs", "download", "--target", f"udpin:{NOWHERE}:0", "back.plan"], "--target: "),
    (["vehicle", "--listen", f"udpin:{NOWHERE}:0"], "--listen: "),
    (["vehicle", "--listen", "udpin:0", "--connect", f"udp:{NOWHERE}:14551"], "--connect: "),
    (["proxy", "--listen", f"udp:{NOWHERE}:0", "--forward", "udp:127.0.0.1:9"], "--listen: "),
    (["proxy", "--listen", "udpin:0", "--forward", f"udp:{NOWHERE}:14550"], "--forward: "),
])
def test_an_unresolvable_host_is_a_usage_error_naming_it_for_every_command(argv, option, capsys, tmp_path):
    folders = {"run": ["--report-dir", str(tmp_path / "r")],
               "fuzz": ["--report-dir", str(tmp_path / "r"), "--findings", str(tmp_path / "f")]}
    err = _usage(argv + folders.get(argv[0], []), capsys)
    assert f"mavconform: error: {option}bad endpoint " in err and f"cannot resolve host {NOWHERE!r}" in err, err


@pytest.mark.parametrize("plugin, option, text", [
    ("mavconform.conformance", "--mavlink-target", f"udp:{NOWHERE}:14550"),
    ("mavconform.conformance", "--mavlink-target", "udpin:70000"),
    ("mavconform.fuzz", "--fuzz-target", f"udpin:{NOWHERE}:0"),
])
def test_pytest_plugins_parse_the_same_grammar_and_name_their_option(plugin, option, text, tmp_path):
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--pyargs",
                           plugin, option, text], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert done.returncode == 4, done.stdout + done.stderr
    assert f"ERROR: {option}: bad endpoint {text!r}: " in done.stderr, done.stderr
