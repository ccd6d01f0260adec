"""The admission rule against the parser real autopilots run: the MAVLink C library's byte
stream, whose state carries from one datagram to the next (reference_impl/wire/cparser.py).

- the Python model of the C parser equals the C code itself, compiled here from pymavlink's
  generated headers for our dialect (mavgen --lang C), on Hypothesis-drawn streams of real,
  mutated frames split into datagrams; PX4 v1.16's own (older) helpers too, where the PX4
  mirror is on this machine;
- each way a C target accepts what our per-datagram decoder refuses (a signed-flag frame
  without signature completed by the next datagram, a frame hidden in the payload of a
  frame with an unknown incompat flag, a frame split across datagrams, a frame starting on
  the 0xFD that ended a bad frame) is caught and neutralised by `Admission.admit`;
- whatever programs Hypothesis draws, the admitted datagrams in order, then the rig's
  resync filler and the oracle's own frame, hold no accepted non-INERT fuzz frame for
  either C parser (model and compiled), and the oracle's frame is not swallowed;
- the rig keeps the model in step with the oracle's datagrams, resyncs before the oracle
  speaks (the same filler on replay), and judges downloads in the target's stored form.
"""

from __future__ import annotations

import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mavconform.fuzz.frames import wire
from mavconform.fuzz.frames.admission import TARGET_TABLE, Admission
from mavconform.reference_impl.wire.cparser import (DIALECT_TABLE, FRAME_CHAR_BUFFER, OK, PARSE_CHAR,
                                 VARIANTS, CParser)
from mavconform.fuzz.frames.program import Builder, programs
from mavconform.reference_impl.wire.dialect import XML_PATH

from .frames_admission_streams import (CLEAR, CLOCK, HEARTBEAT, KEY, TARGET, accepted, ctx, inert, model_events,
                                       mutate, oracle_frame, plan_changing, streams)

PX4_HELPERS = Path("/work/sitl/px4/build/px4_sitl_default/mavlink/mavlink_helpers.h")
STATES = ["IDLE", "IDLE", "GOT_STX", "GOT_LENGTH", "GOT_INCOMPAT_FLAGS", "GOT_COMPAT_FLAGS", "GOT_SEQ",
          "GOT_SYSID", "GOT_COMPID", "GOT_MSGID1", "GOT_MSGID2", "GOT_MSGID3", "GOT_PAYLOAD", "GOT_CRC1",
          "GOT_BAD_CRC1", "SIGNATURE_WAIT", "SIGNATURE_WAIT_BAD_CRC"]    # mavlink_parse_state_t

# One channel of the C parser over stdin: records of <u32 length><bytes>, each a fresh
# channel; per frame the parser reports, "<index after its last byte> <msgid> <result>
# <sysid> <compid>" (from the channel buffer), then "END <parse_state>".
HARNESS_C = r"""
#include <stdio.h>
#include <string.h>
#include "mavconform_dialect/mavlink.h"

static int read_all(unsigned char *buf, size_t n) { return fread(buf, 1, n, stdin) == n; }

int main(int argc, char **argv) {
    int frame_mode = argc > 1 && argv[1][0] == 'f';
    static unsigned char data[1 << 20];
    unsigned char head[4];
    while (read_all(head, 4)) {
        unsigned n = head[0] | head[1] << 8 | head[2] << 16 | (unsigned)head[3] << 24;
        if (n > sizeof data || !read_all(data, n)) return 2;
        memset(mavlink_get_channel_status(MAVLINK_COMM_0), 0, sizeof(mavlink_status_t));
        memset(mavlink_get_channel_buffer(MAVLINK_COMM_0), 0, sizeof(mavlink_message_t));
        mavlink_message_t msg;
        mavlink_status_t status;
        for (unsigned i = 0; i < n; i++) {
            uint8_t r = frame_mode ? mavlink_frame_char(MAVLINK_COMM_0, data[i], &msg, &status)
                                   : mavlink_parse_char(MAVLINK_COMM_0, data[i], &msg, &status);
            if (r != MAVLINK_FRAMING_INCOMPLETE) {
                mavlink_message_t *b = mavlink_get_channel_buffer(MAVLINK_COMM_0);
                printf("%u %u %u %u %u\n", i + 1, (unsigned)b->msgid, r, b->sysid, b->compid);
            }
        }
        printf("END %d\n", (int)mavlink_get_channel_status(MAVLINK_COMM_0)->parse_state);
        fflush(stdout);
    }
    return 0;
}
"""


class CProcess:
    """The compiled harness, kept running: `run(stream)` -> (events, final parse state)."""

    def __init__(self, exe: Path, mode: str, model_variant: str) -> None:
        self.variant = model_variant
        self.proc = subprocess.Popen([str(exe), mode], stdin=subprocess.PIPE, stdout=subprocess.PIPE)

    def run(self, stream: bytes) -> tuple[list[tuple[int, ...]], str]:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(struct.pack("<I", len(stream)) + stream)
        self.proc.stdin.flush()
        events = []
        while True:
            line = self.proc.stdout.readline().split()
            if line[0] == b"END":
                return events, STATES[int(line[1])]
            events.append(tuple(int(x) for x in line))

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def c_build(tmp_path_factory) -> dict[str, CProcess] | str:
    """The C parser compiled three ways, or why it could not be (a string)."""
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        yield "no C compiler (gcc or cc) on PATH to build the MAVLink C parser with"
        return
    root = tmp_path_factory.mktemp("mavlink-c")
    include = root / "include"
    gen = subprocess.run([sys.executable, "-m", "pymavlink.tools.mavgen", "--lang", "C", "--wire-protocol", "2.0",
                          "-o", str(include), str(XML_PATH)], capture_output=True, text=True, timeout=120)
    if gen.returncode != 0 or not (include / "mavconform_dialect" / "mavlink.h").exists():
        yield f"pymavlink mavgen --lang C failed for {XML_PATH.name}: {gen.stderr.strip()[-300:]}"
        return
    source = root / "harness.c"
    source.write_text(HARNESS_C)
    builds = {"current": include}
    if PX4_HELPERS.exists():     # PX4 v1.16's generated helpers, with our dialect's tables
        px4 = root / "include-px4"
        shutil.copytree(include, px4)
        shutil.copy(PX4_HELPERS, px4 / "mavlink_helpers.h")
        builds["px4"] = px4
    exes = {}
    for name, inc in builds.items():
        exe = root / f"harness-{name}"
        done = subprocess.run([cc, "-O1", "-w", "-I", str(inc), "-o", str(exe), str(source)],
                              capture_output=True, text=True, timeout=120)
        if done.returncode != 0:
            yield f"the C harness did not compile against {name} headers: {done.stderr.strip()[-300:]}"
            return
        exes[name] = exe
    procs = {"mavlink_parse_char": CProcess(exes["current"], "p", PARSE_CHAR),
             "mavlink_frame_char_buffer": CProcess(exes["current"], "f", FRAME_CHAR_BUFFER)}
    if "px4" in exes:
        procs["mavlink_parse_char, PX4 v1.16 headers"] = CProcess(exes["px4"], "p", PARSE_CHAR)
    yield procs
    for p in procs.values():
        p.close()


def need_c(c_build) -> dict[str, CProcess]:
    if isinstance(c_build, str):
        pytest.skip(c_build)
    return c_build


# --- the model is the C code -------------------------------------------------------------------

@settings(max_examples=300, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(streams())
def test_the_model_parses_as_the_compiled_c_parser(c_build, datagrams: list[bytes]) -> None:
    procs = need_c(c_build)
    stream = b"".join(datagrams)
    for name, proc in procs.items():
        assert model_events(proc.variant, datagrams) == proc.run(stream), name


def test_the_c_quirks_the_model_follows(c_build) -> None:
    """Hand-picked corners, each checked against the compiled C when it is there."""
    bad_v1 = bytearray(wire.as_v1(HEARTBEAT))
    bad_v1[-2] ^= 0x01
    bad_v1[-1] = 0xFD                                  # a bad v1 frame that ends on 0xFD
    clear_v1 = wire.as_v1(CLEAR)
    signed = wire.sign(CLEAR, KEY, 0, 5)
    bad_signed = bytearray(signed)
    bad_signed[wire.crc_offset(signed)] ^= 0x10
    cases = {
        # after it, parse_char reads the v1 layout on the 0xFD (the MAVLink 1 flag is kept)
        "restart keeps the v1 flag": [bytes(bad_v1) + clear_v1[1:]],
        # short and long payloads are framed as the length byte says
        "length byte off": [mutate("bad_length", CLEAR, 3) + HEARTBEAT],
        # a signed frame with a bad checksum: parse_char resets at once, frame_char_buffer
        # swallows 13 bytes; the HEARTBEAT behind it is found or not
        "signed, bad checksum": [bytes(bad_signed)[:-13] + HEARTBEAT],
        "signed, good checksum, split": [signed[:-5], signed[-5:] + HEARTBEAT],
        "unknown msgid": [mutate("unknown_msgid", CLEAR, 0x1234) + HEARTBEAT],
        "zero length": [bytes([0xFD, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 0]) + HEARTBEAT],
    }
    for name, datagrams in cases.items():
        for variant in VARIANTS:
            CParser(variant).feed(b"".join(datagrams))      # the model never raises
    model = CParser(PARSE_CHAR)
    (found,) = [f for f in model.feed(cases["restart keeps the v1 flag"][0]) if f.ok]
    assert found.v1 and TARGET_TABLE.name(found.msgid) == "MISSION_CLEAR_ALL"
    assert not [f for f in CParser(FRAME_CHAR_BUFFER).feed(cases["restart keeps the v1 flag"][0]) if f.ok]
    procs = need_c(c_build)
    for name, datagrams in cases.items():
        for label, proc in procs.items():
            assert model_events(proc.variant, datagrams) == proc.run(b"".join(datagrams)), (name, label)


@settings(max_examples=150, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(streams(), st.booleans())
def test_the_admission_parses_once_for_both_variants_as_each_would_alone(datagrams: list[bytes], keyed: bool) -> None:
    """Admission feeds one model per group of variants in the same state, splitting the
    group at a frame they part on: the same frames and states as each variant alone."""
    key = KEY if keyed else None
    adm = Admission(key, keyed, CLOCK.wall)
    alone = {v: CParser(v, table=TARGET_TABLE, key=key, accept_unsigned=not keyed, wall_clock=CLOCK.wall)
             for v in VARIANTS}
    models = adm._plan
    for d in datagrams:
        models, hits = adm._stream_offending(models, d)
        want = set()
        for v, one in alone.items():
            want |= {(f.crc, f.msgid) for f in one.feed(d) if f.ok and not inert(f.msgid)}
            p = one.awaiting_signature()
            if p is not None and not inert(p.msgid):
                want.add((p.crc, p.msgid))
        assert {(f.crc, f.msgid) for f, _ in hits} == want
        grouped = {v: g for vs, g in models for v in vs}
        for v, one in alone.items():
            assert (grouped[v]._buf, grouped[v].offset, grouped[v].c_state()) == (one._buf, one.offset, one.c_state())


# --- the cases of the issue --------------------------------------------------------------------

def c_accepted(c_build, stream: bytes) -> dict[str, list[str]] | None:
    """The names of the frames each compiled C parser accepts (None without a compiler)."""
    if isinstance(c_build, str):
        return None
    out = {}
    for label, proc in c_build.items():
        events, _ = proc.run(stream)
        out[label] = [TARGET_TABLE.name(e[1]) for e in events if e[2] == OK]
    return out


def admit_all(datagrams: list[list[bytes]], key: bytes | None = None) -> tuple[list[bytes], list[list[int]]]:
    adm = Admission(key, key is not None, CLOCK.wall)
    sent, fixed = [], []
    for frames in datagrams:
        out, f = adm.admit(frames)
        sent.append(b"".join(out))
        fixed.append(f)
        adm.observe(sent[-1])
    return sent, fixed


CASES = {
    # the signed flag, no signature: the next datagram's first 13 bytes complete it
    "signed flag, no signature": [[mutate("signed_flag_unsigned", CLEAR)], [HEARTBEAT]],
    # an unknown incompat flag: the C parser goes IDLE after the flag byte and rescans
    "hidden in an unknown-incompat frame": [[bytes([0xFD, len(CLEAR), 0x02, 0, 0, 255, 190, 76, 0, 0])
                                             + CLEAR + b"\0\0"]],
    # cut in the payload, and between the two checksum bytes
    "split across datagrams": [[HEARTBEAT, CLEAR[:11]], [CLEAR[11:], HEARTBEAT]],
    "split between checksum bytes": [[CLEAR[:-1]], [CLEAR[-1:] + HEARTBEAT]],
    # a bad frame ending on 0xFD: mavlink_parse_char starts the next frame on it
    "resync on the magic of a bad checksum": [[HEARTBEAT[:-2] + bytes([HEARTBEAT[-2] ^ 1, 0xFD]), CLEAR[1:]]],
}


@pytest.mark.parametrize("name", list(CASES))
def test_each_c_only_acceptance_is_neutralised(c_build, name: str) -> None:
    datagrams = CASES[name]
    raw = [b"".join(d) for d in datagrams]
    # our per-datagram decoder sees no valid MISSION_CLEAR_ALL here, a C parser does
    from mavconform.reference_impl.wire.codec import FrameDecoder
    assert not [i for d in raw for i in FrameDecoder().feed(d) if getattr(i, "name", None) == "MISSION_CLEAR_ALL"]
    found = {v: [TARGET_TABLE.name(f.msgid) for f in accepted(v, raw)] for v in VARIANTS}
    assert any("MISSION_CLEAR_ALL" in names for names in found.values()), found
    c = c_accepted(c_build, b"".join(raw))
    if c is not None:
        assert c == {label: found[c_build[label].variant] for label in c}
    # admitted, none is left, for either C parser, with the checksum flipped in the
    # datagram that holds it; the other frames are untouched
    sent, fixed = admit_all(datagrams)
    assert any(fixed)
    for v in VARIANTS:
        assert not plan_changing(accepted(v, sent)), (v, sent)
    c = c_accepted(c_build, b"".join(sent))
    if c is not None:
        assert all("MISSION_CLEAR_ALL" not in names for names in c.values()), c
    assert sum(len(a) for a in sent) == sum(len(b) for b in raw)
    changed = [i for i, (a, b) in enumerate(zip(b"".join(sent), b"".join(raw))) if a != b]
    assert 1 <= len(changed) <= 2


def test_a_pending_signed_frame_is_neutralised_in_the_datagram_that_holds_its_checksum() -> None:
    adm = Admission(None, False, CLOCK.wall)
    frame = mutate("signed_flag_unsigned", CLEAR)
    out, fixed = adm.admit([HEARTBEAT, frame])
    assert fixed == [1] and out[0] == HEARTBEAT
    at = wire.crc_offset(frame)
    assert out[1][at] == frame[at] ^ 0xFF and out[1][:at] == frame[:at]
    # committed: the next datagram, whatever it is, completes nothing valid
    adm.observe(b"".join(out))
    assert adm.pending()
    assert not plan_changing([f for f in adm.observe(oracle_frame()) if f.ok and f.start < len(b"".join(out))])
    assert adm.leaked == 0


def test_a_signing_target_keeps_its_signature_policy() -> None:
    """A vehicle that requires signatures: unsigned and wrong-key frames go out intact (also
    the signed-flag one: no signature bytes can make it valid); a right-key one does not."""
    strict = Admission(KEY, True, CLOCK.wall)
    for frame in (CLEAR, mutate("signed_flag_unsigned", CLEAR), mutate("wrong_key_signature", CLEAR),
                  mutate("stale_timestamp", CLEAR)):
        assert strict.admit([frame]) == ([frame], []), frame.hex()
    good = wire.sign(CLEAR, KEY, 0, ctx().fresh_timestamp())
    out, fixed = strict.admit([good, good[:20]])
    assert fixed == [0]
    assert not plan_changing(accepted(PARSE_CHAR, [b"".join(out)], key=KEY))


def test_a_datagram_whose_flips_do_not_settle_is_filled(monkeypatch) -> None:
    """If flipping cannot settle a datagram (here: no checksum byte may be flipped), the
    offending frame's bytes are replaced by a filler with no start byte, and `last_filled`
    names the frames."""
    import mavconform.fuzz.frames.admission as admission
    monkeypatch.setattr(admission, "_crc_byte", lambda *a: None)
    hidden = CASES["hidden in an unknown-incompat frame"][0][0]
    adm = Admission(None, False, CLOCK.wall)
    out, fixed = adm.admit([HEARTBEAT, hidden, HEARTBEAT])
    assert fixed == [1] and adm.last_filled == [1] and adm.filled == 1
    assert out[0] == HEARTBEAT == out[2] and len(out[1]) == len(hidden)
    assert out[1][:10] == hidden[:10] and set(out[1][10:10 + len(CLEAR)]) == {0x00}
    assert out[1][10 + len(CLEAR):] == hidden[10 + len(CLEAR):]
    for v in VARIANTS:
        assert not plan_changing(accepted(v, [b"".join(out)]))


# --- the property: nothing admitted is accepted ------------------------------------------------

@settings(max_examples=60, deadline=None, database=None, suppress_health_check=list(HealthCheck))
@given(programs(160), st.booleans())
def test_admitted_programs_hold_no_accepted_plan_changing_frame(c_build, program, signing: bool) -> None:
    key = KEY if signing else None
    adm = Admission(key, signing, CLOCK.wall)
    builder = Builder(TARGET, ctx(), adm, sign_frames=signing)
    sent = []
    for specs in program:
        frames, _ = builder.datagram(specs)
        sent.append(b"".join(frames))
        adm.observe(sent[-1])                 # what the rig's station does as it sends
    fuzz_end = sum(map(len, sent))
    filler = adm.resync()                     # ... and before the oracle speaks
    if filler is not None:
        assert not {0xFD, 0xFE} & set(filler)
        sent.append(filler)
    assert not adm.pending()
    oracle = oracle_frame(signing)
    sent.append(oracle)
    adm.observe(oracle)
    assert adm.leaked == 0 and adm.out_of_order == 0
    for v in VARIANTS:
        for table in (TARGET_TABLE, DIALECT_TABLE):
            got = plan_changing(accepted(v, sent, table=table, key=key))
            # the one accepted plan-changing frame is the oracle's own, whole and on time
            assert [(f.start, f.msgid) for f in got] == [(fuzz_end + len(filler or b""), 43)], (v, got)
    if not signing and not isinstance(c_build, str):
        stream = b"".join(sent)
        for label, proc in c_build.items():
            events, state = proc.run(stream)
            assert [(e[0], e[1]) for e in events if e[2] == OK and not inert(e[1])] == [(len(stream), 43)], label
            assert state == "IDLE"
