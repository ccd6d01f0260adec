"""HOME_POSITION on request (MAV_CMD_REQUEST_MESSAGE 242, MAV_CMD_GET_HOME_POSITION) from every
builtin vehicle, and PARAM_VALUE for the parameters a profile lists (virtual time)."""

from __future__ import annotations

import math

import pytest

from mavconform.reference_impl.mission.constants import Cmd
from mavconform.reference_impl.mission.constants import CommandResult as R
from mavconform.reference_impl.profiles import BUILTIN_PROFILES, load_profile
from mavconform.reference_impl.wire.dialect import mavlink as d

from .pilot import Pilot


def homes(p: Pilot) -> list:
    return [x for x in p.gcs.received if x.get_type() == "HOME_POSITION"]


# (inav: COMMAND_LONG is ignored, as INAV 9.1 has no handler for it: tests/profiles/test_inav_profile.py)
@pytest.mark.parametrize("name", [n for n in BUILTIN_PROFILES
                                  if "COMMAND_LONG" not in load_profile(n).config.ignored_messages])
def test_every_vehicle_says_where_its_home_is_when_asked(name):
    p = Pilot(name)
    home = p.vehicle.config.home
    assert p.command(Cmd.REQUEST_MESSAGE, d.MAVLINK_MSG_ID_HOME_POSITION) == R.ACCEPTED
    assert p.command(Cmd.GET_HOME_POSITION) == R.ACCEPTED
    got = homes(p)
    assert len(got) == 2
    for h in got:
        assert (h.latitude, h.longitude, h.altitude) == (round(home.lat * 1e7), round(home.lon * 1e7),
                                                         round(home.alt * 1000))
        assert (h.x, h.y, h.z) == (0.0, 0.0, 0.0) and all(math.isnan(q) for q in h.q)
    assert p.command(Cmd.REQUEST_MESSAGE, 9999) == R.UNSUPPORTED and len(homes(p)) == 2


def read(p: Pilot, name: str = "", index: int = -1) -> list:
    start = len(p.gcs.received)
    p.gcs.send(d.MAVLink_param_request_read_message(1, 1, name.encode(), index))
    p.run(0.5)
    return [x for x in p.gcs.received[start:] if x.get_type() == "PARAM_VALUE"]


def text(raw) -> str:
    return (raw if isinstance(raw, str) else bytes(raw).decode()).split("\0", 1)[0]


@pytest.mark.parametrize(("name", "param", "value", "kind"), [
    ("px4", "NAV_ACC_RAD", 2.0, d.MAV_PARAM_TYPE_REAL32),
    ("px4-fixedwing", "NAV_LOITER_RAD", 80.0, d.MAV_PARAM_TYPE_REAL32),
    ("px4-fixedwing", "FW_LND_ANG", 5.0, d.MAV_PARAM_TYPE_REAL32),
    ("px4-vtol", "NAV_ACC_RAD", 10.0, d.MAV_PARAM_TYPE_REAL32),
    ("ardupilot", "WP_RADIUS_M", 2.0, d.MAV_PARAM_TYPE_REAL32),
    ("ardupilot-plane", "WP_RADIUS", 50.0, d.MAV_PARAM_TYPE_INT16),
    ("ardupilot-plane", "WP_LOITER_RAD", 80.0, d.MAV_PARAM_TYPE_INT16),
    ("ardupilot-rover", "WP_RADIUS", 3.0, d.MAV_PARAM_TYPE_REAL32),
])
def test_a_listed_parameter_is_answered_by_name_and_by_index(name, param, value, kind):
    p = Pilot(name)
    listed = p.vehicle.config.params
    [got] = read(p, param)
    assert (text(got.param_id), got.param_value, got.param_type) == (param, value, kind)
    assert got.param_count == len(listed) and listed[got.param_index].name == param
    [again] = read(p, index=got.param_index)
    assert text(again.param_id) == param and again.param_value == value


@pytest.mark.parametrize("name", ["spec", "ardupilot", "px4"])
def test_an_unknown_parameter_gets_no_answer(name):
    p = Pilot(name)
    assert read(p, "NO_SUCH_PARAM") == [] and read(p, "WPNAV_RADIUS") == [] and read(p, index=40) == []
