"""The MSP flight-controller model answers as INAV 9.1's SITL did when probed over MSP.

Each row below is one request and the SITL's answer (INAV 9.1.0 e7d5cceb, MSP on TCP 5760,
2026-11-28, in this order from boot); the model must give the same, and a model that breaks
a rule (mutated here) must not.
"""

from __future__ import annotations

import pytest

from mavconform.reference_impl.msp.commands import Waypoint, WaypointInfo
from mavconform.reference_impl.msp.flight_controller import MspFlightController, missing
from mavconform.reference_impl.msp.frame import MspFrame, Version


def wp(n, action=1, lat=473977419, lon=85455938, alt=5000, flag=0, p1=0, p2=0, p3=0) -> bytes:
    return Waypoint(n, action, lat, lon, alt, p1, p2, p3, flag).pack()


def info(valid, count) -> bytes:
    return WaypointInfo(0, 120, valid, count).pack()


# (command, request payload, request framing, reply direction, reply payload): the SITL's answers
SESSION = [
    (1, b"", Version.V1, ">", bytes((0, 2, 5))),
    (20, b"", Version.V1, ">", info(False, 0)),
    (118, b"\x01", Version.V1, ">", missing(1).pack()),
    (118, b"\x00", Version.V1, ">", missing(0).pack()),
    (209, wp(1), Version.V1, ">", b""),
    (209, wp(2, alt=6000, flag=0xA5), Version.V1, ">", b""),
    (20, b"", Version.V1, ">", info(True, 2)),
    (118, b"\x01", Version.V1, ">", wp(1)),
    (118, b"\x02", Version.V1, ">", wp(2, alt=6000, flag=0xA5)),
    (118, b"\x03", Version.V1, ">", missing(3).pack()),
    (209, wp(5, flag=0xA5), Version.V1, ">", b""),        # a gap: ignored, still `>`
    (20, b"", Version.V1, ">", info(True, 2)),
    (209, wp(0), Version.V1, ">", b""),                   # home, disarmed: ignored
    (209, wp(255), Version.V1, ">", b""),
    (209, wp(121), Version.V1, ">", b""),
    (209, wp(3)[:20], Version.V1, "!", b""),              # not 21 bytes
    (209, wp(3, flag=0xA5), Version.V2, ">", b""),        # v2 in, v2 out; appended
    (20, b"", Version.V1, ">", info(True, 3)),
    (209, wp(1, flag=0xA5), Version.V1, ">", b""),        # number 1 starts the list again
    (20, b"", Version.V1, ">", info(True, 1)),
    (209, wp(2, action=2, flag=0xA5), Version.V1, ">", b""),   # no action 2: ignored
    (20, b"", Version.V1, ">", info(True, 1)),
    (118, b"\x02", Version.V1, ">", missing(2).pack()),
    (209, wp(2, action=6, lat=0, lon=0, alt=0, p1=1, p2=3, flag=0xA5), Version.V1, ">", b""),
    (118, b"\x02", Version.V1, ">", wp(2, action=6, lat=0, lon=0, alt=0, p1=1, p2=3, flag=0xA5)),
    (19, b"\x00", Version.V1, ">", b""),                  # save a valid list
    (19, b"", Version.V1, "!", b""),                      # save: the mission id is missing
    (121, b"", Version.V1, ">", bytes.fromhex("00000001000000")),
    (118, bytes([200]), Version.V1, ">", missing(200).pack()),
    (118, b"", Version.V1, ">", missing(0).pack()),       # no payload reads number 0
]
# The SITL restarted with the same EEPROM (the list saved above; waypoints are not loaded at
# boot: nav_wp_load_on_boot is OFF by default, fc/settings.yaml:2590-2594)
AFTER_RESTART = [
    (99, b"", Version.V1, "!", b""),                      # commands it does not know
    (240, b"", Version.V1, "!", b""),
    (0x3FFF, b"", Version.V2, "!", b""),
    (20, b"", Version.V2, ">", info(False, 0)),           # the reply's framing is the request's
    (20, b"", Version.V2_OVER_V1, ">", info(False, 0)),
    (118, b"\x01\x02", Version.V1, ">", missing(1).pack()),   # the first byte is the number
    (18, b"\x00", Version.V1, ">", b""),                  # load the saved list
    (20, b"", Version.V1, ">", info(True, 2)),
]


def _replay(fc: MspFlightController, session=SESSION) -> list[tuple]:
    out = []
    for command, payload, version, _, _ in session:
        replies = fc.handle(MspFrame(command, payload, "<", version))
        assert len(replies) == 1 and replies[0].command == command and replies[0].version is version
        out.append((replies[0].direction, replies[0].payload))
    return out


def test_the_model_answers_every_request_as_the_sitl_did():
    fc = MspFlightController()
    fc.nav_status = bytes.fromhex("00000001000000")   # idle, active waypoint 1: what the SITL reported
    assert _replay(fc) == [(d, p) for *_, d, p in SESSION]
    assert fc.stats.errors == 2 and fc.stats.ignored_waypoints == 5
    restarted = MspFlightController()
    restarted.saved = fc.saved
    assert _replay(restarted, AFTER_RESTART) == [(d, p) for *_, d, p in AFTER_RESTART]


class _AppendsAnywhere(MspFlightController):
    def _set_wp(self, payload):
        if len(payload) == 21:
            w = Waypoint.unpack(payload)
            if 1 <= w.number <= 120:
                self.waypoints = (self.waypoints + [None] * w.number)[:w.number - 1] + [w]
                self.valid = w.flag == 0xA5
                return b""
        return super()._set_wp(payload)


class _RefusesWithError(MspFlightController):
    def _set_wp(self, payload):
        before = len(self.waypoints)
        out = super()._set_wp(payload)
        return None if out is not None and len(self.waypoints) == before and before < 3 else out


@pytest.mark.parametrize("broken", [_AppendsAnywhere, _RefusesWithError])
def test_a_model_that_breaks_a_rule_answers_otherwise(broken):
    fc = broken()
    fc.nav_status = bytes.fromhex("00000001000000")
    assert _replay(fc) != [(d, p) for *_, d, p in SESSION]


def test_a_load_with_nothing_valid_saved_fails_and_empties_the_list():
    fc = MspFlightController()
    fc.handle(MspFrame(209, wp(1)))                       # no 0xA5: not valid
    assert fc.handle(MspFrame(19, b"\x00"))[0].direction == "!"   # a list that is not valid is not saved
    assert fc.handle(MspFrame(18, b"\x00"))[0].direction == "!"
    assert fc.info() == WaypointInfo(0, 120, False, 0)
    assert fc.handle(MspFrame(20, b"", ">")) == []       # a reply is no request
