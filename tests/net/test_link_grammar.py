"""Issue 24: one link grammar: tcp:, tcpin:, serial:DEVICE[:BAUD] and pty[:BAUD] beside udp:."""

from __future__ import annotations

import os

import pytest

from mavconform.conformance.target_uri import parse_target
from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net.uri import SerialUri, TcpUri, parse_link_uri


@pytest.mark.parametrize("text, role, expected", [
    ("tcp:127.0.0.1:5760", "target", TcpUri("tcp", "127.0.0.1", 5760)),
    ("TCP:[::1]:5760", "peer", TcpUri("tcp", "::1", 5760)),
    ("tcpin:5760", "target", TcpUri("tcpin", "127.0.0.1", 5760)),
    ("tcpin:0", "listen", TcpUri("tcpin", "127.0.0.1", 0)),
    ("tcpin:0.0.0.0:5760", "listen", TcpUri("tcpin", "0.0.0.0", 5760)),
    ("serial:/dev/ttyACM0", "target", SerialUri("/dev/ttyACM0", 57600)),
    ("serial:/dev/ttyUSB0:921600", "peer", SerialUri("/dev/ttyUSB0", 921600)),
    ("serial:COM3:115200", "target", SerialUri("COM3", 115200)),
    # a by-path name holds colons; only a trailing :digits is a baud rate
    ("serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0", "target",
     SerialUri("/dev/serial/by-path/pci-0000:00:14.0-usb-0:2:1.0-port0", 57600)),
    ("pty", "listen", SerialUri("pty", 57600)),
    ("pty:921600", "listen", SerialUri("pty", 921600)),
])
def test_stream_forms_parse_and_round_trip(text, role, expected):
    uri = parse_link_uri(text, role=role)
    assert uri == expected
    assert parse_link_uri(str(uri), role=role) == uri


@pytest.mark.parametrize("text, kind", [("tcp:127.0.0.1:5760", "tcp"), ("tcpin:5760", "tcpin"),
                                        ("serial:/dev/null:115200", "serial")])
def test_targets_take_every_link_form(text, kind):
    target = parse_target(text)
    assert target.kind == kind and target.link == parse_link_uri(text) and str(target) == str(target.link)
    assert target.udp is None and not target.in_process


@pytest.mark.parametrize("text, role, says", [
    ("tcp:127.0.0.1:0", "target", "port 0 is only allowed where we listen"),
    ("tcp:5760", "target", "missing host"),
    ("tcpin:5760", "peer", "here a peer listens and we send first: give tcp:HOST:PORT"),
    ("tcp:127.0.0.1:5760", "listen", "here we listen: give tcpin:[HOST:]PORT"),
    ("tcpin:127.0.0.1:99999", "listen", "bad port 99999"),
    ("serial:", "target", "missing device"),
    ("serial:/dev/ttyUSB0:0", "target", "bad baud rate 0"),
    ("serial:/dev/ttyUSB0:99999999", "target", "bad baud rate 99999999"),
    ("pty:fast", "listen", "bad baud rate 'fast': not a number"),
    ("pty", "target", "pty: makes a pseudo-terminal to serve on"),
    ("smoke:1", "target", "unknown scheme 'smoke'"),
])
def test_a_bad_link_address_is_one_line_naming_the_option(text, role, says):
    with pytest.raises(UsageError) as info:
        parse_link_uri(text, role=role, option="--opt")
    message = str(info.value)
    assert message.startswith(f"--opt: bad endpoint {text!r}: ") and says in message and "\n" not in message


def test_a_word_after_an_existing_device_is_a_bad_baud_rate():
    assert os.path.exists("/dev/null")
    with pytest.raises(UsageError, match="bad baud rate 'fast': not a number"):
        parse_link_uri("serial:/dev/null:fast")
