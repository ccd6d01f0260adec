"""A sentinel that closes a window without guessing its length.

To see everything a target answers to what was sent so far, send a properly addressed
COMMAND_LONG MAV_CMD_REQUEST_MESSAGE after it: targets answer in order, so its COMMAND_ACK
comes after any mission reply to the messages before it, and cannot be mistaken for one
whatever the MAVLink version. A target that never acknowledges it gets the reply timeout.
"""

from __future__ import annotations

from mavconform.reference_impl.mission import messages as m
from mavconform.reference_impl.mission.constants import Cmd

from .match import msg
from .tester import Tester

MISSION_REPLIES = ("MISSION_REQUEST", "MISSION_REQUEST_INT", "MISSION_COUNT", "MISSION_ACK",
                   "MISSION_ITEM", "MISSION_ITEM_INT")


def answers_before_sentinel(t: Tester) -> list:
    """The mission messages the target sends in answer to what was sent so far (to be judged
    by the caller), ended by a sentinel: a properly addressed COMMAND_LONG
    MAV_CMD_REQUEST_MESSAGE, whose COMMAND_ACK comes after any answer to the messages before it
    (targets answer in order) and cannot be mistaken for a mission answer, whatever the MAVLink
    version. A target that never acknowledges it has had the reply timeout to answer."""
    t.note("then a properly addressed COMMAND_LONG MAV_CMD_REQUEST_MESSAGE (HEARTBEAT): its "
           "COMMAND_ACK closes the window")
    t.send(m.command_long_message(Cmd.REQUEST_MESSAGE, t.target))
    sentinel = msg("COMMAND_ACK", command=Cmd.REQUEST_MESSAGE)
    seen = t.collect(msg(MISSION_REPLIES), t.timings.default_timeout, stop=sentinel)
    return [f for _, f in seen if not sentinel(f)]


def brief(msg) -> str:
    """A reply as a verdict names it: `MISSION_ACK{type=1, mission_type=0}`."""
    shown = ", ".join(f"{k}={getattr(msg, k)}" for k in ("seq", "count", "type", "mission_type")
                      if hasattr(msg, k))
    return f"{msg._type}{{{shown}}}"
