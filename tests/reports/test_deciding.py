"""Which message decided a clause: the index its check recorded, else a guess from its verdict."""

from mavconform.reports.deciding import deciding_event
from mavconform.reports.enum_names import enum_value_name, field_value_name

from .sample import clause, event

UPLOAD = [event(0.0, "tx", "MISSION_COUNT", count=3, mission_type=0),          # 0
          event(0.001, "rx", "MISSION_REQUEST_INT", seq=0, mission_type=0),    # 1
          event(0.002, "tx", "MISSION_ITEM_INT", seq=0, mission_type=0),       # 2
          event(0.003, "rx", "MISSION_REQUEST", seq=1, mission_type=0),        # 3
          event(0.004, "rx", "MISSION_CURRENT", seq=0, total=3),               # 4
          event(1.0, "rx", "MISSION_CURRENT", seq=0, total=3)]                 # 5
TIMED_OUT = UPLOAD + [event(1.5, "note", "expected MISSION_ACK{mission_type=0} within 1.5 s: "
                                         "nothing matching arrived")]          # 6


def decided(detail, exchange=UPLOAD, outcome="fail", **extra):
    return deciding_event({**clause("MIS.UP.03", outcome, exchange, detail=detail), **extra},
                          exchange)


def test_a_timeout_is_decided_by_the_note_that_says_nothing_came():
    detail = ("precondition: waiting for the final MISSION_ACK: expected MISSION_ACK{mission_type=0} "
              "within 1.5 s; last mission message: MISSION_CURRENT{seq=0, total=3}")
    assert decided(detail, TIMED_OUT) == 6


def test_a_message_cited_with_its_fields_is_the_one_with_those_values():
    assert decided("during the upload the vehicle sent MISSION_REQUEST_INT{seq=0, mission_type=0}") == 1
    # the last of several that agree
    assert decided("last mission message: MISSION_CURRENT{seq=0, total=3}") == 5
    # an enum name cited for a number
    acked = UPLOAD + [event(1.1, "rx", "MISSION_ACK", type=15, mission_type=0)]
    assert decided("ended with MISSION_ACK{type=MAV_MISSION_OPERATION_CANCELLED}", acked) == 6


def test_what_the_verdict_says_did_not_come_is_not_marked():
    acked = [event(0.0, "rx", "MISSION_ACK", type=0, mission_type=0), *UPLOAD[:3]]
    # bare: "no MISSION_ACK"; braced: "expected MISSION_ACK{...}"
    assert decided("the upload got no MISSION_ACK", acked) == 2   # the last received
    assert decided("expected MISSION_ACK{type=0} within 1.5 s", acked) == 2


def test_a_message_named_bare_is_the_last_of_its_name_from_the_target():
    assert decided("the vehicle requested item 1 with MISSION_REQUEST, expected "
                   "MISSION_REQUEST_INT") == 3


def test_otherwise_the_last_message_received():
    assert decided("the plan came back different") == 5
    assert decided("", UPLOAD[:1]) == 0   # nothing received: the last event
    assert decided("", [], outcome="fail") is None
    assert decided("--clauses excluded it", outcome="skipped") is None


def test_a_recorded_index_wins():
    assert decided("last mission message: MISSION_CURRENT{seq=0, total=3}", decided_by=2) == 2
    assert decided("the plan came back different", decided_by=99) == 5   # out of range: ignored


def test_enum_names():
    assert field_value_name("MISSION_ITEM_INT", "frame", 3) == "MAV_FRAME_GLOBAL_RELATIVE_ALT"
    assert field_value_name("MISSION_ITEM_INT", "mission_type", 1) == "MAV_MISSION_TYPE_FENCE"
    assert field_value_name("MISSION_ITEM_INT", "x", 3) is None             # not an enum field
    assert field_value_name("MISSION_ITEM_INT", "frame", "NaN") is None
    assert field_value_name("MISSION_ITEM_INT", "frame", 99) == "not a MAV_FRAME"
    assert field_value_name("MISSION_ITEM_INT", "frame", 22) == "not a MAV_FRAME"  # ENUM_END
    assert field_value_name("NO_SUCH_MESSAGE", "frame", 3) is None
    # a MAV_CMD our dialect does not carry, from pymavlink's common dialect
    assert field_value_name("COMMAND_LONG", "command", 400) == "MAV_CMD_COMPONENT_ARM_DISARM"
    assert enum_value_name("MAV_MODE_FLAG", 129) == \
        "MAV_MODE_FLAG_CUSTOM_MODE_ENABLED|MAV_MODE_FLAG_SAFETY_ARMED"
