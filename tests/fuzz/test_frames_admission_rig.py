"""The frame fuzzer's rig: it keeps the admission model in step with what it sends, resyncs
before the oracle speaks (the same filler on replay), and judges downloads in the stored form."""

from __future__ import annotations

import dataclasses

from mavconform.conformance.target_uri import parse_target
from mavconform.fuzz.case import Case
from mavconform.fuzz.frames import replay
from mavconform.fuzz.frames.admission import TARGET_TABLE
from mavconform.fuzz.frames.program import FrameSpec
from mavconform.fuzz.frames.rig import Rig, _plan_diff
from mavconform.fuzz.frames.templates import TEMPLATE_NAMES
from mavconform.reference_impl.wire.cparser import VARIANTS

from .frames_admission_streams import CLEAR, MUTATOR_INDEX, accepted


def _tx_to_vehicle(records: list) -> list[bytes]:
    return [r.data for r in records if r.kind == "tx" and r.dst == "vehicle"]


def test_the_rig_resyncs_before_the_oracle_speaks_and_replay_sends_the_same_filler() -> None:
    records: list = []
    rig = Rig(parse_target("builtin:spec"), seed=3, capture=records.append)
    assert rig.start() is None
    adm = rig.builder.admission
    before = len(_tx_to_vehicle(records))
    clear = TEMPLATE_NAMES.index("MISSION_CLEAR_ALL all")
    specs = [FrameSpec(0, clear, MUTATOR_INDEX["truncate"], 30)]      # cut short
    frames, fixed = rig.builder.datagram(specs)
    assert fixed == []
    rig.send(frames)
    rig.flush()
    assert adm.pending()            # the stream model is mid-frame: the oracle would be swallowed
    assert rig.check() is None
    assert not adm.pending() and adm.resyncs == 1 and adm.leaked == 0
    sent = _tx_to_vehicle(records)[before:]
    assert sent[0] == b"".join(frames)
    filler = sent[1]
    assert filler and not {0xFD, 0xFE} & set(filler) and len(set(filler)) == 1
    # the oracle's first frame after it is read whole by both C parsers
    for v in VARIANTS:
        got = accepted(v, [b"".join(frames), filler, sent[2]])
        assert [TARGET_TABLE.name(f.msgid) for f in got] == [TARGET_TABLE.name(sent[2][7])]
    # replay: the same datagrams, the same filler, in the same place
    case = Case("frames", "builtin:spec", 3, ({"setup": {"signing": False}}, {"send": [{"bytes": b"".join(frames)}]}))
    again: list = []
    assert replay(case, capture=again.append) is None
    assert _tx_to_vehicle(again) == _tx_to_vehicle(records)


def test_the_oracle_is_held_back_while_a_batch_is_sent() -> None:
    rig = Rig(parse_target("builtin:spec"), seed=4)
    assert rig.start() is None
    rig.gcs.poll(rig.clock.now() + 5.0)           # a HEARTBEAT of the oracle is due
    rig.send([CLEAR[:12]])
    out = rig.station.take_outgoing()
    assert [d for d, _ in out] == [CLEAR[:12]]    # the fuzz datagram only, the oracle held
    rig.flush()
    out = rig.station.take_outgoing()
    assert len(out) >= 2 and not {0xFD, 0xFE} & set(out[0][0])   # filler first, then the oracle
    assert not rig.builder.admission.pending()


def test_downloads_are_compared_in_the_stored_form() -> None:
    rig = Rig(parse_target("builtin:spec"), seed=5)
    assert rig.start() is None
    known = rig.expected
    # a real vehicle moves the `current` flag: not a difference
    rig.expected = tuple(dataclasses.replace(i, current=1 - i.current) for i in known)
    assert rig.check() is None
    rig.expected = (dataclasses.replace(known[0], x=known[0].x + 1),) + tuple(known[1:])
    v = rig.check()
    assert v.invariant == "download-completes"
    assert f"seq {known[0].seq}: x {known[0].x} (expected {known[0].x + 1})" in v.detail
    assert "compared as" in v.detail and "builtin:spec" in v.detail
    assert _plan_diff(known, known[:-1], rig.form) == f"{len(known) - 1} items instead of {len(known)}"
    assert _plan_diff(known, None) == "nothing came back"
