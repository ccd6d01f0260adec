"""Frame fuzzer (`--mode frames`): byte-level faults in mission traffic, and a liveness oracle.

Valid frames of every mission message (templates.py), from plausible GCS ids and addressed
to the target, go through one mutator each (mutators.py: bad_crc, bad_length, truncate,
bad_magic, unknown_msgid, v1_v2_mix, as_mavlink1, incompat_flags, wrong_key_signature,
stale_timestamp, garbage_between, bit_flip, signed_flag_unsigned, random_bytes, unmutated)
and are packed one to eight per datagram (program.py). What the target would accept as a
plan-changing message never goes out intact (admission.py): not as our per-datagram decoder
reads it, nor as the MAVLink C parser of PX4 (mavlink_parse_char) or ArduPilot
(mavlink_frame_char_buffer) reads the link, a byte stream whose state carries from one
datagram to the next (reference_impl/wire/cparser.py models it; a frame completed by the next datagram, hidden
in an unknown-incompat frame's payload or started on the 0xFD that ended a bad frame is
neutralised too), and every batch leaves that parser IDLE before the oracle speaks (a filler
the model derives, sent again on replay). After each batch the oracle (rig.py) wants: no
exception in an in-process vehicle, its stored plans unchanged, a HEARTBEAT still coming,
and a normal mission download that completes and returns the known plan (in the target's
stored form: the `current` flag, ArduPilot's home slot and compact storage aside).
`builtin:` examples also run a vehicle that requires MAVLink 2 signing, so unsigned,
wrong-key and stale frames must be ignored.

    search(target, *, seed, max_examples=None, stop_after=None, database=None,
           on_example=None) -> list[Case]
    replay(case, *, capture=None) -> Violation | None
"""

from .engine import FrameCampaign, minimise, replay, search
from .mutators import MUTATOR_NAMES, MUTATORS

# What the oracle asserts after every batch (the report's rows, in this order).
INVARIANTS = {
    "target-crash": "The target keeps sending HEARTBEAT after any bytes on the wire",
    "download-completes": "After the batch a normal mission download completes and returns the known plan",
    "no-exception": "Bad bytes never raise inside the (in-process) vehicle",
    "plan-unchanged": "Frames that fail to decode, or are refused, never change a stored plan",
}

__all__ = ["search", "replay", "minimise", "FrameCampaign", "MUTATORS", "MUTATOR_NAMES", "INVARIANTS"]
