import pytest

from mavconform.reference_impl.errors import UsageError
from mavconform.reference_impl.net import UdpUri, parse_udp_uri


@pytest.mark.parametrize("text, expected", [
    ("udp:127.0.0.1:14550", UdpUri("udp", "127.0.0.1", 14550)),
    ("udpin:127.0.0.1:14550", UdpUri("udpin", "127.0.0.1", 14550)),
    ("udpin:0.0.0.0:14550", UdpUri("udpin", "0.0.0.0", 14550)),
    ("udpin:127.0.0.1:0", UdpUri("udpin", "127.0.0.1", 0)),
    ("udp:localhost:65535", UdpUri("udp", "localhost", 65535)),
    ("UDP:127.0.0.1:1", UdpUri("udp", "127.0.0.1", 1)),
    ("udp:[::1]:14550", UdpUri("udp", "::1", 14550)),
])
def test_good_uris(text, expected):
    uri = parse_udp_uri(text)
    assert uri == expected
    assert parse_udp_uri(str(uri)) == uri


def test_address():
    assert parse_udp_uri("udp:127.0.0.1:14550").address == ("127.0.0.1", 14550)


@pytest.mark.parametrize("text, what", [
    ("127.0.0.1", "missing scheme"),
    ("tcp:127.0.0.1:5760", "unknown scheme 'tcp'"),
    ("serial:/dev/ttyUSB0:57600", "unknown scheme"),
    ("udp:127.0.0.1", "missing port"),
    ("udp:127.0.0.1:", "missing port"),
    ("udpin::14550", "missing host"),
    ("udp:14550", "missing host"),
    ("udpin:[::1]", "missing port"),
    ("udp:127.0.0.1:abc", "bad port 'abc'"),
    ("udp:127.0.0.1:-1", "bad port"),
    ("udp:127.0.0.1:65536", "bad port 65536"),
    ("udp:127.0.0.1:0", "port 0 is only allowed where we listen"),
    ("udp:999.0.0.1:14550", "bad host '999.0.0.1'"),
    ("udp:bad_host!:14550", "bad host"),
    # issue 12: a name that does not resolve (.invalid never does, RFC 6761) is said to be one,
    # not reported later as "no HEARTBEAT from the target"
    ("udp:no-such-host.invalid:14550", "cannot resolve host 'no-such-host.invalid'"),
    ("udp:::1:14550", "brackets"),
    ("udp:[not-v6]:14550", "not an IPv6 address"),
    ("", "missing scheme"),
    ("udp:127.0.0.1:1\n2", "bad port"),
])
def test_bad_uris_give_one_line_naming_the_text(text, what):
    with pytest.raises(UsageError) as info:
        parse_udp_uri(text)
    message = str(info.value)
    assert what in message
    assert repr(text) in message
    assert "\n" not in message
