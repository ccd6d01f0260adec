"""seed 004's mapping (reference_impl/msp/mapping.py): exact where it can be, refused where not.

- MAVLink -> MSP -> MAVLink is the identity on every item `to_waypoint` accepts (up to the
  frame synonyms common.xml declares, and a NaN param4 coming back 0);
- an item outside what MSP holds is refused with the error its row names, never changed;
- docs/msp-mapping.md is the table as the code has it.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from mavconform.reference_impl.mission.constants import MissionResult as R
from mavconform.reference_impl.mission.items import MissionItem, MissionType
from mavconform.reference_impl.msp.commands import FLAG_LAST, Waypoint
from mavconform.reference_impl.msp.mapping import (ACTIONS, MAX_WAYPOINTS, SYNONYMS, Refusal, render_markdown,
                                                    to_item, to_waypoint)

DOC = Path(__file__).resolve().parents[2] / "docs" / "msp-mapping.md"
i16 = st.integers(-32768, 32767).map(float)


@st.composite
def fitting_items(draw):
    """(item, count): an item any MSP flight controller can hold, at seq < count."""
    count = draw(st.integers(1, MAX_WAYPOINTS))
    seq = draw(st.integers(0, count - 1))
    action = draw(st.sampled_from(list(ACTIONS.values())))
    p1 = draw(st.integers(0, count - 1).map(float)) if action.p1 == "jump" else draw(i16) if action.p1 else 0.0
    p2 = draw(i16) if action.p2 else 0.0
    param4 = draw(st.sampled_from([0.0, math.nan]))
    if action.positional:
        frame = draw(st.sampled_from([0, 3, 5, 6]))
        x, y = draw(st.integers(-900_000_000, 900_000_000)), draw(st.integers(-1_800_000_000, 1_800_000_000))
        z = draw(st.integers(-100_000, 10_000_000)) / 100
    else:
        frame, x, y, z = 2, 0, 0, 0.0
    return MissionItem(seq, frame, int(action.command), p1, p2, 0.0, param4, x, y, z, draw(st.integers(0, 1)), 1), count


def _as_it_comes_back(item: MissionItem) -> MissionItem:
    return dataclasses.replace(item, frame=SYNONYMS.get(item.frame, item.frame), current=0,
                               param4=0.0, z=float(item.z))


@given(fitting_items())
def test_mavlink_to_msp_and_back_is_the_identity_on_what_fits(case):
    item, count = case
    wp = to_waypoint(item, count)
    assert isinstance(wp, Waypoint), wp
    assert Waypoint.unpack(wp.pack()) == wp                           # and it fits the 21-byte record
    assert wp.number == item.seq + 1 and (wp.flag == FLAG_LAST) == (item.seq == count - 1)
    back = to_item(wp)
    assert back == _as_it_comes_back(item)


# (what breaks the item, the error its row names)
BREAKS = [
    (dict(command=22), R.UNSUPPORTED),                               # NAV_TAKEOFF: no action
    (dict(autocontinue=0), R.UNSUPPORTED),
    (dict(frame=1), R.UNSUPPORTED_FRAME),                            # local NED
    (dict(frame=10), R.UNSUPPORTED_FRAME),                           # terrain altitude
    (dict(param1=5.0), R.INVALID_PARAM1),                            # NAV_WAYPOINT has no slot for a hold
    (dict(param2=1.0), R.INVALID_PARAM2),
    (dict(param3=1.0), R.INVALID_PARAM3),                            # p3 holds the altitude datum
    (dict(param4=90.0), R.INVALID_PARAM4),
    (dict(z=10.129), R.INVALID_PARAM7),                              # not whole centimetres
    (dict(z=math.inf), R.INVALID_PARAM7),
    (dict(mission_type=MissionType.FENCE), R.UNSUPPORTED),
]


@pytest.mark.parametrize("change, code", BREAKS, ids=[next(iter(c)) + "-" + R(code).name for c, code in BREAKS])
def test_what_does_not_fit_is_refused_with_its_rows_error(change, code):
    item = dataclasses.replace(MissionItem(0, 3, 16, 0.0, 0.0, 0.0, 0.0, 473977419, 85455938, 50.0), **change)
    got = to_waypoint(item, 1)
    assert isinstance(got, Refusal) and got.code == code, got


@given(i16, st.floats(allow_nan=True, allow_infinity=True))
def test_params_that_are_no_16_bit_integers_are_refused(ok, bad):
    assume(not (math.isfinite(bad) and bad == int(bad) and -32768 <= bad <= 32767))
    hold = MissionItem(0, 3, 19, ok, 0.0, 0.0, 0.0, 1, 2, 3.0)
    assert isinstance(to_waypoint(hold, 1), Waypoint)
    got = to_waypoint(dataclasses.replace(hold, param1=bad), 1)
    assert isinstance(got, Refusal) and got.code == R.INVALID_PARAM1


def test_limits_of_the_list_and_of_jumps():
    wp = MissionItem(0, 3, 16, 0.0, 0.0, 0.0, 0.0, 1, 2, 3.0)
    assert to_waypoint(wp, MAX_WAYPOINTS + 1).code == R.NO_SPACE
    jump = MissionItem(1, 2, 177, 5.0, 1.0, 0.0, 0.0, 0, 0, 0.0)
    assert to_waypoint(jump, 3).code == R.INVALID_PARAM1               # seq 5 is not in a 3-item mission
    assert to_waypoint(dataclasses.replace(jump, param1=2.0), 3).p1 == 3   # a number over MSP
    assert to_waypoint(dataclasses.replace(jump, param1=0.0, x=1), 3).code == R.INVALID_PARAM5_X
    assert to_item(Waypoint(0, 1, 1, 2, 3)).code == R.INVALID_SEQUENCE    # home is no mission waypoint
    assert to_item(Waypoint(1, 2, 1, 2, 3)).code == R.UNSUPPORTED         # action 2 does not exist


def test_the_mapping_page_is_the_table_as_the_code_has_it():
    assert DOC.read_text() == render_markdown(), "regenerate: python -m mavconform.reference_impl.msp.mapping > docs/msp-mapping.md"
