"""Our MSP codec against yamspy (PyPI), an MSP client written apart from ours.

yamspy writes requests (v1 for commands below 255, v2 native above) and reads replies; so
our parser reads what yamspy writes, and yamspy reads the replies we write, v1 and v2,
error frames too. It needs the interop extra (`make setup-interop`; `make run-msp-interop`
in CI).
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mavconform.reference_impl.msp.frame import MspFrame, Version, encode
from mavconform.reference_impl.msp.parser import MspParser

yamspy = pytest.importorskip("yamspy")


class _Wire:
    """What yamspy takes for its serial port."""

    def __init__(self) -> None:
        self.written, self.to_read = bytearray(), bytearray()

    def write(self, data) -> int:
        self.written += bytes(data)
        return len(data)

    def read(self, n: int = 1) -> bytes:
        out = bytes(self.to_read[:n])
        del self.to_read[:n]
        return out


def _client():
    board = yamspy.MSPy("not-opened", logfilename=None, loglevel="WARNING")
    board.conn = _Wire()
    return board


@settings(max_examples=200)
@given(st.integers(0, 0xFFFF).filter(lambda c: c != 255), st.binary(max_size=250))
def test_we_read_the_requests_yamspy_writes(code, payload):
    board = _client()
    board.send_RAW_msg(code, data=list(payload))
    got = MspParser().feed(bytes(board.conn.written))
    version = Version.V1 if code < 255 else Version.V2
    assert got == [MspFrame(code, payload, "<", version)]
    assert encode(got[0]) == bytes(board.conn.written)       # and we write them byte for byte


@settings(max_examples=200)
@given(st.integers(0, 0xFFFF).filter(lambda c: c != 255), st.binary(max_size=250), st.sampled_from([">", "!"]))
def test_yamspy_reads_the_replies_we_write(code, payload, direction):
    board = _client()
    version = Version.V1 if code < 255 else Version.V2
    board.conn.to_read += encode(MspFrame(code, payload, direction, version))
    got = board.receive_msg()
    if direction == "!":            # yamspy stops at an error frame's direction byte and says so
        assert got["unsupported"] == 1
        return
    assert got["packet_error"] == 0 and got["unsupported"] == 0
    assert got["code"] == code and got["message_length_expected"] == len(payload)
    assert bytes(got["message_buffer"]) == payload


def _committed_msp_vectors():
    from mavconform.vectors import store
    return store.load(store.DATA_DIR).msp


def test_yamspy_writes_our_v1_request_vectors_byte_for_byte():
    requests = [v for v in _committed_msp_vectors() if v["expected_error"] is None and v["direction"] == "<"
                and v["version"] == "v1"]
    assert len(requests) == 7
    for vec in requests:
        board = _client()
        board.send_RAW_msg(vec["command"], data=list(bytes.fromhex(vec["payload"])))
        assert bytes(board.conn.written).hex() == vec["bytes"], vec["id"]


def test_yamspy_reads_our_reply_vectors():
    replies = [v for v in _committed_msp_vectors() if v["expected_error"] is None and v["direction"] == ">"
               and v["version"] in ("v1", "v2")]
    assert len(replies) >= 14
    for vec in replies:
        board = _client()
        board.conn.to_read += bytes.fromhex(vec["bytes"])
        got = board.receive_msg()
        assert got["packet_error"] == 0 and got["code"] == vec["command"], vec["id"]
        assert bytes(got["message_buffer"]).hex() == vec["payload"], vec["id"]
