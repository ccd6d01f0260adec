"""The project's own MAVLink dialect: facts match upstream, stays wire-compatible with
pymavlink's bundled common dialect, round-trips, and the committed module is fresh."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from pymavlink.dialects.v20 import common as bundled
from pymavlink.generator import mavparse

from mavconform.reference_impl.wire.dialect import XML_PATH, mavlink, regenerate

# Beside the repository, wherever it is cloned: <repo_root>.parent / "shared".
UPSTREAM_DIR = Path(__file__).resolve().parents[3] / "shared" / "mavlink-upstream"
UPSTREAM_FILES = ("minimal.xml", "standard.xml", "common.xml", "development.xml")

REQUIRED_MESSAGES = {
    "HEARTBEAT": 0, "PARAM_REQUEST_READ": 20, "PARAM_VALUE": 22, "GLOBAL_POSITION_INT": 33,
    "MISSION_REQUEST_PARTIAL_LIST": 37,
    "MISSION_WRITE_PARTIAL_LIST": 38, "MISSION_ITEM": 39, "MISSION_REQUEST": 40,
    "MISSION_SET_CURRENT": 41, "MISSION_CURRENT": 42, "MISSION_REQUEST_LIST": 43,
    "MISSION_COUNT": 44, "MISSION_CLEAR_ALL": 45, "MISSION_ITEM_REACHED": 46, "MISSION_ACK": 47,
    "MISSION_REQUEST_INT": 51, "REQUEST_DATA_STREAM": 66, "MISSION_ITEM_INT": 73, "COMMAND_INT": 75, "COMMAND_LONG": 76,
    "COMMAND_ACK": 77, "HOME_POSITION": 242, "STATUSTEXT": 253, "SETUP_SIGNING": 256, "CONTROL_STATUS": 512,
}
# Enums we carry in full; MAV_COMPONENT and MAV_CMD are deliberate subsets.
FULL_ENUMS = {
    "MAV_TYPE", "MAV_AUTOPILOT", "MAV_MODE_FLAG", "MAV_STATE", "MAV_SEVERITY", "MAV_FRAME",
    "MAV_MISSION_TYPE", "MAV_MISSION_RESULT", "MAV_RESULT", "MISSION_STATE", "GCS_CONTROL_STATUS_FLAGS",
    "MAV_DATA_STREAM", "MAV_PARAM_TYPE",
}
REQUIRED_SUBSETS = {
    "MAV_COMPONENT": {"MAV_COMP_ID_ALL", "MAV_COMP_ID_AUTOPILOT1", "MAV_COMP_ID_MISSIONPLANNER",
                      "MAV_COMP_ID_ONBOARD_COMPUTER"},
    "MAV_CMD": {16, 17, 18, 19, 20, 21, 22, 31, 93, 112, 114, 115, 176, 177, 178, 179, 183, 189, 224, 300,
                400, 410, 512, 5000, 5001, 5002, 5003, 5004, 5100, 32100},
}

MessageShape = tuple[int, list[tuple[str, str, int, str]], int | None, int]
EnumFacts = dict[str, dict[str, tuple[dict[str, str], list[dict[str, str]]]]]


def _shapes(xml_files: list[Path]) -> dict[str, MessageShape]:
    """name -> (id, [(field, type, array_length, enum)], extensions_start, crc_extra), via mavparse."""
    out: dict[str, MessageShape] = {}
    for path in xml_files:
        for m in mavparse.MAVXML(str(path), mavparse.PROTOCOL_2_0).message:
            fields = [(f.name, f.type, f.array_length, f.enum) for f in m.fields]
            out[m.name] = (m.id, fields, m.extensions_start, m.crc_extra)
    return out


def _field_attrs(xml_files: list[Path]) -> dict[str, list[dict[str, str]]]:
    """message name -> attributes of each <field> and <extensions/> marker, in document order."""
    out: dict[str, list[dict[str, str]]] = {}
    for path in xml_files:
        for m in ET.parse(path).getroot().iter("message"):
            out[m.get("name", "")] = [dict(c.attrib, tag=c.tag) for c in m if c.tag in ("field", "extensions")]
    return out


def _enum_facts(xml_files: list[Path]) -> EnumFacts:
    """enum -> entry name -> (entry attributes, [param attributes]); merges MAV_CMD across files."""
    out: EnumFacts = {}
    for path in xml_files:
        for e in ET.parse(path).getroot().iter("enum"):
            entries = out.setdefault(e.get("name", ""), {})
            for entry in e.iter("entry"):
                entries[entry.get("name", "")] = (dict(entry.attrib), [dict(p.attrib) for p in entry.iter("param")])
    return out


@pytest.fixture(scope="module")
def upstream() -> list[Path]:
    if not UPSTREAM_DIR.is_dir():
        pytest.skip(f"upstream MAVLink XML not found at {UPSTREAM_DIR} (expected beside the repo in shared/)")
    return [UPSTREAM_DIR / name for name in UPSTREAM_FILES]


@pytest.fixture(scope="module")
def ours() -> dict[str, MessageShape]:
    return _shapes([XML_PATH])


# --- what the dialect must contain -----------------------------------------------------------

def test_carries_the_required_definitions(ours: dict[str, MessageShape]) -> None:
    assert {name: shape[0] for name, shape in ours.items()} == REQUIRED_MESSAGES
    enums = _enum_facts([XML_PATH])
    assert FULL_ENUMS <= enums.keys()
    assert REQUIRED_SUBSETS["MAV_COMPONENT"] <= enums["MAV_COMPONENT"].keys()
    assert {int(attrs["value"]) for attrs, _ in enums["MAV_CMD"].values()} == REQUIRED_SUBSETS["MAV_CMD"]
    assert mavlink.MAV_RESULT_NOT_IN_CONTROL == 10
    # Every enum a field refers to is defined here, so generated code can name its values.
    assert {f[3] for shape in ours.values() for f in shape[1] if f[3]} <= enums.keys()


# --- 1. facts against upstream -----------------------------------------------------------------

def test_messages_match_upstream(upstream: list[Path], ours: dict[str, MessageShape]) -> None:
    theirs = _shapes(upstream)
    their_attrs, our_attrs = _field_attrs(upstream), _field_attrs([XML_PATH])
    for name, shape in ours.items():
        assert shape == theirs[name], f"{name}: id / fields / extension split / CRC_EXTRA differ from upstream"
        assert our_attrs[name] == their_attrs[name], f"{name}: field attributes differ from upstream"
        assert mavlink.mavlink_map[shape[0]].crc_extra == theirs[name][3], f"{name}: generated CRC_EXTRA is stale"


def test_enum_entries_match_upstream(upstream: list[Path]) -> None:
    theirs, ours = _enum_facts(upstream), _enum_facts([XML_PATH])
    for enum, entries in ours.items():
        assert enum in theirs, f"{enum} is not an upstream enum"
        if enum in FULL_ENUMS:
            assert entries.keys() == theirs[enum].keys(), f"{enum}: entries differ from upstream"
        for name, (attrs, params) in entries.items():
            assert name in theirs[enum], f"{enum}.{name} is not upstream"
            assert attrs == theirs[enum][name][0], f"{enum}.{name}: value/attributes differ from upstream"
            assert params == theirs[enum][name][1], f"{enum}.{name}: <param> elements differ from upstream"


# --- 2. wire compatibility with pymavlink's bundled common dialect ------------------------------

def test_wire_compatible_with_bundled_common() -> None:
    shared = mavlink.mavlink_map.keys() & bundled.mavlink_map.keys()
    assert shared == set(REQUIRED_MESSAGES.values()) - {512}
    for msgid in shared:
        mine, theirs = mavlink.mavlink_map[msgid], bundled.mavlink_map[msgid]
        assert mine.msgname == theirs.msgname
        assert mine.crc_extra == theirs.crc_extra, f"{mine.msgname}: CRC_EXTRA differs from bundled"
        assert mine.fieldnames[: len(theirs.fieldnames)] == theirs.fieldnames, mine.msgname
        assert mine.ordered_fieldnames[: len(theirs.ordered_fieldnames)] == theirs.ordered_fieldnames


@pytest.mark.parametrize(
    ("msgname", "fields"),
    [
        ("MISSION_COUNT", {"opaque_id"}),
        ("MISSION_ACK", {"opaque_id"}),
        ("MISSION_CURRENT", {"mission_id", "fence_id", "rally_points_id"}),
    ],
)
def test_carries_what_bundled_lacks(msgname: str, fields: set[str]) -> None:
    """The reason this dialect exists: upstream extensions pymavlink 2.4.50 does not know."""
    msgid = REQUIRED_MESSAGES[msgname]
    assert fields <= set(mavlink.mavlink_map[msgid].fieldnames)
    assert not fields & set(bundled.mavlink_map[msgid].fieldnames)


def test_bundled_lacks_operator_control() -> None:
    assert 512 not in bundled.mavlink_map and not hasattr(bundled, "MAV_CMD_REQUEST_OPERATOR_CONTROL")
    assert mavlink.MAV_CMD_REQUEST_OPERATOR_CONTROL == 32100


# --- 3. round trip through the generated module --------------------------------------------

_UNSIGNED_BASE = {"uint8_t": 200, "uint16_t": 60000, "uint32_t": 4_000_000_000, "uint64_t": 2**40}


def _value(ftype: str, length: int, i: int) -> Any:
    """A non-default value that differs per field index, so swapped fields are caught."""
    if ftype == "char":
        return f"mavconform-{i}"[: length or 1]  # str here; the generated constructor takes bytes
    if length:
        return [_value(ftype, 0, i + j) for j in range(length)]
    if ftype in ("float", "double"):
        return 0.5 + i  # exactly representable in float32
    if ftype.startswith("int"):
        return -(1 + i % 100)
    return _UNSIGNED_BASE[ftype] - i


def _build(msg: Any) -> tuple[Any, dict[str, Any]]:
    """The generated class for a mavparse message, with non-default values, and those values."""
    values = {f.name: _value(f.type, f.array_length, i) for i, f in enumerate(msg.fields)}
    args = {name: v.encode() if isinstance(v, str) else v for name, v in values.items()}
    return mavlink.mavlink_map[msg.id](**args), values


def _roundtrip(message: Any, force_mavlink1: bool) -> Any:
    sender = mavlink.MAVLink(None, srcSystem=7, srcComponent=mavlink.MAV_COMP_ID_AUTOPILOT1)
    frame = message.pack(sender, force_mavlink1=force_mavlink1)
    assert frame[0] == (mavlink.PROTOCOL_MARKER_V1 if force_mavlink1 else mavlink.PROTOCOL_MARKER_V2)
    decoded = mavlink.MAVLink(None, 1, 1).parse_buffer(bytearray(frame))
    assert decoded is not None and len(decoded) == 1, f"{message.msgname}: did not decode as one frame"
    # type(...).id, not message.id: STATUSTEXT's field `id` shadows the class's message id.
    assert decoded[0].get_msgId() == type(message).id
    return decoded[0]


_MESSAGES = mavparse.MAVXML(str(XML_PATH), mavparse.PROTOCOL_2_0).message


@pytest.mark.parametrize("msg", _MESSAGES, ids=lambda m: m.name)
def test_roundtrip_mavlink2(msg: Any) -> None:
    message, values = _build(msg)
    decoded = _roundtrip(message, force_mavlink1=False)
    assert {name: getattr(decoded, name) for name in values} == values


@pytest.mark.parametrize("msg", [m for m in _MESSAGES if m.id <= 255], ids=lambda m: m.name)
def test_roundtrip_mavlink1(msg: Any) -> None:
    """pymavlink's MAVLink 1 frames keep the extension bytes (it never cuts the payload back
    to the base fields), so the round trip is lossless there too; pinned here on purpose."""
    message, values = _build(msg)
    decoded = _roundtrip(message, force_mavlink1=True)
    assert decoded.get_header().mlen == type(message).unpacker.size
    assert {name: getattr(decoded, name) for name in values} == values


# --- 4. the committed module is what mavgen makes of the XML -------------------------------

def test_generated_module_is_up_to_date() -> None:
    assert regenerate.check() == "identical", "run: python -m mavconform.reference_impl.wire.dialect.regenerate"
