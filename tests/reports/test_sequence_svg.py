"""The sequence diagram: every field readable, enum names, lanes from the peers, real times."""

import re

from mavconform.reference_impl.wire.dialect import mavlink as dialect
from mavconform.reports.message_label import wrap
from mavconform.reports.sequence_svg import FIT_WIDTH, sequence_diagram

from .sample import event

ITEM = event(0.2, "tx", "MISSION_ITEM_INT", seq=0, frame=3, command=16, current=0,
             autocontinue=1, param1=0.0, param2=0.0, param3=0.0, param4=0.0, x=473977460,
             y=85456100, z=13.0, mission_type=1, target_system=1, target_component=1)
CANCELLED = event(0.3, "rx", "MISSION_ACK", type=15, mission_type=1, opaque_id=0,
                  target_system=245, target_component=190)


def drawn_labels(svg):
    """The visible text of each arrow (its tspans joined by spaces), not the tooltip."""
    return [" ".join(re.findall(r"<tspan[^>]*>([^<]*)</tspan>", text))
            for text in re.findall(r'<g class="arrow[^"]*">.*?<text[^>]*>(.*?)</text></g>',
                                   svg, re.S)]


def lanes(svg):
    return re.findall(r'<text class="actor[^"]*" x="[\d.]+" y="22">([^<]*)</text>', svg)


def test_a_label_shows_every_field_with_enum_names_without_hovering():
    svg = sequence_diagram([ITEM, CANCELLED])
    item, ack = drawn_labels(svg)
    for token in ("MISSION_ITEM_INT", "seq=0", "frame=3 (MAV_FRAME_GLOBAL_RELATIVE_ALT)",
                  "command=16 (MAV_CMD_NAV_WAYPOINT)", "current=0", "autocontinue=1",
                  "param1=0.0", "param4=0.0", "x=473977460", "y=85456100", "z=13.0",
                  "mission_type=1 (MAV_MISSION_TYPE_FENCE)", "target_system=1",
                  "target_component=1"):
        assert token in item, token
    assert "…" not in item
    assert "type=15 (MAV_MISSION_OPERATION_CANCELLED)" in ack
    assert "opaque_id=0" in ack and "target_system=245" in ack
    # more than one line: wrapped, not cut
    assert svg.count('<tspan x=') > 4


def test_enum_names_come_from_the_dialect_metadata():
    svg = sequence_diagram([ITEM, CANCELLED])
    assert dialect.MAVLink_mission_ack_message.fieldenums_by_name["type"] == "MAV_MISSION_RESULT"
    assert f"type=15 ({dialect.enums['MAV_MISSION_RESULT'][15].name})" in svg
    assert f"command=16 ({dialect.enums['MAV_CMD'][16].name})" in svg


def test_wrapping_keeps_every_character_within_the_width():
    tokens = ["MISSION_ITEM_INT", "seq=0", "x=473977460", "text=" + "A" * 70]
    lines = wrap(tokens, 30)
    assert all(len(line) <= 30 for line in lines)
    assert "".join(lines).replace(" ", "") == "".join(tokens)


def test_lanes_are_the_peers_the_exchange_names_and_the_target():
    exchange = [event(0.0, "tx", "MISSION_COUNT", peer="tester", count=1),
                event(0.001, "rx", "MISSION_REQUEST_INT", peer="tester", seq=0),
                event(0.002, "tx", "MISSION_COUNT", peer="gcs-b", count=2),
                event(0.003, "rx", "MISSION_ACK", peer="gcs-b", type=0),
                event(0.004, "note", "a remark", peer="fuzzer")]
    svg = sequence_diagram(exchange, target="vehicle")
    assert lanes(svg) == ["tester", "vehicle (target)", "gcs-b"]
    x = dict(zip(lanes(svg), map(float, re.findall(r'<line class="lifeline" x1="([\d.]+)"', svg))))
    arrows = re.findall(r'<line x1="([\d.]+)" y1="[\d.]+" x2="([\d.]+)"', svg)
    assert [(float(a), float(b)) for a, b in arrows] == [
        (x["tester"], x["vehicle (target)"]), (x["vehicle (target)"], x["tester"]),
        (x["gcs-b"], x["vehicle (target)"]), (x["vehicle (target)"], x["gcs-b"])]
    width = int(re.search(r'<svg[^>]* width="(\d+)"', svg).group(1))
    assert width <= FIT_WIDTH   # three lanes fit the page's column


def test_no_tester_lane_unless_an_event_names_it():
    svg = sequence_diagram([event(0.0, "tx", "MISSION_CLEAR_ALL", peer="a"),
                            event(0.01, "rx", "MISSION_ACK", peer="a", type=0)])
    assert lanes(svg) == ["a", "target"]


def test_an_event_labelled_with_the_target_as_its_peer_is_drawn_from_the_target():
    """An exchange that names the sender, not the tester's side, still draws no arrow from
    the target to itself."""
    svg = sequence_diagram([event(0.0, "tx", "MISSION_COUNT", peer="a", count=1),
                            event(0.0, "tx", "MISSION_REQUEST_INT", peer="vehicle", seq=0)],
                           target="vehicle")
    assert lanes(svg) == ["a", "vehicle (target)"]
    arrows = re.findall(r'<g class="arrow (\w+)">.*?<line x1="([\d.]+)" y1="[\d.]+" x2="([\d.]+)"',
                        svg)
    assert [d for d, _, _ in arrows] == ["tx", "rx"]
    assert all(a != b for _, a, b in arrows)


def test_times_are_shown_when_the_events_have_them():
    svg = sequence_diagram([event(0.0, "tx", "MISSION_COUNT", count=1),
                            event(0.0015, "rx", "MISSION_REQUEST_INT", seq=0),
                            event(0.25, "rx", "MISSION_ACK", type=0)])
    assert re.findall(r'<text class="time" [^>]*>([^<]*)</text>', svg) == [
        "+0.000 s", "+0.002 s", "+0.250 s"]


def test_events_that_share_one_time_are_numbered_instead():
    svg = sequence_diagram([event(0.0, "tx", "MISSION_COUNT", count=1),
                            event(0.0, "rx", "MISSION_REQUEST_INT", seq=0)])
    assert re.findall(r'<text class="time" [^>]*>([^<]*)</text>', svg) == ["#1", "#2"]
    assert "(all +0.000 s)" in svg


def test_the_deciding_event_is_highlighted():
    exchange = [ITEM, CANCELLED, event(1.8, "note", "expected X within 1.5 s: nothing")]
    svg = sequence_diagram(exchange, decided=1)
    assert re.findall(r'<g class="(arrow rx decided)">', svg) == ["arrow rx decided"]
    assert svg.count('class="decided-band"') == 1 and svg.count('class="time decided-mark"') == 1
    assert svg.count("▶ +0.100 s") == 1   # its time, marked
    band = svg.index('class="decided-band"')
    assert band < svg.index('<g class="arrow rx decided">')   # drawn beneath it
    note = sequence_diagram(exchange, decided=2)
    assert '<g class="note decided">' in note and "arrow rx decided" not in note
    assert "decided" not in sequence_diagram(exchange)
